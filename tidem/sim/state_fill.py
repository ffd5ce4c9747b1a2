"""Start values of the State's fields (`tidem.sim.state.allocate` places them): positions,
velocities, sizes and masses of the particles, temperatures and heat capacities, the walls',
tubes' and heated foils' tables, and the mesh triangles with their bins (S: a `tidem.sim.state.State`).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from tidem.sim.model import Model
from tidem.walls.surfaces import angle_bin_area


def foil_vector(tube: dict, model: Model) -> list[float]:
    """tube_foil's row for a tube (see the module docstring); zeros unless it has a heat flux."""
    if tube["flux"] is None:
        return [0.0, 1.0, 1.0, 0.0]
    ds = 2 * np.pi * tube["r"] / model.angle_bins
    return [tube["flux"], tube["foil_C"], angle_bin_area(model, tube), tube["foil_G"] / ds**2]


def wall_foil_vector(plane: dict, model: Model) -> list[float]:
    """plane_foil's row: heating per area [W/m^2], foil heat capacity per area [J/(m^2 K)] and
    the wall's area, the domain's cross-section normal to it [m^2]; zeros without a heat flux."""
    if plane.get("flux") is None:
        return [0.0, 1.0, 1.0]
    axis = int(np.argmax(np.abs(plane["n"])))
    area = float(np.prod([model.grid.length[a] for a in range(3) if a != axis]))
    return [plane["flux"], plane["foil_C"], area]


def fill_particles(S: SimpleNamespace, model: Model) -> None:
    """Start positions, velocities and sizes; fixed particles get zero inverse mass and inertia."""
    feat = model.features
    N = model.capacity
    radius = model.radius
    inertia = 0.4 * model.mass * radius**2
    movable = ~model.fixed  # fixed particles: zero inverse mass and inertia, zero velocity
    S.x.from_numpy(model.x0)
    S.x_build.from_numpy(model.x0)
    S.v.from_numpy(model.v0 * movable[:, None])
    S.radius.from_numpy(radius)
    if feat.growth:
        S.r_build.from_numpy(radius)
    S.mass.from_numpy(model.mass)
    S.inv_mass.from_numpy(movable / model.mass)
    S.inv_inertia.from_numpy(movable / inertia)
    S.mat.from_numpy(model.material)
    if feat.reactions:
        S.rx.from_numpy(model.reaction_index)
        if "sublimation" in feat.reactions:
            S.rt0.fill(-1.0)
            S.rt1.fill(0.0)
    S.active.from_numpy(model.active0.astype(np.int32))
    if feat.coarse_grain and feat.gas:
        S.cg.from_numpy(model.coarse_grain)
    S.ident.from_numpy(np.arange(N, dtype=np.int32))
    S.wid.fill(-1)
    if feat.contact_time:
        S.touch_start.fill(-1.0)
        S.touch_end.fill(-1.0)


def fill_heat(S: SimpleNamespace, model: Model) -> None:
    """Start temperatures, 1/(m c), fixed surface temperatures, foils and the tubes' side vectors."""
    feat = model.features
    S.T.from_numpy(model.temperature0)
    S.inv_heat_cap.from_numpy(1.0 / model.heat_capacity)
    T0 = model.scene.heat.initial_temperature  # a foil's own temperature is in tube_bin_T
    temps = [T0 if s.get("flux") is not None else s["T"] for s in model.planes + model.tubes]
    temps += [m.temperature for m in model.meshes]
    S.surf_T.from_numpy(np.array([-1.0 if T is None else T for T in temps] or [-1.0]))
    if feat.foil:
        S.tube_foil.from_numpy(np.array([foil_vector(t, model) for t in model.tubes]))
        S.tube_bin_T.fill(T0)
    if feat.wall_foil:
        S.plane_foil.from_numpy(np.array([wall_foil_vector(p, model) for p in model.planes]))
        S.plane_foil_T.fill(T0)
    if model.angle_bins:
        S.tube_side.from_numpy(np.array([[0.0, 1.0, 0.0] if t["mask"][1] else [1.0, 0.0, 0.0]
                                         for t in model.tubes]))


def fill_surfaces(S: SimpleNamespace, model: Model) -> None:
    """The parameter tables and the geometry of the tubes."""
    S.pp.from_numpy(model.pair_params)
    S.ps.from_numpy(model.surface_params)
    if model.features.n_meshes:
        _fill_meshes(S, model)
    if model.tubes:
        S.tube_c.from_numpy(np.array([t["c"] for t in model.tubes], float))
        S.tube_mask.from_numpy(np.array([t["mask"] for t in model.tubes], float))
        S.tube_r.from_numpy(np.array([t["r"] for t in model.tubes], float))


def _fill_meshes(S: SimpleNamespace, model: Model) -> None:
    """Triangles at t = 0, their bins, the meshes' motion (v, Omega, centre, surface velocity)."""
    tab = model.mesh_table
    S.tri_v.from_numpy(tab.rest + tab.shift[:, None, :])
    S.tri_mesh.from_numpy(tab.mesh_id)
    S.tri_patch.from_numpy(tab.patch)
    if model.features.moving_meshes:
        S.tri_rest.from_numpy(tab.rest)
        S.tri_shift.from_numpy(tab.shift)
    load_bins(S, tab.start, tab.tri)
    S.mesh_motion.from_numpy(np.array([[m.velocity, np.asarray(m.axis) * m.speed, m.center, m.surface_velocity]
                                       for m in model.meshes], float))
    S.mh_id.fill(-1)


def load_bins(S: SimpleNamespace, start: np.ndarray, tri: np.ndarray) -> None:
    """Put the triangles' cell lists (`tidem.walls.mesh_bins.bin_triangles`) into mbin_start / mbin_tri."""
    S.mbin_start.from_numpy(start)
    full = np.zeros(S.mbin_tri.shape[0], np.int32)
    full[:len(tri)] = tri
    S.mbin_tri.from_numpy(full)
