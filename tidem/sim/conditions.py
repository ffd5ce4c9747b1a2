"""Conditions that follow a schedule while a run goes (`tidem.scene.schedule`): before each step's
forces the Solver asks `Conditions.apply(t)`, which writes the scheduled values at time t into the
fields the kernels read, each only when it has changed:

- fixed surface temperatures (planes, tubes, meshes): surf_T, and the gas's wall_T of the cells
  beside a heated tube or mesh (`tidem.gas.phase.GasPhase.set_wall_temperature`);
- an outlet plate's speed: its shift from its start height and its velocity, plane_shift and plane_u
  (`kernels/surface_contact.py`; `tidem.walls.surfaces.plate_z`, the integral of the speed until the
  plate reaches its stop height);
- a mesh's rotation speed and velocity: its angle theta(t) and offset s(t), the schedules' exact
  integrals, in mesh_pose (`kernels/mesh_contact.make_mesh_mover`), and its motion row mesh_motion
  (v(t), omega(t) axis, and c0 + s(t) - v(t) t as the centre, which the contact kernels move by
  v t to the rotation centre at t).

The gas inlet's velocities and temperature are set by the gas phase itself at each gas step
(`GasPhase.set_inlet`). Every value is a function of t alone, so a run resumed from a checkpoint
takes the same values at the same steps as the unbroken run.
"""


import dataclasses
import re

import numpy as np
import taichi as ti

from tidem.scene.schedule import Schedule
from tidem.walls.surfaces import NEVER, plate_velocity, plate_z


class Conditions:
    """The scheduled surface temperatures, outlet plate and mesh motions of a run; `install` puts a new
    schedule of a scene key in place while the run goes (`tidem.runner.steering`)."""

    def __init__(self, model, state, gas=None):
        self.model, self.state, self.gas = model, state, gas
        surfaces = model.planes + model.tubes
        self.n_planes, self.n_surfaces = len(model.planes), len(surfaces)
        self.temperatures: dict[int, Schedule] = {
            s: surface["T_schedule"] for s, surface in enumerate(surfaces) if surface.get("T_schedule") is not None}
        self.temperatures.update({self.n_surfaces + k: m.schedules["temperature"] for k, m in enumerate(model.meshes)
                                  if "temperature" in m.schedules})
        self.meshes = [k for k, m in enumerate(model.meshes) if m.schedules.keys() - {"temperature"}
                       and model.features.scheduled_motion]
        self.plates = [s for s, p in enumerate(model.planes) if p.get("speed_schedule") is not None]
        self.last: dict[int, float] = {}
        self._set_motion = make_motion_setter(state) if self.meshes else None

    @property
    def active(self) -> bool:
        return bool(self.temperatures or self.meshes or self.plates)

    def apply(self, t: float) -> None:
        """Write the scheduled values at time t."""
        S = self.state
        for s, schedule in self.temperatures.items():
            value = schedule.at(t)
            if self.last.get(s) != value:
                self.last[s] = value
                S.surf_T[s] = value
                if self.gas is not None and self.gas.walls and s >= self.n_planes:  # gas wall_k: tubes, then meshes
                    self.gas.set_wall_temperature(s - self.n_planes, value)
        for s in self.plates:
            plane = self.model.planes[s]
            S.plane_shift[s] = ti.Vector([0.0, 0.0, plate_z(plane, t) - plane["p0"][2]])
            S.plane_u[s] = ti.Vector([0.0, 0.0, plate_velocity(plane, t)])
        for k in self.meshes:
            m = self.model.meshes[k]
            v = np.asarray(m.velocity_at(t))
            offset = m.offset_at(t)
            centre = np.asarray(m.center, float) + offset - v * t
            omega = np.asarray(m.axis, float) * m.speed_at(t)
            self._set_motion(k, m.angle_at(t), *offset, *v, *omega, *centre)

    def sync_from_fields(self) -> None:
        """After a checkpoint's fields are restored: the surface temperatures last written."""
        self.last = {s: float(self.state.surf_T[s]) for s in self.temperatures}

    def install(self, key: str, schedule: Schedule) -> None:
        """From now on the scene key `key` follows `schedule` (ValueError for a key this run cannot change:
        it is not a scheduled condition, or its motion was compiled in as a constant)."""
        model = self.model
        if key.startswith("gas."):
            if self.gas is None:
                raise ValueError(f"{key}: the scene has no [gas]")
            self.gas.install(key, schedule)
            return
        if key == "domain.wall_temperature" or key.endswith(".temperature"):
            for s in self._surfaces(key):
                self.temperatures[s] = schedule
                self.last.pop(s, None)
            return
        found = re.fullmatch(r"meshes\[(\d+)\]\.(rotation\.speed|velocity)", key)
        if found:
            k = int(found[1])
            if k not in self.meshes:
                raise ValueError(f"{key}: meshes[{k}]'s motion is compiled in as a constant in this run")
            model.meshes[k].schedules["speed" if found[2] == "rotation.speed" else "velocity"] = schedule
            return
        if key == "outlet.speed" and self.plates:
            model.planes[self.plates[0]]["speed_schedule"] = schedule
            return
        raise ValueError(f"{key}: not a condition this run can change")

    def _surfaces(self, key: str) -> list[int]:
        """The surface-table indices (planes, tubes, meshes) whose fixed temperature `key` sets."""
        planes = self.model.planes
        if key == "domain.wall_temperature":
            found = [s for s, p in enumerate(planes) if p["name"].startswith("box ")]
        elif (m := re.fullmatch(r"walls\[(\d+)\]\.temperature", key)):
            found = [s for s, p in enumerate(planes) if p["name"] == f"walls[{m[1]}]"]
        elif (m := re.fullmatch(r"tubes\[(\d+)\]\.temperature", key)) and int(m[1]) < len(self.model.tubes):
            found = [self.n_planes + int(m[1])]
        elif (m := re.fullmatch(r"meshes\[(\d+)\]\.temperature", key)) and int(m[1]) < len(self.model.meshes):
            found = [self.n_surfaces + int(m[1])]
        else:
            found = []
        if not found:
            raise ValueError(f"{key}: no such surface in this scene")
        return found


def make_steerable(model) -> None:
    """Before the Solver is built: compile every rotating mesh and the outlet plate with the motion the
    host sets each step (a one-point schedule of their constant speed), so that a live control
    (`tidem.runner.steering`) can change their speed. The same bits in float64 (theta = omega t either
    way)."""
    for m in model.meshes:
        if m.rotates and "speed" not in m.schedules:
            m.schedules["speed"] = Schedule(times=[0.0], values=[m.speed])
    for p in model.planes:
        if p["name"] == "outlet plate" and p.get("speed_schedule") is None:
            p["speed_schedule"] = Schedule(times=[0.0], values=[-p["vel"][2]])
            p["t"] = (p["t"][0], NEVER)
    f = model.features
    model.features = dataclasses.replace(
        f, scheduled_motion=f.contacts and any(m.schedules.keys() - {"temperature"} for m in model.meshes),
        scheduled_plate=any(p.get("speed_schedule") is not None for p in model.planes))


def make_motion_setter(S):
    """One launch per mesh and step: its pose (theta, s) and motion row (v, omega axis, centre)."""

    @ti.kernel
    def set_motion(k: ti.i32, theta: float, sx: float, sy: float, sz: float, vx: float, vy: float, vz: float,
                   wx: float, wy: float, wz: float, cx: float, cy: float, cz: float):
        S.mesh_pose[k] = ti.Vector([theta, sx, sy, sz])
        S.mesh_motion[k, 0] = ti.Vector([vx, vy, vz])
        S.mesh_motion[k, 1] = ti.Vector([wx, wy, wz])
        S.mesh_motion[k, 2] = ti.Vector([cx, cy, cz])

    return set_motion
