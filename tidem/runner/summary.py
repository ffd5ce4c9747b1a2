"""run.json's tables of a run: the summary (scene, counts, time steps, speed, what the renderer
needs) and the observables with the per-particle and per-time tables behind some of them
(`tidem.results.observables`). The run loop (`tidem.runner.loop`) writes them at the start and the end.
"""

from __future__ import annotations

import numpy as np

from tidem.io.mesh_output import mesh_geometry
from tidem.render.settings import render_settings
from tidem.results import observables as obs
from tidem.results.hydrodynamics import bed_weight_per_area
from tidem.scene.schedule import is_scheduled, start
from tidem.sim.model import Model
from tidem.sim.solver import Solver
from tidem.version import __version__


def distributor_parts(scene) -> list[dict]:
    """The gas distributor for the frames: the background inflow, then each nozzle (velocity at t = 0,
    and its schedule where the scene gives one)."""
    gas = scene.gas
    if gas is None:
        return []
    parts = [{"background": True, "velocity": gas.inlet_velocity}]
    parts += [{"x": list(nz.x), "y": list(nz.y) if nz.y is not None else None, "velocity": nz.velocity}
              for nz in gas.nozzles]
    for part in parts:
        if is_scheduled(part["velocity"]):
            part["schedule"] = part["velocity"].model_dump()
            part["velocity"] = start(part["velocity"])
    return parts


def summary(model: Model, solver: Solver | None, status: str, wall: float, message: str = "",
            mean_particles: float | None = None) -> dict:
    """run.json's table; particle_steps_per_s counts `mean_particles` (the time-series mean,
    for runs whose particle count changes: pours, outlets, reactions) or else the particles now."""
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
        **({"grains_at_start": round(float((model.coarse_grain[model.active0] ** 3).sum())),
            "coarse_grain": sorted({float(k) for k in model.coarse_grain})} if f.coarse_grain else {}),
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
        "particle_steps_per_s": (n if mean_particles is None else mean_particles) * steps / wall if wall > 0 else 0.0,
        "precision": f.precision,
        **({"bed_weight_per_area_Pa": bed_weight_per_area(float(model.mass[model.active0].sum()),
                                                          model.scene.domain.gravity, model.scene.domain.min,
                                                          model.scene.domain.max)} if f.gas else {}),
        "scene_echo": model.loaded.raw,
        "render": render_settings(model),
        "render_geometry": {
            "bounds": [v for a in range(3) for v in (model.scene.domain.min[a], model.scene.domain.max[a])],
            "periodic": list(model.grid.periodic),
            "tubes": [{"c": t["c"], "mask": t["mask"], "r": t["r"], "T": t["T"]} for t in model.tubes],
            "distributor": distributor_parts(model.scene),
            "meshes": mesh_geometry(model.meshes),
        },
    }
    return out


def observed(model: Model, solver: Solver, series: dict[str, np.ndarray], bed_profiles: dict | None = None,
             snapshots: list | None = None) -> dict:
    """run.json's `observables` (the scene's declared ones, `tidem.results.observables`) and the
    per-particle or per-time tables behind some of them; `snapshots` the run's snapshot files [(time, path)]."""
    names = model.scene.observables
    if not names:
        return {}
    rec = obs.record(model, solver, series, bed_profiles, snapshots)
    out = {"observables": obs.compute(names, rec)}
    if bed_profiles:
        out["packed_bed_profiles"] = bed_profiles
    if rec.contact_rows:
        out["contact_times"] = rec.contact_rows
    if rec.impact_rows:
        out["impact_heat"] = rec.impact_rows
    if rec.packet_rows:
        out["packet_model"] = rec.packet_rows
    return out
