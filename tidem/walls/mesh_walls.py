"""Triangle-mesh walls of a scene (`[[meshes]]`) as plain numpy for the Model: welded vertices
and triangles in scene coordinates at t = 0, material, friction, fixed temperature, and the rigid
motion (rotation about an axis through a centre, translation) plus a surface velocity.

The position of a mesh point at time t is (`MeshWall.points_at`)
    x(t) = c + v t + R(omega t) (x0 - c),
R the rotation by the angle omega t about the unit `axis` (Rodrigues), c the rotation centre at
t = 0, v the translation velocity; its velocity is v + Omega x (x(t) - c - v t) (Omega = omega axis),
plus the surface velocity projected onto the tangent plane at a contact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class MeshWall:
    """One [[meshes]] entry, ready for the kernels."""

    name: str  # "meshes[k]"
    vertices: np.ndarray  # [V, 3] float64, scene coordinates at t = 0 [m]
    triangles: np.ndarray  # [T, 3] int32 indices into vertices
    material: str
    friction: float | None = None
    temperature: float | None = None  # fixed wall temperature [K], None: adiabatic
    convection_length: float | None = None  # length of the gas convection correlation [m] (`tidem.gas.mesh_convection`)
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)  # rotation centre at t = 0 [m]
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)  # unit rotation axis
    speed: float = 0.0  # rotation rate [rad/s]
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)  # rigid translation [m/s]
    surface_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)  # belt velocity [m/s]
    source: str = ""  # the file it was read from
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
        return self.speed != 0.0 or any(self.velocity)

    def rotation_at(self, t: float) -> np.ndarray:
        """R(omega t) [3, 3] (Rodrigues' formula)."""
        a = np.asarray(self.axis, float)
        th = self.speed * t
        k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        return np.eye(3) + np.sin(th) * k + (1.0 - np.cos(th)) * (k @ k)

    def points_at(self, t: float, points: np.ndarray | None = None) -> np.ndarray:
        """Mesh points (default: its vertices) at time t [.., 3]."""
        p = self.vertices if points is None else np.asarray(points, float)
        c = np.asarray(self.center, float)
        return c + np.asarray(self.velocity, float) * t + (p - c) @ self.rotation_at(t).T

    def max_speed(self) -> float:
        """The speed of the mesh's fastest point [m/s]: translation plus rotation at its farthest vertex."""
        return float(np.linalg.norm(self.velocity)) + abs(self.speed) * self.reach_from_axis()

    def reach_from_axis(self) -> float:
        """Largest distance of a vertex from the rotation axis [m] (0 without rotation); kept after
        the first call (the run asks every step)."""
        if "reach" not in self._cache:
            a = np.asarray(self.axis, float)
            d = self.vertices - np.asarray(self.center, float)
            far = float(np.sqrt(np.max(np.sum(np.cross(d, a) ** 2, axis=1)))) if len(d) else 0.0
            self._cache["reach"] = far if self.speed != 0.0 else 0.0
            self._cache["drift"] = float(np.linalg.norm(self.velocity))
        return self._cache["reach"]

    def displacement_bound(self, t0: float, t1: float) -> float:
        """An upper bound of how far any point of the mesh moves between t0 and t1 [m]: the chord
        2 R sin(omega dt / 2) of the farthest vertex plus the translation."""
        dt = abs(t1 - t0)
        chord = 2.0 * self.reach_from_axis() * abs(math.sin(min(0.5 * self.speed * dt, 0.5 * math.pi)))
        return chord + self._cache["drift"] * dt


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
            fix = (f"lower rotation.speed or velocity (the mesh's fastest point moves at {m.max_speed():.3g} m/s), "
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
        heated = f", at {m.temperature:g} K" if m.temperature is not None else ""
        out.append(f"{m.name}: {m.source or 'mesh'}: {len(m.triangles)} triangles, {len(m.vertices)} vertices "
                   f"({st.get('welded', 0)} welded), area {st.get('area', float('nan')):.4g} m^2, largest facet sag "
                   f"{sag:.3g} m = {100 * sag / d_min:.2g} % of the smallest particle diameter{heated}{motion}")
    if table is not None:
        flat = len(np.unique(table.patch[table.patch >= 0]))
        out.append(f"mesh triangles in the kernels: {len(table.mesh_id)} (periodic copies included), "
                   f"{len(table.tri)} cell entries; {flat} flat patches (a particle over one touches its face alone)")
    return out
