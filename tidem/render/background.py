"""Frames rendered in a background process while the run goes on.

The simulation process never imports VTK. At the first snapshot it starts a worker process
(`python -m tidem.render.background RUN_DIR PARENT_PID`) that watches snapshots.pvd and
renders each new snapshot to its frame with `tidem.render.frames.render_frame`, the function
`tidem render` uses, with the style `tidem render` would use (run.json's settings and colour
range), so the frames are the same either way. The worker runs with one llvmpipe thread
(and one OpenMP/BLAS/VTK thread) at idle priority, so the simulation keeps its cores and the
renderer uses what they leave.

When the run ends the parent closes the worker's stdin: the worker renders the snapshots
that are left and exits, and the parent encodes the movie. On Ctrl-C the parent stops the
worker at once. Frames are written under a temporary name and renamed, so only finished
frames stay on disk. The worker has its own session (the terminal's Ctrl-C goes to the parent
only) and, on Linux, is killed when its parent dies, so it never outlives the run.
"""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

from tidem.render.movie import clear_frames, frame_path, snapshots

THREAD_CAPS = {"LP_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
               "MKL_NUM_THREADS": "1", "VTK_SMP_MAX_THREADS": "1"}
POLL_S = 0.2  # how often the worker looks for new snapshots [s]


class BackgroundRenderer:
    """Parent side: a context manager whose instance is the run's `on_snapshot` hook."""

    def __init__(self, run_dir: Path):
        self.run_dir = Path(run_dir)
        self.proc: subprocess.Popen | None = None
        self._log = None

    def __call__(self, snapshot: Path) -> None:
        """Start the worker at the first snapshot (the run folder is set up by then)."""
        if self.proc is None:
            clear_frames(self.run_dir)
            self._log = tempfile.TemporaryFile()
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "tidem.render.background", str(self.run_dir), str(os.getpid())],
                stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._log,
                env={**os.environ, **THREAD_CAPS}, start_new_session=True)

    def frames_done(self) -> int:
        return len(list((self.run_dir / "frames").glob("frame_*.png")))

    def finish(self, progress=None) -> str | None:
        """Let the worker render what is left and wait for it; `progress(done, total)` is
        called while waiting. Returns None, or the worker's error message."""
        if self.proc is None:
            return None
        self.proc.stdin.close()
        total = len(snapshots(self.run_dir))
        while True:
            try:
                rc = self.proc.wait(timeout=POLL_S)
                break
            except subprocess.TimeoutExpired:
                if progress:
                    progress(self.frames_done(), total)
        if progress:
            progress(self.frames_done(), total)
        if rc == 0:
            return None
        self._log.seek(0)
        lines = [ln for ln in self._log.read().decode(errors="replace").splitlines() if ln.strip()]
        return lines[-1] if lines else f"the renderer process ended with code {rc}"

    def stop(self) -> None:
        """Stop the worker now; finished frames stay, a half-written one is removed."""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for tmp in (self.run_dir / "frames").glob(".frame_*.png"):
            tmp.unlink(missing_ok=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
        if self._log is not None:
            self._log.close()
        return False


def _die_with_parent(parent: int) -> None:
    """Ask Linux to kill this process when the parent dies (PR_SET_PDEATHSIG)."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)
    except (OSError, AttributeError):  # not Linux: the closed stdin still ends the worker
        pass
    if os.getppid() != parent:
        sys.exit(0)


def _parent_closed(timeout: float) -> bool:
    """Wait up to `timeout` s; True once the parent has closed our stdin."""
    ready, _, _ = select.select([sys.stdin.fileno()], [], [], timeout)
    return bool(ready) and os.read(sys.stdin.fileno(), 4096) == b""


def work(run_dir: Path) -> None:
    """Render snapshots as they appear until the parent closes stdin, then the rest."""
    from tidem.render.frames import render_frame
    from tidem.render.movie import style_for

    style = None
    done = 0
    while True:
        closed = _parent_closed(POLL_S)
        snaps = snapshots(run_dir)
        for k in range(done, len(snaps)):
            style = style or style_for(run_dir)
            render_frame(snaps[k][1], snaps[k][0], style, frame_path(run_dir, k))
            done = k + 1
        if closed:
            return


def _yield_to_simulation() -> None:
    """Run only when a core is idle (Linux SCHED_IDLE: the simulation's threads preempt us at
    once); elsewhere at the lowest nice level."""
    try:
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    except (AttributeError, OSError):
        os.nice(19)


def main(argv: list[str]) -> int:
    _die_with_parent(int(argv[1]))
    _yield_to_simulation()
    try:
        work(Path(argv[0]))
    except (ValueError, KeyError) as exc:
        print(exc.args[0] if exc.args else exc, file=sys.stderr)
        return 2
    except Exception as exc:  # noqa: BLE001 - reported by the parent as one line, never a traceback
        print(f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
