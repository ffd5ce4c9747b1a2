"""The run loop: advance the solver, write snapshots and the time series on their cadence,
show progress, and keep every finished output on disk whatever happens (Ctrl-C, a run error).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from tidem import __version__
from tidem.bed_profiles import CSV_NAME, ProfileRecorder, profile_rows, write_csv
from tidem.io.timeseries import TimeSeries
from tidem.io.vtp import write_pvd, write_vtp
from tidem.model import Model
from tidem.observables import alpha_profile, contact_times
from tidem.render.settings import render_settings
from tidem.solver import RunError, Solver


@dataclass
class RunResult:
    status: str
    out_dir: Path
    steps: int
    wall_s: float
    message: str = ""
    summary: dict = field(default_factory=dict)


class Output:
    """Snapshots (vtp + pvd), timeseries.csv and run.json of one run folder."""

    def __init__(self, out_dir: Path, model: Model):
        self.dir = Path(out_dir)
        self.snap_dir = self.dir / "snapshots"
        self.snap_dir.mkdir(parents=True, exist_ok=True)
        for old in [*self.snap_dir.glob("*.vtp"), self.dir / "snapshots.pvd"]:
            old.unlink(missing_ok=True)
        self.model = model
        self.entries: list[tuple[float, str]] = []
        self.series = TimeSeries(self.dir / "timeseries.csv")

    def snapshot(self, solver: Solver) -> Path:
        """Write the next snapshot and list it in snapshots.pvd; returns its file."""
        S = solver.state
        active = S.active.to_numpy().astype(bool)
        idx = np.flatnonzero(active)
        name = f"snap_{len(self.entries):05d}.vtp"
        extra = {"temperature": S.T.to_numpy()[idx]} if self.model.features.heat else {}
        write_vtp(self.snap_dir / name, S.x.to_numpy()[idx], {**extra,
            "radius": S.radius.to_numpy()[idx],
            "velocity": S.v.to_numpy()[idx],
            "omega": S.w.to_numpy()[idx],
            "id": idx.astype(np.int32),
            "group": self.model.group[idx].astype(np.int32),
            "contacts": S.ncontact.to_numpy()[idx].astype(np.int32),
        }, time=solver.t)
        self.entries.append((solver.t, f"snapshots/{name}"))
        write_pvd(self.dir / "snapshots.pvd", self.entries)
        return self.snap_dir / name

    def sample(self, solver: Solver) -> None:
        row = {"time_s": solver.t, "step": solver.steps}
        row.update(solver.energies())
        row["max_overlap_ratio"] = float(solver.state.ovl.to_numpy().max()) if solver.n else 0.0
        if self.model.features.heat:
            row.update(solver.heat_summary())
        if solver.gas is not None:
            row.update(solver.gas.summary())
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

    def write_bed_profiles(self, solver: Solver, recorder: ProfileRecorder) -> dict:
        """preheat_profiles.csv (see `tidem.bed_profiles`); returns the summary for run.json."""
        rows, result = profile_rows(self.model, solver, recorder)
        if rows:
            write_csv(self.dir / CSV_NAME, rows)
        return result

    def write_summary(self, data: dict) -> None:
        path = self.dir / "run.json"
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(data, indent=2, default=float))
        tmp.replace(path)


def summary(model: Model, solver: Solver | None, status: str, wall: float, message: str = "") -> dict:
    steps = solver.steps if solver else 0
    n = int(model.active0.sum()) if solver is None else int(solver.state.active.to_numpy().sum())
    f = model.features
    out = {
        "tidem_version": __version__,
        "scene": model.name,
        "scene_file": str(model.loaded.source),
        "status": status,
        "message": message,
        "active_models": f.kernels(),
        "particles": n,
        "capacity": model.capacity,
        "steps": steps,
        "t_end_s": model.t_end,
        "time_s": solver.t if solver else 0.0,
        "dt_s": model.dt,
        "rayleigh_time_s": model.scales.rayleigh,
        "contact_time_s": model.scales.contact,
        "dt_limit_s": model.scales.limit,
        "neighbour_rebuilds": solver.rebuilds if solver else 0,
        "wall_s": wall,
        "particle_steps_per_s": n * steps / wall if wall > 0 else 0.0,
        "precision": f.precision,
        "scene_echo": model.loaded.raw,
        "render": render_settings(model),
        "render_geometry": {
            "bounds": [v for a in range(3) for v in (model.scene.domain.min[a], model.scene.domain.max[a])],
            "periodic": list(model.grid.periodic),
            "tubes": [{"c": t["c"], "mask": t["mask"], "r": t["r"], "T": t["T"]} for t in model.tubes],
        },
    }
    if solver is not None and f.contact_time:
        out["observables"] = {"contact_time": contact_times(model, solver)}
    if solver is not None and model.angle_bins:
        out.setdefault("observables", {})["tube_mean_alpha"] = alpha_profile(model, solver)[1]
    return out


def run(model: Model, out_dir: Path, progress: bool = True, solver: Solver | None = None,
        on_snapshot: Callable[[Path], None] | None = None, view=None) -> RunResult:
    """Run `model` to its end time, writing to `out_dir`.

    `on_snapshot` is called with each snapshot file once it is on disk (the background
    renderer starts on the first); `view` (a `tidem.render.live.LiveView`) is updated after
    every step. Time the view spends paused is not counted in wall_s.
    """
    out = Output(out_dir, model)
    out.write_summary(summary(model, None, "starting", 0.0))
    t_setup = time.perf_counter()
    try:
        solver = solver or Solver(model)
    except RunError as exc:  # a limit already broken at t = 0 (e.g. the gas Courant number)
        out.series.close()
        data = summary(model, None, "failed", 0.0, str(exc))
        out.write_summary(data)
        return RunResult(status="failed", out_dir=Path(out_dir), steps=0, wall_s=0.0, message=str(exc), summary=data)
    t0 = time.perf_counter()
    setup_s = t0 - t_setup
    scene = model.scene
    t_end = model.t_end
    snap_dt = scene.output.interval or t_end / scene.output.snapshots
    series_dt = scene.output.timeseries_interval or snap_dt / 10.0
    next_snap = 0.0
    next_series = 0.0
    profiles = ProfileRecorder(model) if model.features.packed_bed_profiles else None
    total_steps = max(1, math.ceil(t_end / model.dt - 1e-9))
    status, message = "finished", ""
    from tidem.progress import RunProgress

    bar = RunProgress(enabled=progress, t_end=t_end, particles=int(model.active0.sum()) or model.capacity)
    try:
        with bar:
            while True:
                if solver.t >= next_series - 1e-12 * t_end:
                    out.sample(solver)
                    next_series += series_dt
                if solver.t >= next_snap - 1e-12 * t_end:
                    written = out.snapshot(solver)
                    next_snap += snap_dt
                    if on_snapshot is not None:
                        on_snapshot(written)
                if profiles is not None and profiles.due(solver.t):
                    profiles.record(solver)
                if view is not None:
                    view.update(solver)
                if solver.steps >= total_steps:
                    break
                solver.step()
                if solver.steps % 50 == 0 or solver.steps == total_steps:
                    bar.update(solver.t, solver.steps, time.perf_counter() - t0)
            solver.check()
    except RunError as exc:
        status, message = "failed", str(exc)
    except KeyboardInterrupt:
        status, message = "interrupted", f"interrupted at t = {solver.t:.6g} s (step {solver.steps})"
    finally:
        out.series.close()
        if model.angle_bins:
            out.write_alpha_profile(solver)
        wall = time.perf_counter() - t0 - (view.paused_s if view is not None else 0.0)
        data = summary(model, solver, status, wall, message)
        data["setup_s"] = setup_s
        if profiles is not None:
            data.setdefault("observables", {})["packed_bed_profiles"] = out.write_bed_profiles(solver, profiles)
        out.write_summary(data)
    return RunResult(status=status, out_dir=Path(out_dir), steps=solver.steps, wall_s=wall, message=message, summary=data)
