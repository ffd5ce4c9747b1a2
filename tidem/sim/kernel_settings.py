"""What the contact kernels take from the model besides fields: the rounding margins of the quiet
partners and of the mesh contacts, the mesh settings, and which surfaces never move."""

from __future__ import annotations

import numpy as np

from tidem.sim.model import Model
from tidem.walls.mesh_bins import MESH_SLOTS
from tidem.walls.surfaces import moves

QUIET_MARGIN = 1e-4  # of the skin: the rounding margin of the quiet partners' reach (kernels/contact.py)


def rounding_unit(model: Model) -> float:
    """One rounding unit [m] of the largest coordinate of the domain in the kernels' float type."""
    g = model.grid
    largest = max(max(abs(lo), abs(lo + L)) for lo, L in zip(g.lo, g.length))
    return float(np.finfo(np.float32 if model.features.float_bytes == 4 else np.float64).eps) * largest


def quiet_margin(model: Model) -> float:
    """The rounding margin [m] of the quiet partners' reach (`kernels/contact.py`): 1e-4 of the
    skin, plus 16 rounding units of the largest coordinate in the kernels' float type."""
    return QUIET_MARGIN * model.skin + 16 * rounding_unit(model)


def quiet_bounds(model: Model) -> tuple[float, float]:
    """The gaps [m] that group a row's quiet partners (`kernels/broadphase.py`, step 5): half the skin and
    the skin. A contact pass reaches the first group as the grains spend the first half of the skin, the
    second before the next build; the partners beyond, listed for the gas lens only, it evaluates only in
    the steps with conduction (`kernels/pair_contact.py`)."""
    return 0.5 * model.skin, model.skin


def mesh_settings(model: Model) -> tuple[int, int, int, float, float, bool] | None:
    """What the contact kernel needs of the mesh walls (`kernels/mesh_contact.py`): their number, the
    candidate triangles and contact slots per particle, the tolerance [m] within which a closest
    point lies on another triangle (1e-6 of the smallest radius plus 64 rounding units of the largest
    coordinate), how far beyond its radius a particle lists triangles [m] (`mesh_bins.mesh_table`),
    and whether any has a temperature; None without meshes."""
    if not model.features.n_meshes:
        return None
    return (model.features.n_meshes, model.mesh_table.candidates, MESH_SLOTS,
            1e-6 * float(model.radius.min()) + 64 * rounding_unit(model), model.mesh_table.list_reach,
            any(m.temperature is not None for m in model.meshes))


def static_surfaces(model: Model) -> int:
    """Bit s set for each surface (planes, then tubes) that never moves: the contact kernel skips it
    for particles out of its reach at the last neighbour build."""
    still = [not moves(p) for p in model.planes] + [True] * len(model.tubes)
    return sum(1 << s for s, fixed in enumerate(still) if fixed)
