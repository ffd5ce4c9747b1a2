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


import numpy as np
import taichi as ti

from tidem.scene.schedule import Schedule
from tidem.walls.surfaces import plate_velocity, plate_z


class Conditions:
    """The scheduled surface temperatures and mesh motions of a run."""

    def __init__(self, model, state, gas=None):
        self.state, self.gas = state, gas
        surfaces = model.planes + model.tubes
        self.temperatures: list[tuple[int, Schedule]] = [
            (s, surface["T_schedule"]) for s, surface in enumerate(surfaces) if surface.get("T_schedule") is not None]
        self.temperatures += [(len(surfaces) + k, m.schedules["temperature"]) for k, m in enumerate(model.meshes)
                              if "temperature" in m.schedules]
        n_planes = len(model.planes)
        self.wall_index = {s: s - n_planes for s, _ in self.temperatures if s >= n_planes}  # gas wall_k: tubes, meshes
        self.meshes = [(k, m) for k, m in enumerate(model.meshes) if m.schedules.keys() - {"temperature"}
                       and model.features.scheduled_motion]
        self.plates = [(s, p) for s, p in enumerate(model.planes) if p.get("speed_schedule") is not None]
        self.last: dict[int, float] = {}
        self._set_motion = make_motion_setter(state) if self.meshes else None

    @property
    def active(self) -> bool:
        return bool(self.temperatures or self.meshes or self.plates)

    def apply(self, t: float) -> None:
        """Write the scheduled values at time t."""
        S = self.state
        for s, schedule in self.temperatures:
            value = schedule.at(t)
            if self.last.get(s) != value:
                self.last[s] = value
                S.surf_T[s] = value
                if self.gas is not None and self.gas.walls and s in self.wall_index:
                    self.gas.set_wall_temperature(self.wall_index[s], value)
        for s, plane in self.plates:
            S.plane_shift[s] = ti.Vector([0.0, 0.0, plate_z(plane, t) - plane["p0"][2]])
            S.plane_u[s] = ti.Vector([0.0, 0.0, plate_velocity(plane, t)])
        for k, m in self.meshes:
            v = np.asarray(m.velocity_at(t))
            offset = m.offset_at(t)
            centre = np.asarray(m.center, float) + offset - v * t
            omega = np.asarray(m.axis, float) * m.speed_at(t)
            self._set_motion(k, m.angle_at(t), *offset, *v, *omega, *centre)


    def sync_from_fields(self) -> None:
        """After a checkpoint's fields are restored: the surface temperatures last written."""
        self.last = {s: float(self.state.surf_T[s]) for s, _ in self.temperatures}


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
