"""The run loop: advance the solver, write snapshots and the time series on their cadence,
show progress, and keep every finished output on disk whatever happens (Ctrl-C, a run error).
"""

from __future__ import annotations

import math
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import taichi as ti

from tidem.render.plots import read_series
from tidem.results.averaging import write_averages
from tidem.runner import checkpoint
from tidem.runner.controls import Controls
from tidem.runner.output import Output
from tidem.runner.output_size import cadence
from tidem.runner.steering import WATCHED_STEPS, Steering
from tidem.runner.summary import observed, summary
from tidem.runtime.phases import SAMPLE_EVERY, clock
from tidem.sim.conditions import make_steerable
from tidem.sim.model import Model
from tidem.sim.solver import RunError, Solver


@dataclass
class RunResult:
    status: str
    out_dir: Path
    steps: int
    wall_s: float
    message: str = ""
    summary: dict = field(default_factory=dict)


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
        on_snapshot: Callable[[Path], None] | None = None, view=None, resume: tuple[dict, dict] | None = None,
        controls: Controls | None = None) -> RunResult:
    """Run `model` to its end time, writing to `out_dir`.

    `on_snapshot` is called with each snapshot file once it is on disk (the background
    renderer starts on the first); `view` (a `tidem.render.live.LiveView`) is updated after
    every few steps. `controls` (a `tidem.runner.steering.Controls`) is the event queue of live
    controls, emptied every few steps (`tidem.runner.steering.Steering`); the rotating meshes and the
    outlet plate are then compiled with host-set motion (`tidem.sim.conditions.make_steerable`).
    Time spent paused is not counted in wall_s. `resume` is a
    checkpoint (`tidem.runner.checkpoint.load`) of this scene in `out_dir` to continue from.
    Checkpoints are written every `output.checkpoint_wall_s` of wall time (and every
    `output.checkpoint_interval` of simulated time if set), at the end, and when SIGINT or
    SIGTERM stops the run; never after a failure, which keeps the last good one. A solver made
    here (none passed) is released at the end.
    """
    loop = resume[0]["loop"] if resume else None
    if view is not None and controls is None:
        controls = Controls()  # the window's keys pause and step the run through the queue
    out = Output(out_dir, model, loop)
    if resume is None:
        out.write_summary(summary(model, None, "starting", 0.0))
    t_setup = time.perf_counter()
    owned = solver is None  # made here: its Taichi fields are freed at the end (a notebook runs many)
    stop = StopRequest()
    try:
        with stop:  # Ctrl-C or SIGTERM while the solver is built: the run stops before its first step
            if controls is not None and solver is None:
                make_steerable(model)
            solver = solver or Solver(model)
            if resume is not None:
                checkpoint.restore(solver, *resume)
            out.prepare(solver)  # the output's reads compiled before the clock starts
            checkpoint.prepare(solver)
    except (RunError, checkpoint.CheckpointError) as exc:
        out.close()
        data = summary(model, None, "failed", 0.0, str(exc))
        out.write_summary(data)
        return RunResult(status="failed", out_dir=Path(out_dir), steps=0, wall_s=0.0, message=str(exc), summary=data)
    steering = None
    if controls is not None:
        steering = Steering(model, solver, out.dir, controls, model.loaded.raw, model.loaded.source)
        if view is not None:
            view.attach(controls, steering)
    paused_s = 0.0
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
    from tidem.runner.progress import RunProgress

    def save_checkpoint() -> None:
        out.flush()  # every snapshot it lists on disk
        state = {"snap_dt": snap_dt, "series_dt": series_dt, "next_snap": next_snap, "next_series": next_series,
                 "entries": out.entries, "series_rows": out.series.rows, "last_sample_t": last_sample_t,
                 "output": output_table, "wall_s": wall_before + time.perf_counter() - t0, "above_top": out.above_top}
        if out.profiles is not None:
            state["profiles"] = out.profiles.state()
        if out.averages is not None:
            state["averages"] = out.averages.state()
        if out.reactions is not None:
            state["reaction_rows"] = out.reactions.rows
        checkpoint.save(out.dir, solver, state, steering.raw if steering is not None and steering.changes
                        else model.loaded.raw)

    solver.timer.reset()
    solver.timer.sample_every = 0 if ti.lang.impl.current_cfg().arch == ti.cpu else SAMPLE_EVERY  # runtime/phases.py
    lap, steps0 = solver.timer.lap, solver.steps
    begin_output = solver.timer.begin_output
    bar = RunProgress(enabled=progress, t_end=t_end, particles=int(model.active0.sum()) or model.capacity)
    last_ckpt = time.perf_counter()
    in_step = False

    def output_due(t: float) -> bool:
        """Whether the loop writes or shows anything at the end of a step at time t."""
        tol = 1e-12 * t_end
        return (t >= next_series - tol or t >= next_snap - tol or bool(ckpt_every and t >= next_ckpt)
                or (out.profiles is not None and out.profiles.due(t)) or (out.averages is not None and out.averages.due(t)))

    def due(every: int) -> int:
        """Steps to the next output, at most `every` (the progress bar's cadence, or a watched run's)."""
        return solver.steps_until(output_due, every, total_steps)

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
                if steering is not None:
                    steering.poll()
                    paused_s += steering.hold(view, solver, stop)
                lap("output", start)
                if solver.steps >= total_steps:
                    break
                if stop.signal is not None:  # asked during the set-up
                    raise KeyboardInterrupt
                in_step = True
                if steering is not None:
                    solver.advance(steering.next_steps(due))
                else:
                    solver.advance(due(WATCHED_STEPS if view is not None else 50))
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
        wall = wall_before + time.perf_counter() - t0 - paused_s
        series = read_series(out.series.path) if out.series.path.is_file() else {}
        counts = series.get("particles")
        data = summary(model, solver, status, wall, message,
                       float(np.mean(counts)) if counts is not None and len(counts) else None)
        data["setup_s"] = setup_s
        if (above := out.above_top_note(data["particles"])) is not None:
            data["above_open_top"] = above
        data["profile"] = solver.timer.table(solver.steps - steps0)
        if resume is not None:
            data["resumed_from"] = checkpoint.describe(resume[0])
        if steering is not None:
            data["steering"] = [{"time_s": t, "key": key, "value": value} for t, key, value in steering.changes]
        if status == "finished":
            data.update(observed(model, solver, series, bed_profiles, [(t, out.dir / name) for t, name in out.entries]))
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
