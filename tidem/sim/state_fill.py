"""Start values of the State's fields (`tidem.sim.state.allocate` places them): positions,
velocities, sizes and masses of the particles, temperatures and heat capacities, the walls',
tubes' and heated foils' tables, and the mesh triangles with their bins (S: a `tidem.sim.state.State`).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from tidem.kernels.field_copy import write_fields
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


def particle_values(model: Model) -> dict:
    """Start positions, velocities and sizes; fixed particles get zero inverse mass and inertia."""
    feat = model.features
    N = model.capacity
    radius = model.radius
    inertia = 0.4 * model.mass * radius**2
    movable = ~model.fixed  # fixed particles: zero inverse mass and inertia, zero velocity
    values = {"x": model.x0, "x_build": model.x0, "v": model.v0 * movable[:, None], "radius": radius,
              "mass": model.mass, "inv_mass": movable / model.mass, "inv_inertia": movable / inertia,
              "mat": model.material, "active": model.active0, "ident": np.arange(N), "wid": -1}
    if feat.growth:
        values["r_build"] = radius
    if feat.reactions:
        values["rx"] = model.reaction_index
        if "sublimation" in feat.reactions:
            values.update(rt0=-1.0, rt1=0.0)
    if feat.coarse_grain and feat.gas:
        values["cg"] = model.coarse_grain
    if feat.contact_time:
        values.update(touch_start=-1.0, touch_end=-1.0)
    return values


def heat_values(model: Model) -> dict:
    """Start temperatures, 1/(m c), fixed surface temperatures, foils and the tubes' side vectors."""
    feat = model.features
    T0 = model.scene.heat.initial_temperature  # a foil's own temperature is in tube_bin_T
    temps = [T0 if s.get("flux") is not None else s["T"] for s in model.planes + model.tubes]
    temps += [m.temperature for m in model.meshes]
    values = {"T": model.temperature0, "inv_heat_cap": 1.0 / model.heat_capacity,
              "surf_T": np.array([-1.0 if T is None else T for T in temps] or [-1.0])}
    if feat.foil:
        values.update(tube_foil=np.array([foil_vector(t, model) for t in model.tubes]), tube_bin_T=T0)
    if feat.wall_foil:
        values.update(plane_foil=np.array([wall_foil_vector(p, model) for p in model.planes]), plane_foil_T=T0)
    if model.angle_bins:
        values["tube_side"] = np.array([[0.0, 1.0, 0.0] if t["mask"][1] else [1.0, 0.0, 0.0] for t in model.tubes])
    return values


def surface_values(S: SimpleNamespace, model: Model) -> dict:
    """The parameter tables and the geometry of the tubes and the meshes."""
    values = {"pp": model.pair_params, "ps": model.surface_params}
    if model.features.n_meshes:
        values.update(mesh_values(S, model))
    if model.tubes:
        values.update(tube_c=np.array([t["c"] for t in model.tubes], float),
                      tube_mask=np.array([t["mask"] for t in model.tubes], float),
                      tube_r=np.array([t["r"] for t in model.tubes], float))
    return values


def mesh_values(S: SimpleNamespace, model: Model) -> dict:
    """Triangles at t = 0, their bins, the meshes' motion (v, Omega, centre, surface velocity)."""
    tab = model.mesh_table
    values = {"tri_v": tab.rest + tab.shift[:, None, :], "tri_mesh": tab.mesh_id, "tri_patch": tab.patch,
              "mbin_start": tab.start, "mbin_tri": padded_bins(S, tab.tri), "mh_id": -1,
              "mesh_motion": np.array([[m.velocity, np.asarray(m.axis) * m.speed, m.center, m.surface_velocity]
                                       for m in model.meshes], float)}
    if model.features.moving_meshes:
        values.update(tri_rest=tab.rest, tri_shift=tab.shift)
    return values


def padded_bins(S: SimpleNamespace, tri: np.ndarray) -> np.ndarray:
    """The triangles' cell lists in mbin_tri's length (zeros after them)."""
    full = np.zeros(S.mbin_tri.shape[0], np.int32)
    full[:len(tri)] = tri
    return full


def fill(S: SimpleNamespace, model: Model) -> None:
    """Every start value of the State's fields, in one launch per element type (`kernels/field_copy.py`);
    a number fills its whole field."""
    values = particle_values(model)
    if model.features.heat:
        values.update(heat_values(model))
    values.update(surface_values(S, model))
    write_fields({name: (getattr(S, name), value) for name, value in values.items()})


def load_bins(S: SimpleNamespace, start: np.ndarray, tri: np.ndarray) -> None:
    """Put the triangles' cell lists (`tidem.walls.mesh_bins.bin_triangles`) into mbin_start / mbin_tri."""
    S.mbin_start.from_numpy(start)
    S.mbin_tri.from_numpy(padded_bins(S, tri))
