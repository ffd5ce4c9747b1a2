"""What every `tidem` command shares: the Typer app with the exit codes in its help, the --set
option, and the exits with code 2 for bad input (a scene that does not validate or build, an
output folder that cannot be written)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from tidem.scene.errors import SceneError

EXIT_CODES = ("Exit codes: 0 done; 2 bad input (the message names the file, the key and the fix); 3 a run stopped "
              "(output so far kept); 70 internal error (a bug: one line names a log file with the traceback, in "
              "$TIDEM_LOG_DIR or the temporary folder's tidem-logs); 74 the output folder could not be written any "
              "more (removed, disk full); 130 interrupted (output and checkpoint kept).")
app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help=f"tidem: hot granular flows in Taichi.\n\n{EXIT_CODES}")

Sets = Annotated[Optional[list[str]], typer.Option("--set", help="Override a scene key, e.g. --set outlet.speed=0.003")]


def fail(message: str, code: int) -> None:
    """Print `message` to stderr and exit with `code`."""
    typer.echo(message, err=True)
    raise typer.Exit(code)


def load_scene(path: Optional[str], sets: Optional[list[str]]):
    """The validated scene of a file or shipped name with --set overrides, or exit 2."""
    from tidem.scene.load import load

    try:
        return load(path, sets or [])
    except SceneError as exc:
        fail(exc.render(), 2)


def start_taichi(arch: str, precision: str, threads: int | None = None) -> None:
    """Start Taichi on `arch` (`tidem.runner.launch.start_taichi`), or exit 2 with the reason."""
    from tidem.runner.launch import InputError
    from tidem.runner.launch import start_taichi as start

    try:
        start(arch, precision, threads)
    except InputError as exc:
        fail(str(exc), 2)


def build_or_exit(loaded, smoke=False, t_end=None):
    """The Model of a loaded scene, or exit 2 with the problems `build_model` finds."""
    from tidem.sim.model import build_model

    try:
        return build_model(loaded, smoke=smoke, t_end=t_end)
    except SceneError as exc:
        fail(exc.render(), 2)


def writable(out_dir: Path, option: str) -> None:
    """Exit 2 naming the option unless `out_dir` is (or can be made) a folder this process can write in."""
    from tidem.runner.launch import InputError
    from tidem.runner.launch import writable as check

    try:
        check(out_dir, option)
    except InputError as exc:
        fail(str(exc), 2)


def script_main(main) -> None:
    """Call main(SCENE, RUN_DIR, [INT [INT]], sets=[KEY=VALUE ...]) with sys.argv, as the scripts in benchmarks/
    take their arguments; a scene or checkpoint refused (`typer.Exit`, its reason printed) exits with its code."""
    import sys

    args = sys.argv[1:]
    numbers = [a for a in args[2:4] if a.isdigit()]
    try:
        main(args[0], args[1], *map(int, numbers), sets=args[2 + len(numbers):])
    except typer.Exit as stop:
        sys.exit(stop.exit_code)
