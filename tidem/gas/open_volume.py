"""The open volume each gas cell's voidage, each face's drag and each layer's voidage are taken over, beside
tubes and meshes (`kernels/gas_coupling.py`, `kernels/gas_flow.py`).

A grain hands its volume to the cells with its cloud-in-cell weights taken over the cells the gas flows in
(`kernels/gas_weights.py`). Grains packed at solid fraction phi all through the space outside the tubes
and meshes then put phi V_c^open into cell c (and their drag on a face likewise), with

    V_c^open = integral over the open space of w~_c(x) dx,

w~_c(x) the weight a grain at x gives cell c. Taken over this volume, the voidage
eps_c = 1 - sum_p w~_pc V_p / V_c^open is 1 - phi at any wall, however the wall cuts the cells. The
cell's own open share f_c V is not that volume beside a wall:
- a tube's solid cells (their centre inside it) keep part of their volume outside it, 31 of 192 mm^2
  of fluidized_tube's cross-section. The grains there give their volume to the cells beside, which
  then read up to 1.3 times as dense as the bed is (`tests/gas/test_open_volume.py`);
- the cells beside a cut cell take its grains in proportion to the weights, not to its open share.

Away from walls V_c^open = V, which the weights' partition of unity gives exactly; there the integral is
not evaluated. Near walls it is a midpoint sum over points in each cell: 12 a side within reach of a tube
(its round edge sampled at a twelfth of a cell), one per fine sub-cell in the cells beside those a mesh cuts
(12 a side on grids of up to 2300 cells, 8 up to 7800, 4 beyond, `tidem.gas.mesh.refinement`), 4 elsewhere.
A point is open outside the tubes and in a fine sub-cell the gas reaches past the meshes
(`tidem.gas.mesh.GasCut.fine_wet`). That counts the part of a mesh's sealed cells outside it, as the ring of
a tube's solid cells outside the tube is counted: grains lie there, and their weights hand them to the cells
beside.
"""

from __future__ import annotations

import numpy as np

from tidem.gas.geometry import shifted
from tidem.gas.grid_graph import bordering
from tidem.gas.mesh import MIN_OPEN, GasCut, cell_index, sub_grid
from tidem.kernels.gas_grid import CLOSED, GasGrid, layer_grid

SUB_TUBE = 12  # points per cell along its longest side within reach of a tube (its round edge sampled)
SUB_WALL = 4  # elsewhere (a mesh's open share is even across a cell); both even: the kinks fall between points
CHUNK = 1 << 18  # points per numpy pass


def open_volumes(gg: GasGrid, solid: np.ndarray, kinds: list[np.ndarray], tubes: list[dict], cut: GasCut | None,
                 layers: int = 1) -> dict[str, np.ndarray] | None:
    """V^open / V (module docstring) of each lattice point the gas's exchange with the grains uses: "cells"
    (the voidage), "faces0".."faces2" (the drag on the faces normal to x, y, z) and with `layers` > 1
    "layers" (the layered voidage, `gas_grid.layer_grid`). At least MIN_OPEN at points the gas flows in,
    1 at the others; None without tubes and meshes (the plain weights then, and the whole volume)."""
    if not tubes and cut is None:
        return None
    solid = solid.astype(bool)
    share = None if cut is None else np.where(cut.unreachable.astype(bool), 0.0, cut.open_fraction)
    near = grow(gg, solid | (cut_share(gg, tubes, share) < 1.0), 1)  # gas cells with a wall within one cell
    mesh = None if cut is None else (cut.open_sub_cells(solid), grow(gg, cut.mixed_cells(), 1), cut.fine)
    out = {"cells": lattice_open_volume(gg, gg, solid, near, tubes, mesh)}
    for c in range(3):
        lattice = face_lattice(gg, c)
        out[f"faces{c}"] = lattice_open_volume(gg, lattice, ~face_in_gas(gg, kinds[c], solid, c), near, tubes, mesh)
    if layers > 1:
        out["layers"] = lattice_open_volume(gg, layer_grid(gg, layers), np.repeat(solid, layers, axis=2), near,
                                            tubes, mesh)
    return out


def lattice_open_volume(gg: GasGrid, lattice: GasGrid, out_of_gas: np.ndarray, near: np.ndarray,
                        tubes: list[dict], mesh: tuple[np.ndarray, np.ndarray, int] | None) -> np.ndarray:
    """V^open / V of the points of `lattice` (cells, faces or layers; `out_of_gas` there), evaluated where a
    point lies within two of a point out of the gas or of a gas cell `near` a wall, 1 elsewhere. `mesh`: (the
    fine sub-cells open past the meshes, the gas cells beside those the meshes cut, fine sub-cells per cell)."""
    centres = np.asarray(lattice.lo) + (np.indices(lattice.cells).reshape(3, -1).T + 0.5) * np.asarray(lattice.h)
    cell_of = tuple(gas_cell(gg, centres).T)
    special = out_of_gas | near[cell_of].reshape(lattice.cells)
    sampled, kept = grow(lattice, special, 3), grow(lattice, special, 2)
    by_tube = near_tubes(lattice, tubes)
    open_sub, fine = (None, SUB_WALL) if mesh is None else (mesh[0], mesh[2])
    by_mesh = np.zeros(lattice.cells, bool) if mesh is None else mesh[1][cell_of].reshape(lattice.cells) & ~by_tube
    parts = ((by_tube, SUB_TUBE), (by_mesh, max(fine, SUB_WALL)), (~by_tube & ~by_mesh, SUB_WALL))
    total = sum(masked_integral(gg, lattice, out_of_gas, tubes, open_sub, np.argwhere(sampled & part), sub)
                for part, sub in parts if (sampled & part).any())
    fraction = np.ones(lattice.cells)
    fraction[kept] = total[kept]
    return np.where(out_of_gas, 1.0, np.maximum(fraction, MIN_OPEN))


def face_lattice(gg: GasGrid, c: int) -> GasGrid:
    """The faces normal to axis c as a lattice of their own (`kernels/gas_grid.make_cic`'s stagger c)."""
    lo = list(gg.lo)
    lo[c] -= 0.5 * gg.h[c]
    return GasGrid(tuple(lo), gg.face_shape(c), gg.h, gg.periodic)


def face_in_gas(gg: GasGrid, kind: np.ndarray, solid: np.ndarray, c: int) -> np.ndarray:
    """The faces normal to c the gas's weights use (`kernels/gas_weights.make_in_gas`): not closed, or closed
    but bounding a cell of the gas (a wall's face, normal velocity 0)."""
    return (kind != CLOSED) | bordering(~solid.astype(bool), c, gg.periodic[c])


def gas_cell(gg: GasGrid, x: np.ndarray) -> np.ndarray:
    """[N, 3] index of the gas cell holding each point x [N, 3] (clamped into the grid)."""
    idx = np.floor((x - np.asarray(gg.lo)) / np.asarray(gg.h)).astype(int)
    return np.clip(idx, 0, np.asarray(gg.cells) - 1)


def cut_share(gg: GasGrid, tubes: list[dict], mesh: np.ndarray | None) -> np.ndarray:
    """Each cell's share outside the tubes, times `mesh` (a mesh's open share of each cell, 0 where the gas
    cannot reach; None without meshes)."""
    share = np.ones(gg.cells)
    near = np.argwhere(near_tubes(gg, tubes))
    if len(near):
        points = cell_points(gg, near).reshape(-1, 3)
        share[tuple(near.T)] = open_at(gg, tubes, None, points).reshape(len(near), -1).mean(axis=1)
    return share if mesh is None else share * mesh


def near_tubes(gg: GasGrid, tubes: list[dict]) -> np.ndarray:
    """Cells a tube may reach into: the axis within its radius plus a cell's diagonal of the centre."""
    idx = np.indices(gg.cells).reshape(3, -1).T
    centres = np.asarray(gg.lo) + (idx + 0.5) * np.asarray(gg.h)
    near = np.zeros(len(idx), bool)
    for t in tubes:
        d = (centres - np.asarray(t["c"])) * np.asarray(t["mask"])
        near |= np.einsum("ij,ij->i", d, d) < (t["r"] + float(np.linalg.norm(gg.h))) ** 2
    return near.reshape(gg.cells)


def grow(gg: GasGrid, mask: np.ndarray, by: int) -> np.ndarray:
    """Cells within `by` cells (per axis) of a cell of `mask`, wrapping across periodic axes."""
    out = mask.copy()
    for _ in range(by):
        for a in range(3):
            out = out | shifted(gg, out, a, 1) | shifted(gg, out, a, -1)
    return out


def cell_points(gg: GasGrid, cells: np.ndarray, sub: int = SUB_TUBE) -> np.ndarray:
    """[len(cells), points, 3] midpoints of equal sub-cells of each cell, `sub` along its longest side and an
    even number at least as dense along the others."""
    h = np.asarray(gg.h)
    counts = [max(2, 2 * int(np.ceil(sub / 2 * h[a] / h.max() - 1e-9))) for a in range(3)]
    offsets = [(np.arange(c) + 0.5) / c for c in counts]
    sub = np.stack(np.meshgrid(*offsets, indexing="ij"), axis=-1).reshape(-1, 3)
    return np.asarray(gg.lo) + (cells[:, None, :] + sub[None, :, :]) * h


def open_at(gg: GasGrid, tubes: list[dict], mesh: np.ndarray | None, x: np.ndarray) -> np.ndarray:
    """Whether points x [N, 3] are open (1.0) or not (0.0): outside every tube and, with meshes, in a sub-cell
    of `mesh` (bool, s sub-cells per cell and axis: those the gas reaches) that is True."""
    open_ = np.ones(len(x))
    for t in tubes:
        d = (x - np.asarray(t["c"])) * np.asarray(t["mask"])
        open_[np.einsum("ij,ij->i", d, d) < t["r"] ** 2] = 0.0
    if mesh is not None:
        open_ *= mesh[tuple(cell_index(sub_grid(gg, mesh.shape[0] // gg.cells[0]), x).T)]
    return open_


def masked_integral(gg: GasGrid, lattice: GasGrid, out_of_gas: np.ndarray, tubes: list[dict],
                    mesh: np.ndarray | None, cells: np.ndarray, sub: int) -> np.ndarray:
    """Sum over `sub` points a side of each of the lattice's `cells` of w~_c(x) open(x) / points into each
    lattice point c: V_c^open / V for every point all of whose neighbours are among `cells`. w~ are `kernels/gas_weights.py`'s
    weights over the points the gas flows in, on `kernels/gas_grid.make_cic`'s lattice (clamped at the box,
    wrapped where periodic)."""
    n = np.asarray(lattice.cells)
    lo, h = np.asarray(lattice.lo), np.asarray(lattice.h)
    per = np.asarray(lattice.periodic)
    total = np.zeros(int(np.prod(n)))
    corners = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T
    points = cell_points(lattice, cells[:1], sub).shape[1]
    x_all = cell_points(lattice, cells, sub).reshape(-1, 3)
    for start in range(0, len(x_all), CHUNK):
        x = x_all[start:start + CHUNK]
        value = open_at(gg, tubes, mesh, x) / points
        x, value = x[value > 0.0], value[value > 0.0]  # points in a tube or sealed off add nothing
        g = (x - lo) / h - 0.5
        base = np.floor(g).astype(int)
        frac = g - base
        idx = base[:, None, :] + corners[None, :, :]
        idx = np.where(per, idx % n, np.clip(idx, 0, n - 1))
        w = np.prod(np.where(corners[None, :, :] == 1, frac[:, None, :], 1.0 - frac[:, None, :]), axis=2)
        flat = np.ravel_multi_index(tuple(np.moveaxis(idx, 2, 0)), tuple(n))
        in_gas = ~out_of_gas.reshape(-1)[flat]
        inside = (w * in_gas).sum(axis=1)
        masked = (~in_gas).any(axis=1) & (inside > 0.0)
        w = np.where(masked[:, None], w * in_gas / np.where(masked, inside, 1.0)[:, None], w)
        total += np.bincount(flat.reshape(-1), (w * value[:, None]).reshape(-1), minlength=len(total))
    return total.reshape(lattice.cells)
