"""Triangle-mesh walls of a scene (`[[meshes]]`) as plain numpy for the Model: welded vertices
and triangles in scene coordinates at t = 0, material, friction, fixed temperature, and the rigid
motion (rotation about an axis through a centre, translation) plus a surface velocity.

The position of a mesh point at time t is (`MeshWall.points_at`)
    x(t) = c + s(t) + R(theta(t)) (x0 - c),   theta(t) = int_0^t omega dt',   s(t) = int_0^t v dt',
R the rotation by the angle theta about the unit `axis` (Rodrigues), c the rotation centre at
t = 0, omega the rotation speed and v the translation velocity (theta = omega t and s = v t where
they are constant; a schedule's exact integrals where the scene gives one, `tidem.scene.schedule`);
its velocity is v + Omega x (x(t) - c - s(t)) (Omega = omega axis), plus the surface velocity
projected onto the tangent plane at a contact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tidem.scene.schedule import Schedule, VectorSchedule, integral, largest_magnitude, value_at


@dataclass
class MeshWall:
    """One [[meshes]] entry, ready for the kernels."""

    name: str  # "meshes[k]"
    vertices: np.ndarray  # [V, 3] float64, scene coordinates at t = 0 [m]
    triangles: np.ndarray  # [T, 3] int32 indices into vertices
    material: str
    friction: float | None = None
    temperature: float | None = None  # fixed wall temperature [K] at t = 0, None: adiabatic
    convection_length: float | None = None  # length of the gas convection correlation [m] (`tidem.gas.mesh_convection`)
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)  # rotation centre at t = 0 [m]
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)  # unit rotation axis
    speed: float = 0.0  # rotation rate [rad/s] at t = 0
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)  # rigid translation [m/s] at t = 0
    surface_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)  # belt velocity [m/s]
    source: str = ""  # the file it was read from
    schedules: dict[str, Schedule | VectorSchedule] = field(default_factory=dict)  # "temperature", "speed", "velocity"
    stats: dict = field(default_factory=dict)  # what `tidem check` reports (welded vertices, dropped triangles, sag)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def surface(self) -> dict:
        """The mesh as a surface of the material-surface tables and heat summaries (as `tidem.walls.surfaces`'
        planes and tubes): name, material, friction override, fixed temperature."""
        return dict(name=self.name, material=self.material, friction=self.friction, T=self.temperature)

    def spans(self, axis: int, lo: float, length: float) -> bool:
        """Whether the mesh reaches from one end of the period [lo, lo + length] along `axis` to the
        other (within 1e-6 of it: an STL holds float32 coordinates); what it holds beyond is then not
        part of the apparatus (a drum's slice drawn over one period)."""
        tol = 1e-6 * length
        v = self.vertices[:, axis]
        return bool(v.min() <= lo + tol and v.max() >= lo + length - tol)

    @property
    def moving(self) -> bool:
        return self.rotates or self.translates

    @property
    def rotates(self) -> bool:
        return "speed" in self.schedules or self.speed != 0.0

    @property
    def translates(self) -> bool:
        return "velocity" in self.schedules or any(self.velocity)

    def _key(self, name: str):
        """A motion key as the scene gives it: its schedule, else its constant value."""
        return self.schedules.get(name, getattr(self, name))

    def speed_at(self, t: float) -> float:
        """omega(t) [rad/s]."""
        return float(value_at(self._key("speed"), t))

    def velocity_at(self, t: float) -> tuple[float, float, float]:
        """v(t) [m/s]."""
        return tuple(float(c) for c in value_at(self._key("velocity"), t))

    def temperature_at(self, t: float) -> float | None:
        """The fixed wall temperature at time t [K] (None: adiabatic)."""
        return value_at(self._key("temperature"), t)

    def angle_at(self, t: float) -> float:
        """theta(t) [rad]: omega t, or the integral of a scheduled speed."""
        return float(integral(self._key("speed"), t))

    def offset_at(self, t: float) -> np.ndarray:
        """s(t) [m]: v t, or the integral of a scheduled velocity."""
        return np.asarray(integral(self._key("velocity"), t), float)

    def rotation_at(self, t: float) -> np.ndarray:
        """R(theta(t)) [3, 3] (Rodrigues' formula)."""
        a = np.asarray(self.axis, float)
        th = self.angle_at(t)
        k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        return np.eye(3) + np.sin(th) * k + (1.0 - np.cos(th)) * (k @ k)

    def points_at(self, t: float, points: np.ndarray | None = None) -> np.ndarray:
        """Mesh points (default: its vertices) at time t [.., 3]."""
        p = self.vertices if points is None else np.asarray(points, float)
        c = np.asarray(self.center, float)
        return c + self.offset_at(t) + (p - c) @ self.rotation_at(t).T

    def max_speed(self) -> float:
        """The speed of the mesh's fastest point over the run [m/s]: translation plus rotation at its
        farthest vertex, each at its largest."""
        return largest_magnitude(self._key("velocity")) + largest_magnitude(self._key("speed")) * self.reach_from_axis()

    def first_faster(self, limit: float) -> float | None:
        """The first time [s] the mesh's fastest point moves faster than `limit` m/s (a bound: the
        translation's and the rotation's speeds added), or None."""
        times = sorted({0.0, *(t for s in self.schedules.values() for t in s.times)})
        fastest = [float(np.linalg.norm(self.velocity_at(t))) + abs(self.speed_at(t)) * self.reach_from_axis()
                   for t in times]
        for k, (t, v) in enumerate(zip(times, fastest)):
            if v > limit:  # both parts are piecewise linear (held or ramped) between these times
                if k == 0 or self._held():
                    return t
                t0, v0 = times[k - 1], fastest[k - 1]
                return t0 + (limit - v0) / (v - v0) * (t - t0)
        return None

    def _held(self) -> bool:
        return any("hold" in s.between for name, s in self.schedules.items() if name != "temperature")

    def reach_from_axis(self) -> float:
        """Largest distance of a vertex from the rotation axis [m] (0 without rotation); kept after
        the first call (the run asks every step)."""
        if "reach" not in self._cache:
            a = np.asarray(self.axis, float)
            d = self.vertices - np.asarray(self.center, float)
            far = float(np.sqrt(np.max(np.sum(np.cross(d, a) ** 2, axis=1)))) if len(d) else 0.0
            self._cache["reach"] = far if self.rotates else 0.0
        return self._cache["reach"]

    def displacement_bound(self, t0: float, t1: float) -> float:
        """An upper bound of how far any point of the mesh moves between t0 and t1 [m]: the chord
        2 R sin(omega dt / 2) of the farthest vertex plus the translation |v| dt, omega and |v| at their
        largest within [t0, t1] (a schedule's value is linear between its points, so its magnitude
        peaks at one of them or at an end)."""
        dt = abs(t1 - t0)
        omega, drift = self._largest_between("speed", t0, t1), self._largest_between("velocity", t0, t1)
        chord = 2.0 * self.reach_from_axis() * abs(math.sin(min(0.5 * omega * dt, 0.5 * math.pi)))
        return chord + drift * dt

    def _largest_between(self, name: str, t0: float, t1: float) -> float:
        key = f"largest {name}"
        if name not in self.schedules:
            if key not in self._cache:
                self._cache[key] = largest_magnitude(getattr(self, name))
            return self._cache[key]
        s = self.schedules[name]
        lo, hi = min(t0, t1), max(t0, t1)
        return max(largest_magnitude(value_at(s, t)) for t in [lo, hi, *(t for t in s.times if lo < t < hi)])


STEP_SHARE = 0.2  # the most a particle may close on a mesh in one step, as a share of the smallest radius


def pass_through_errors(meshes: list[MeshWall], dt: float, speed: float, r_min: float) -> list[str]:
    """Refusals of a step at which a particle could pass through a mesh sheet between two contact
    checks: the particles' impact speed `speed` (`tidem.particles.timestep`) plus a mesh's fastest point
    (translation plus rotation at its farthest vertex) times dt must stay below STEP_SHARE of the
    smallest radius r_min."""
    out = []
    for m in meshes:
        closing = (speed + m.max_speed()) * dt
        if closing > STEP_SHARE * r_min:
            when = ""
            if m.schedules.keys() - {"temperature"}:
                when = f" from t = {m.first_faster(STEP_SHARE * r_min / dt - speed):.4g} s on (its schedule)"
            fix = (f"lower rotation.speed or velocity (the mesh's fastest point moves at {m.max_speed():.3g} m/s{when}), "
                   if m.moving else "")
            out.append(f"{m.name}: a particle could close {closing:.3g} m on it in one step of {dt:.3g} s, more than "
                       f"{STEP_SHARE:g} of the smallest radius ({r_min:.3g} m), and pass through a thin sheet between "
                       f"two contact checks; {fix}lower numerics.dt_fraction (or numerics.dt) to below "
                       f"{STEP_SHARE * r_min / (speed + m.max_speed()):.3g} s")
    return out


def report_lines(meshes: list[MeshWall], table, d_min: float) -> list[str]:
    """What `tidem check` says of each mesh: triangles, vertices welded, area, the largest facet sag
    against the smallest particle diameter (a coarse cylinder is a polygon), its motion; and the
    triangles the kernels hold (periodic copies included) with their cell lists and flat patches."""
    out = []
    for m in meshes:
        st = m.stats
        sag = st.get("sag", 0.0)
        motion = f", moving (fastest point {m.max_speed():.3g} m/s)" if m.moving else ""
        motion += " on a schedule" if m.schedules.keys() - {"temperature"} else ""
        heated = f", at {m.temperature:g} K" if m.temperature is not None else ""
        heated += " (scheduled)" if "temperature" in m.schedules else ""
        out.append(f"{m.name}: {m.source or 'mesh'}: {len(m.triangles)} triangles, {len(m.vertices)} vertices "
                   f"({st.get('welded', 0)} welded), area {st.get('area', float('nan')):.4g} m^2, largest facet sag "
                   f"{sag:.3g} m = {100 * sag / d_min:.2g} % of the smallest particle diameter{heated}{motion}")
    if table is not None:
        flat = len(np.unique(table.patch[table.patch >= 0]))
        out.append(f"mesh triangles in the kernels: {len(table.mesh_id)} (periodic copies included), "
                   f"{len(table.tri)} cell entries; {flat} flat patches (a particle over one touches its face alone)")
    return out
