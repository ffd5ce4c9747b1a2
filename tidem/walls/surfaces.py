"""Walls and tubes of a scene as plain dicts for the Model: the box sides, `[[walls]]` and a
moving outlet plate as planes (point p0, unit normal n, velocity, active time span; a plate whose
speed follows a schedule carries it as `speed_schedule`, and `plate_z` gives its height), `[[tubes]]`
as infinite cylinders (centre c, axis mask, radius r), each with its material, friction, fixed
temperature (`T`, at t = 0; `T_schedule` where the scene gives one) and heated-foil settings. The
contact kernels that use them: `kernels/contact.py`
(wall and tube contacts), `kernels/heat.py` (wall conduction and radiation).
"""

from __future__ import annotations

import math

import numpy as np

from tidem.scene.schedule import integral, is_scheduled, start, value_at

AXES = "xyz"
NEVER = 1e30


def surfaces(scene, default_mat: str):
    """Planes (box sides, walls, outlet plate) and tubes with their materials and friction."""
    dom = scene.domain
    planes: list[dict] = []
    for side in dom.wall_sides():
        a = AXES.index(side[0])
        n = [0.0, 0.0, 0.0]
        p0 = [0.0, 0.0, 0.0]
        if side[1] == "-":
            n[a], p0[a] = 1.0, dom.min[a]
        else:
            n[a], p0[a] = -1.0, dom.max[a]
        if side == "z-" and scene.outlet is not None and scene.outlet.type == "moving_plate":
            continue  # the plate is the floor
        planes.append(dict(name=f"box {side}", p0=p0, n=n, vel=[0.0] * 3, t=(0.0, NEVER),
                           material=dom.wall_material or default_mat, friction=dom.wall_friction,
                           **_temperature(dom.wall_temperature)))
    for i, w in enumerate(scene.walls):
        n = np.asarray(w.normal, float)
        planes.append(dict(name=f"walls[{i}]", p0=list(w.point), n=list(n / np.linalg.norm(n)), vel=list(w.velocity),
                           t=(0.0, NEVER), material=w.material or default_mat, friction=w.friction,
                           **_temperature(w.temperature),
                           flux=w.heat_flux, foil_C=w.foil_heat_capacity, foil_G=0.0))
    if scene.outlet is not None and scene.outlet.type == "moving_plate":
        o = scene.outlet
        h = dom.min[2] if o.height is None else o.height
        stop = dom.min[2] if o.stop_height is None else o.stop_height
        plan = o.speed if is_scheduled(o.speed) else None
        t1 = NEVER if plan is not None else o.start + max(h - stop, 0.0) / o.speed
        planes.append(dict(name="outlet plate", p0=[0.0, 0.0, h], n=[0.0, 0.0, 1.0], vel=[0.0, 0.0, -start(o.speed)],
                           t=(o.start, t1), material=o.material or default_mat, friction=o.friction, T=None,
                           T_schedule=None, speed_schedule=plan, stop=stop))
    tubes = []
    for i, t in enumerate(scene.tubes):
        mask = [0.0 if AXES[a] == t.axis else 1.0 for a in range(3)]
        tubes.append(dict(name=f"tubes[{i}]", c=list(t.center), mask=mask, r=0.5 * t.diameter,
                          material=t.material or default_mat, friction=t.friction, **_temperature(t.temperature),
                          flux=t.heat_flux, foil_C=t.foil_heat_capacity, foil_G=t.foil_conductance))
    return planes, tubes


def moves(plane: dict) -> bool:
    """A plane that moves at some time: a velocity, or an outlet plate on a speed schedule."""
    return any(plane["vel"]) or plane.get("speed_schedule") is not None


def plate_z(plane: dict, t: float) -> float:
    """The outlet plate's height at time t [m]: it sinks from `start` at its speed (a schedule's value at
    each time) until it reaches the stop height."""
    t0, t1 = plane["t"]
    plan = plane.get("speed_schedule")
    if plan is None:
        return plane["p0"][2] + plane["vel"][2] * (min(max(t, t0), t1) - t0)
    sunk = integral(plan, max(t, t0)) - integral(plan, t0)
    return max(plane["p0"][2] - sunk, plane["stop"])


def plate_velocity(plane: dict, t: float) -> float:
    """The outlet plate's vertical velocity at time t [m/s] (negative: sinking; 0 before start and at the stop)."""
    t0, t1 = plane["t"]
    if not t0 < t < t1 or plate_z(plane, t) <= plane["stop"]:
        return 0.0
    plan = plane.get("speed_schedule")
    return plane["vel"][2] if plan is None else -float(value_at(plan, t))


def _temperature(value) -> dict:
    """A surface's fixed temperature as the surface dicts hold it: T at t = 0 and the schedule, if any."""
    return dict(T=start(value), T_schedule=value if is_scheduled(value) else None)


def angle_bin_area(model, tube: dict) -> float:
    """Tube surface in one angle bin inside the domain [m^2]: arc 2 pi r / heat.angle_bins
    times the domain's length along the tube axis."""
    axis = 0 if tube["mask"][0] == 0.0 else 1
    return 2 * math.pi * tube["r"] / model.angle_bins * model.grid.length[axis]


def is_heated(surface: dict) -> bool:
    """A plane or tube with a fixed temperature, or a heated-foil tube (fixed heat flux)."""
    return surface["T"] is not None or surface.get("flux") is not None
