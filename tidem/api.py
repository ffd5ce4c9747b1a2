"""tidem's Python API, for notebooks and scripts (docs/python_api.md):

    import tidem
    scene = tidem.load_scene("fluidized_tube", numerics__t_end=0.3)  # a shipped scene, one key overridden
    run = tidem.run(scene, out="runs/ft")                            # a RunFolder
    run.observables["pressure_fluctuation"], run.series["gas_pressure_drop_Pa"]
    run = tidem.read_run("runs/ft")                                  # the same, read back later

`tidem scene` is built on the same functions (`tidem.scene.load.load`, `tidem.runner.launch.prepare`
and `execute`), so a scene, its overrides and its errors behave as on the command line; the
errors are exceptions carrying the CLI's message: `SceneError` (the scene file or an override),
`InputError` (an option, the output folder, a checkpoint), `RunFailed` (the run stopped: NaN,
runaway overlap, capacity; its output so far is kept) and `RunInterrupted` (Ctrl-C: the run
stops at the end of the step, writes its checkpoint and outputs, then raises; a
KeyboardInterrupt, so a notebook cell stops as usual). Taichi is started once per process and
restarted only for another backend or precision; each run frees its Taichi fields at the end,
so one process runs many scenes. Frames are rendered by a separate process (`render=True`),
stopped with the run.
"""

from __future__ import annotations

import json
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from tidem.runner.controls import Controls
from tidem.runner.launch import InputError, OutputLost
from tidem.scene.errors import SceneError

__all__ = ["load_scene", "run", "read_run", "RunFolder", "RunFailed", "RunInterrupted", "SceneError", "InputError",
           "OutputLost"]


class RunFailed(RuntimeError):
    """The run stopped (`tidem scene`'s exit 3): the message names the cause; `run` is the
    RunFolder of what it wrote before."""

    def __init__(self, message: str, run: "RunFolder"):
        super().__init__(message)
        self.run = run


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM stopped the run (`tidem scene`'s exit 130) after it wrote its outputs
    and, between steps, a checkpoint (continue with `tidem.run(scene, resume=folder)`); `run` is
    the RunFolder."""

    def __init__(self, message: str, run: "RunFolder"):
        super().__init__(message)
        self.run = run


def load_scene(path_or_name: str | Path | None = None, sets: dict[str, Any] | list[str] | None = None,
               **overrides: Any):
    """The validated scene (a `tidem.scene.load.LoadedScene`) of a file or a shipped scene's
    name (None: the default scene), found as `tidem scene` finds it, with overrides as `--set`
    gives them: `sets` as {"particles[0].diameter.value": 0.002} or ["gas.inlet_velocity=1.2"],
    keyword arguments with `__` for the dot (`numerics__t_end=0.3`). Values are Python values
    (numbers, strings, lists, dicts) or, in the "KEY=VALUE" strings, TOML text. Raises SceneError
    listing every problem of the scene."""
    from tidem.scene.load import load

    if isinstance(sets, dict):
        sets = list(sets.items())
    items = list(sets or []) + [(key.replace("__", "."), value) for key, value in overrides.items()]
    return load(None if path_or_name is None else str(path_or_name), items)


def run(scene, out: str | Path | None = None, *, render: bool = False, plots: bool = True, progress: bool = True,
        t_end: float | None = None, smoke: bool = False, arch: str = "cpu", resume: str | Path | None = None,
        controls: Controls | None = None) -> "RunFolder":
    """Run a scene (a `load_scene` result, or a file or shipped name as `load_scene` takes it) as
    `tidem scene` does, into `out` (default renders/<scene name>; with `resume`, the folder whose
    checkpoint it continues from); returns the finished run folder. `render` renders frames and
    the movie (a background process), `plots` writes plots/*.png, `progress` shows the progress
    bar and the lines `tidem scene` prints; `t_end`, `smoke` and `arch` are the CLI's --t-end,
    --smoke and --arch. `controls` (a `tidem.Controls`) steers the run while it goes: another thread
    puts events in it (`set`, `pause`, `resume`, `step`; docs/steering.md). Raises SceneError, InputError, RunFailed, RunInterrupted or OutputLost (module
    docstring)."""
    from tidem.runner import launch
    from tidem.scene.load import LoadedScene

    loaded = scene if isinstance(scene, LoadedScene) else load_scene(scene)
    say = launch.to_stderr if progress else _quiet
    prepared = launch.prepare(loaded, None if out is None else Path(out), None if resume is None else Path(resume),
                              smoke, t_end, arch, frames=render, say=say)
    try:
        result = launch.execute(prepared, progress=progress, render=render, plots=plots, say=say, controls=controls)
    except launch.RenderInterrupted as exc:
        raise RunInterrupted(str(exc), RunFolder(prepared.out_dir)) from None
    message = launch.outcome_message(result)
    if result.status == "failed":
        raise RunFailed(message, RunFolder(result.out_dir))
    if result.status == "interrupted":
        raise RunInterrupted(message, RunFolder(result.out_dir))
    return RunFolder(result.out_dir)


def _quiet(line: str) -> None:
    """`say` of a run without progress: nothing."""


def read_run(run_dir: str | Path) -> "RunFolder":
    """A finished (or stopped) run folder read back: run.json, the time series, the snapshots."""
    return RunFolder(run_dir)


class RunFolder:
    """A run folder: `summary` (run.json), `status`, `observables`, `series` (timeseries.csv as
    numpy arrays), `dataframe()` (the same as a pandas DataFrame), `snapshots` (time and file of
    each), `snapshot(i)` and `gas(i)` (one read on demand), `plot()` (plots/*.png)."""

    def __init__(self, run_dir: str | Path):
        """Read run.json of `run_dir`; InputError if it is not a run folder."""
        self.path = Path(run_dir)
        summary = self.path / "run.json"
        if not summary.is_file():
            raise InputError(f"{self.path}: not a run folder (run.json is missing)")
        try:
            self.summary: dict = json.loads(summary.read_text())
        except ValueError:
            raise InputError(f"{summary}: not the JSON table a run writes; run the scene again to remake the "
                             "folder") from None
        if not isinstance(self.summary, dict):
            raise InputError(f"{summary}: not the JSON table a run writes; run the scene again to remake the folder")

    def __repr__(self) -> str:
        return f"RunFolder({str(self.path)!r}, scene={self.summary.get('scene')!r}, status={self.status!r})"

    @property
    def status(self) -> str:
        """'finished', 'failed', 'interrupted' (or 'starting' for a run still in its set-up)."""
        return self.summary.get("status", "")

    @property
    def observables(self) -> dict[str, dict]:
        """run.json's observables: {observable name: {column: value}} (docs/scenes.md#observables);
        empty unless the run finished."""
        return self.summary.get("observables", {})

    @property
    def values(self) -> dict[str, float]:
        """The observables' numbers as one {column: value} table (what `tidem tradeoff` compares)."""
        from tidem.results.observables import flatten

        return flatten(self.observables)

    @cached_property
    def series(self) -> dict[str, np.ndarray]:
        """timeseries.csv as {column: array}, e.g. series["time_s"], series["gas_pressure_drop_Pa"]."""
        from tidem.render.plots import read_series

        path = self.path / "timeseries.csv"
        return read_series(path) if path.is_file() else {}

    def dataframe(self):
        """The time series as a pandas DataFrame (pandas is not one of tidem's requirements)."""
        try:
            import pandas
        except ImportError:
            raise ImportError("RunFolder.dataframe() needs pandas (pip install pandas); RunFolder.series holds the "
                              "same columns as numpy arrays") from None
        return pandas.DataFrame(self.series)

    @property
    def snapshots(self) -> list[tuple[float, Path]]:
        """(time [s], file) of each snapshot in snapshots.pvd."""
        from tidem.render.movie import snapshots

        return snapshots(self.path)

    def snapshot(self, index: int = -1) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Snapshot `index` (default the last): particle centres [m], shape [n, 3], and the point
        arrays (radius, velocity, omega, id, group, contacts, with heat temperature)."""
        from tidem.io.vtp import read_vtp

        return read_vtp(self._listed(self.snapshots, index, "snapshots"))

    def gas(self, index: int = -1) -> tuple[dict, dict[str, np.ndarray]]:
        """The gas grid written with snapshot `index` (runs with [gas]): the grid (cells, origin,
        spacing, time) and the cell arrays (voidage, pressure, velocity, ...)."""
        from tidem.io.vtp import read_vti

        listed = sorted((self.path / "gas").glob("gas_*.vti"))
        return read_vti(self._listed([(0.0, p) for p in listed], index, "gas files"))

    def _listed(self, entries: list[tuple[float, Path]], index: int, what: str) -> Path:
        if not entries:
            raise IndexError(f"{self.path}: the run wrote no {what}")
        if not -len(entries) <= index < len(entries):
            raise IndexError(f"{self.path}: {what} {index} out of range (0 to {len(entries) - 1})")
        return entries[index][1]

    def plot(self) -> list[Path]:
        """Write the run's plots (plots/*.png, docs/usage.md) and return their files."""
        from tidem.render.plots import plot_timeseries

        return plot_timeseries(self.path)
