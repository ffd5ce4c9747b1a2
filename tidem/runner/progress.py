"""Progress bar of a run: simulated time, ETA and particle-steps per second (rich)."""

from __future__ import annotations

from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn


class RunProgress:
    """A context manager; `update` is cheap enough to call every few dozen steps."""

    def __init__(self, enabled: bool, t_end: float, particles: int):
        self.enabled = enabled
        self.t_end = t_end
        self.particles = particles
        self._p = None

    def __enter__(self):
        if self.enabled:
            self._p = Progress(
                TextColumn("[bold]t = {task.fields[t]:.4g} / {task.fields[t_end]:.4g} s"),
                BarColumn(),
                TextColumn("{task.percentage:>5.1f} %"),
                TimeRemainingColumn(),
                TextColumn("{task.fields[rate]}"),
                transient=False,
            )
            self._p.__enter__()
            self._task = self._p.add_task("run", total=self.t_end, t=0.0, t_end=self.t_end, rate="")
        return self

    def update(self, t: float, steps: int, wall: float) -> None:
        if self._p is None:
            return
        rate = f"{self.particles * steps / wall:.3g} particle-steps/s" if wall > 0 else ""
        self._p.update(self._task, completed=t, t=t, rate=rate)

    def __exit__(self, *exc):
        if self._p is not None:
            self._p.__exit__(*exc)
        return False
