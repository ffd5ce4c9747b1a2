"""The last line of defence of the command line: an unexpected exception becomes one line on
the terminal and a log file holding the full traceback for a bug report.

Exit codes of `tidem` (also in the CLI help and docs/errors.md): 0 done, 2 bad input (scene,
option or path; one message names the file, the key and the fix), 3 a run stopped (NaN,
runaway overlap, capacity; the output written so far is kept), 70 an internal error (a bug:
the log file named on the terminal has the traceback), 74 the output folder could not be written
any more (`tidem.runner.launch.OutputLost`), 130 interrupted (Ctrl-C or SIGTERM;
finished output and a checkpoint are kept).
"""

from __future__ import annotations

import os
import platform
import sys
import tempfile
import time
import traceback
from pathlib import Path

INTERNAL_ERROR = 70  # EX_SOFTWARE of sysexits.h


def log_folder() -> Path:
    """Where crash logs go: $TIDEM_LOG_DIR if set, else tidem-logs in the system's temporary folder."""
    return Path(os.environ.get("TIDEM_LOG_DIR") or Path(tempfile.gettempdir()) / "tidem-logs")


def write_log(exc: BaseException) -> Path | None:
    """Write the command line, versions and traceback of `exc` to a new log file; its path, or
    None where no file could be written."""
    from tidem.version import __version__

    text = (f"tidem {__version__}, Python {platform.python_version()}, {platform.platform()}\n"
            f"command: {' '.join(sys.argv)}\nworking folder: {os.getcwd()}\n\n"
            + "".join(traceback.format_exception(exc)))
    try:
        folder = log_folder()
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"tidem-error-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.log"
        path.write_text(text)
        return path
    except OSError:
        return None


def one_line(exc: BaseException, log: Path | None) -> str:
    """The terminal's line for an unexpected exception."""
    what = "ran out of memory" if isinstance(exc, MemoryError) else "internal error"
    detail = (str(exc).splitlines() or [""])[0][:200]
    where = (f"the full traceback is in {log}; please attach it and the scene file to a bug report"
             if log is not None else f"no log could be written in {log_folder()} (set TIDEM_LOG_DIR)")
    return f"tidem: {what}: {type(exc).__name__}{': ' + detail if detail else ''}; {where}"
