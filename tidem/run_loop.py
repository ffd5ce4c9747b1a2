"""The run loop: advance the solver, write snapshots and the time series on their cadence,
show progress, and keep every finished output on disk whatever happens (Ctrl-C, a run error).
"""

from __future__ import annotations

import json
import math
import signal
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import taichi as ti

from tidem import checkpoint
from tidem.averaging import AverageRecorder, write_averages
from tidem.bed_profiles import CSV_NAME, ProfileRecorder, profile_rows, write_csv
from tidem.hydrodynamics import bed_top
from tidem.io.mesh_output import MeshOutput
from tidem.io.timeseries import TimeSeries
from tidem.io.vtp import write_pvd, write_vti, write_vtp
from tidem.model import Model
from tidem.output_size import cadence
from tidem.phases import SAMPLE_EVERY, clock
from tidem.render.plots import read_series
from tidem.reaction_output import ReactionLog
from tidem.reactions import reaction_summary
from tidem.run_summary import observed, summary
from tidem.run_tables import alpha_profile, tube_alpha_columns
from tidem.solver import RunError, Solver


WRITES_AHEAD = 2  # snapshots the writer thread may be behind the run loop (each held in memory meanwhile)


@dataclass
class RunResult:
    status: str
    out_dir: Path
    steps: int
    wall_s: float
    message: str = ""
    summary: dict = field(default_factory=dict)


class Output:
    """Snapshots (vtp + pvd), the mesh walls (meshes/ + meshes.pvd), timeseries.csv and run.json
    of one run folder."""

    def __init__(self, out_dir: Path, model: Model, loop: dict | None = None):
        """A fresh run folder, or with `loop` (a checkpoint's run-loop state) the folder of the
        run being resumed: its snapshots and time-series rows up to the checkpoint are kept,
        anything written after it is dropped."""
        self.dir = Path(out_dir)
        self.snap_dir = self.dir / "snapshots"
        self.snap_dir.mkdir(parents=True, exist_ok=True)
        self.model = model
        self.entries: list[tuple[float, str]] = [tuple(e) for e in loop["entries"]] if loop else []
        self.gas_dir = self.dir / "gas" if model.features.gas else None
        if self.gas_dir is not None:
            self.gas_dir.mkdir(exist_ok=True)
        folders = [self.dir, self.snap_dir] + ([self.gas_dir] if self.gas_dir is not None else [])
        for half in [p for folder in folders for p in folder.glob("*.tmp")]:
            half.unlink()  # half-written by a killed run (every file is written under .tmp, then renamed)
        kept = {Path(name).name for _, name in self.entries}
        for old in self.snap_dir.glob("*.vtp"):
            if old.name not in kept:
                old.unlink()
        if self.gas_dir is not None:
            for old in self.gas_dir.glob("*.vti"):
                if old.name.replace("gas_", "snap_").replace(".vti", ".vtp") not in kept:
                    old.unlink()
        for pvd, entries in (("snapshots.pvd", self.entries), ("gas.pvd", self._gas_entries())):
            if entries:
                write_pvd(self.dir / pvd, entries)
            else:
                (self.dir / pvd).unlink(missing_ok=True)
        self.meshes = MeshOutput(self.dir, model.meshes, self.entries)  # each mesh at t = 0, before the renderer starts
        self._writer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="tidem-snapshots")
        self._pending: list[tuple[Future, Path, Callable | None]] = []
        self.series = TimeSeries(self.dir / "timeseries.csv", loop["series_rows"] if loop else None)
        # the column bed_height_m: the bed_height observable's height at each sample
        self.bed_height = model.features.gas or "bed_height" in model.scene.observables
        self.reactions = (ReactionLog(self.dir, model, [tuple(r) for r in loop.get("reaction_rows", [])] if loop else None)
                          if model.features.reactions else None)
        self.profiles = (ProfileRecorder(model, loop.get("profiles") if loop else None)
                         if model.features.packed_bed_profiles else None)
        self.averages = (AverageRecorder(model, cadence(model.scene, model.t_end)[1],
                                         loop.get("averages") if loop else None)
                         if model.features.averaging else None)

    def snapshot(self, solver: Solver, on_written: Callable[[Path], None] | None = None) -> Path:
        """Write the next snapshot and list it in snapshots.pvd; returns its file. The particles and
        the gas are copied from the solver here; the files are written by the writer thread while the
        next steps run (at most WRITES_AHEAD snapshots behind; `flush` waits for them). `on_written`
        is called with the file once it is on disk, in this thread (`poll`, `flush`): the background
        renderer it starts dies with the thread that started it (PR_SET_PDEATHSIG)."""
        S = solver.state
        active = S.active.to_numpy().astype(bool)
        idx = np.flatnonzero(active)
        ident = S.ident.to_numpy()[idx]  # index in the scene (storage is re-sorted as the bed flows)
        name = f"snap_{len(self.entries):05d}.vtp"
        extra = {"temperature": S.T.to_numpy()[idx]} if self.model.features.heat else {}
        if self.model.features.coarse_grain:
            extra["grains"] = self.model.coarse_grain[ident] ** 3  # grains a parcel stands for (k^3)
        t = solver.t
        points, point_data = S.x.to_numpy()[idx], {**extra,
            "radius": S.radius.to_numpy()[idx],
            "velocity": S.v.to_numpy()[idx],
            "omega": S.w.to_numpy()[idx],
            "id": ident.astype(np.int32),
            "group": self.model.group[ident].astype(np.int32),
            "contacts": S.ncontact.to_numpy()[idx].astype(np.int32),
        }
        self.entries.append((t, f"snapshots/{name}"))
        self.meshes.snapshot()
        gas = None
        if self.gas_dir is not None:
            gg = solver.gas.gg
            gas = (self.gas_dir / name.replace("snap_", "gas_").replace(".vtp", ".vti"), gg.lo, gg.h, gg.cells,
                   solver.gas.cell_fields(), self._gas_entries())
        entries, path = list(self.entries), self.snap_dir / name

        def write() -> None:
            write_vtp(path, points, point_data, time=t)
            if gas is not None:
                write_vti(*gas[:5], time=t)
                write_pvd(self.dir / "gas.pvd", gas[5])
            write_pvd(self.dir / "snapshots.pvd", entries)

        while len(self._pending) >= WRITES_AHEAD:
            self._done(wait=True)
        self._pending.append((self._writer.submit(write), path, on_written))
        return path

    def _done(self, wait: bool) -> bool:
        """Finish the oldest snapshot handed to the writer (waiting for it with `wait`): raise its
        error (e.g. a full disk) or call its `on_written`. False if there is none (or not yet)."""
        if not self._pending or not (wait or self._pending[0][0].done()):
            return False
        future, path, on_written = self._pending.pop(0)
        future.result()
        if on_written is not None:
            on_written(path)
        return True

    def poll(self) -> None:
        """Finish the snapshots the writer thread has written so far (in order)."""
        while self._done(wait=False):
            pass

    def flush(self) -> None:
        """Wait until every snapshot handed to the writer thread is on disk (raises its error)."""
        while self._done(wait=True):
            pass

    def close(self) -> None:
        """Flush the snapshots and the time series, and stop the writer thread."""
        try:
            self.flush()
        finally:
            self._writer.shutdown()
            self.series.close()

    def _gas_entries(self) -> list[tuple[float, str]]:
        """gas.pvd's rows: the gas file written with each snapshot (runs with [gas])."""
        if self.gas_dir is None:
            return []
        return [(t, name.replace("snapshots/snap_", "gas/gas_").replace(".vtp", ".vti")) for t, name in self.entries]

    def sample(self, solver: Solver) -> None:
        row = {"time_s": solver.t, "step": solver.steps}
        row.update(solver.energies())
        row["max_overlap_ratio"] = solver.health()[2]
        if self.bed_height:
            active = solver.state.active.to_numpy().astype(bool)
            row["bed_height_m"] = bed_top(solver.state.x.to_numpy()[active, 2])
        row.update(solver.outlet_summary())
        if self.model.features.heat:
            row.update(solver.heat_summary())
        if solver.gas is not None:
            row.update(solver.gas.summary())
        row.update(tube_alpha_columns(self.model, row))
        if self.reactions is not None:
            row.update(reaction_summary(solver))
            self.reactions.sample(solver)
        for p in self.model.planes:
            if p["name"] == "outlet plate":
                t0, t1 = p["t"]
                row["plate_z_m"] = p["p0"][2] + p["vel"][2] * (min(max(solver.t, t0), t1) - t0)
        self.series.append(row)

    def write_alpha_profile(self, solver: Solver) -> None:
        """alpha_profile.csv: tube, angle_deg (0 = top), alpha_W_m2K."""
        rows, _ = alpha_profile(self.model, solver)
        if rows:
            lines = ["tube,angle_deg,alpha_W_m2K"] + [f"{r['tube']},{r['angle_deg']:.2f},{r['alpha_W_m2K']:.6g}" for r in rows]
            (self.dir / "alpha_profile.csv").write_text("\n".join(lines) + "\n")

    def write_bed_profiles(self, solver: Solver) -> dict | None:
        """preheat_profiles.csv of the profiles recorded so far (`tidem.bed_profiles`); returns
        their summary for run.json, or None without the packed_bed_profiles observable."""
        if self.profiles is None:
            return None
        rows, result = profile_rows(self.model, solver, self.profiles)
        if rows:
            write_csv(self.dir / CSV_NAME, rows)
        return result

    def write_summary(self, data: dict) -> None:
        path = self.dir / "run.json"
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(data, indent=2, default=float))
        tmp.replace(path)


class StopRequest:
    """SIGINT and SIGTERM ask the run loop to stop at the end of the current step (it then
    writes a checkpoint and flushes every output); a second Ctrl-C interrupts at once.
    Handlers are installed only in the main thread and restored on exit."""

    def __init__(self):
        self.signal: str | None = None
        self._old = {}

    def _handle(self, signum, frame):
        if self.signal is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt
        self.signal = signal.Signals(signum).name

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc):
        for sig, handler in self._old.items():
            signal.signal(sig, handler)
        return False


def _next_after(t: float, every: float) -> float:
    return (math.floor(t / every + 1e-9) + 1) * every


def run(model: Model, out_dir: Path, progress: bool = True, solver: Solver | None = None,
        on_snapshot: Callable[[Path], None] | None = None, view=None, resume: tuple[dict, dict] | None = None
        ) -> RunResult:
    """Run `model` to its end time, writing to `out_dir`.

    `on_snapshot` is called with each snapshot file once it is on disk (the background
    renderer starts on the first); `view` (a `tidem.render.live.LiveView`) is updated after
    every step. Time the view spends paused is not counted in wall_s. `resume` is a
    checkpoint (`tidem.checkpoint.load`) of this scene in `out_dir` to continue from.
    Checkpoints are written every `output.checkpoint_wall_s` of wall time (and every
    `output.checkpoint_interval` of simulated time if set), at the end, and when SIGINT or
    SIGTERM stops the run; never after a failure, which keeps the last good one. A solver made
    here (none passed) is released at the end.
    """
    loop = resume[0]["loop"] if resume else None
    out = Output(out_dir, model, loop)
    if resume is None:
        out.write_summary(summary(model, None, "starting", 0.0))
    t_setup = time.perf_counter()
    owned = solver is None  # made here: its Taichi fields are freed at the end (a notebook runs many)
    try:
        solver = solver or Solver(model)
        if resume is not None:
            checkpoint.restore(solver, *resume)
    except (RunError, checkpoint.CheckpointError) as exc:
        out.close()
        data = summary(model, None, "failed", 0.0, str(exc))
        out.write_summary(data)
        return RunResult(status="failed", out_dir=Path(out_dir), steps=0, wall_s=0.0, message=str(exc), summary=data)
    t0 = time.perf_counter()
    setup_s = t0 - t_setup
    scene = model.scene
    t_end = model.t_end
    output_table = scene.output.model_dump()
    snap_dt, series_dt = cadence(scene, t_end)
    next_snap = next_series = next_ckpt = 0.0
    wall_before = 0.0
    if loop is not None:
        wall_before = loop["wall_s"]
        if loop["output"] == output_table:
            snap_dt, series_dt, next_snap, next_series = (loop[k] for k in ("snap_dt", "series_dt", "next_snap",
                                                                              "next_series"))
        else:  # new cadence from the last snapshot and sample on
            next_snap = _next_after(out.entries[-1][0], snap_dt) if out.entries else solver.t
            next_series = _next_after(loop["last_sample_t"], series_dt)
    ckpt_every = scene.output.checkpoint_interval
    if ckpt_every:
        next_ckpt = _next_after(solver.t, ckpt_every)
    last_sample_t = loop["last_sample_t"] if loop else -1.0
    total_steps = max(1, math.ceil(t_end / model.dt - 1e-9))
    status, message = "finished", ""
    from tidem.progress import RunProgress

    def save_checkpoint() -> None:
        out.flush()  # every snapshot it lists on disk
        state = {"snap_dt": snap_dt, "series_dt": series_dt, "next_snap": next_snap, "next_series": next_series,
                 "entries": out.entries, "series_rows": out.series.rows, "last_sample_t": last_sample_t,
                 "output": output_table, "wall_s": wall_before + time.perf_counter() - t0}
        if out.profiles is not None:
            state["profiles"] = out.profiles.state()
        if out.averages is not None:
            state["averages"] = out.averages.state()
        if out.reactions is not None:
            state["reaction_rows"] = out.reactions.rows
        checkpoint.save(out.dir, solver, state, model.loaded.raw)

    solver.timer.reset()
    solver.timer.sample_every = 0 if ti.lang.impl.current_cfg().arch == ti.cpu else SAMPLE_EVERY  # phases.py
    lap, steps0 = solver.timer.lap, solver.steps
    begin_output = solver.timer.begin_output
    bar = RunProgress(enabled=progress, t_end=t_end, particles=int(model.active0.sum()) or model.capacity)
    last_ckpt = time.perf_counter()
    in_step = False
    stop = StopRequest()

    def output_due(t: float) -> bool:
        """Whether the loop writes or shows anything at the end of a step at time t."""
        tol = 1e-12 * t_end
        return (view is not None or t >= next_series - tol or t >= next_snap - tol or bool(ckpt_every and t >= next_ckpt)
                or (out.profiles is not None and out.profiles.due(t)) or (out.averages is not None and out.averages.due(t)))

    try:
        with bar, stop:
            while True:
                start = begin_output()
                if solver.t >= next_series - 1e-12 * t_end:
                    out.sample(solver)
                    last_sample_t = solver.t
                    next_series += series_dt
                if solver.t >= next_snap - 1e-12 * t_end:
                    out.snapshot(solver, on_snapshot)
                    next_snap += snap_dt
                if out.profiles is not None and out.profiles.due(solver.t):
                    out.profiles.record(solver)
                if out.averages is not None and out.averages.due(solver.t):
                    out.averages.record(solver)
                if view is not None:
                    view.update(solver)
                lap("output", start)
                if solver.steps >= total_steps:
                    break
                in_step = True
                solver.advance(solver.steps_until(output_due, 50, total_steps))
                in_step = False
                start = begin_output()
                out.poll()
                if solver.steps % 50 == 0 or solver.steps == total_steps:
                    bar.update(solver.t, solver.steps, time.perf_counter() - t0)
                if stop.signal is not None:
                    raise KeyboardInterrupt
                now = time.perf_counter()
                if now - last_ckpt >= scene.output.checkpoint_wall_s or (ckpt_every and solver.t >= next_ckpt):
                    save_checkpoint()
                    last_ckpt = now
                    if ckpt_every:
                        next_ckpt = _next_after(solver.t, ckpt_every)
                lap("output", start)
            start = begin_output()
            solver.check()
            save_checkpoint()
            lap("output", start)
    except RunError as exc:
        status, message = "failed", str(exc)
    except KeyboardInterrupt:
        why = f" by {stop.signal}" if stop.signal not in (None, "SIGINT") else ""
        status, message = "interrupted", f"interrupted{why} at t = {solver.t:.6g} s (step {solver.steps})"
        if not in_step:
            save_checkpoint()
            message += "; checkpoint written, continue with --resume"
    finally:
        start = clock()
        out.close()
        if model.angle_bins:
            out.write_alpha_profile(solver)
        if out.averages is not None:
            write_averages(out.dir, model, solver)
        bed_profiles = out.write_bed_profiles(solver)
        lap("output", start)
        wall = wall_before + time.perf_counter() - t0 - (view.paused_s if view is not None else 0.0)
        series = read_series(out.series.path) if out.series.path.is_file() else {}
        counts = series.get("particles")
        data = summary(model, solver, status, wall, message,
                       float(np.mean(counts)) if counts is not None and len(counts) else None)
        data["setup_s"] = setup_s
        data["profile"] = solver.timer.table(solver.steps - steps0)
        if resume is not None:
            data["resumed_from"] = checkpoint.describe(resume[0])
        if status == "finished":
            data.update(observed(model, solver, series, bed_profiles))
        if out.reactions is not None:  # per reaction group, and flat in observables for tradeoff/sweep
            figures = out.reactions.finish(solver)
            data["reactions"] = figures
            data.setdefault("observables", {})["reactions"] = {
                f"{group}_{key}": value for group, values in figures.items() for key, value in values.items()
                if isinstance(value, (int, float)) and not isinstance(value, bool)}
        out.write_summary(data)
        if owned:
            solver.release()
    return RunResult(status=status, out_dir=Path(out_dir), steps=solver.steps, wall_s=wall, message=message, summary=data)
