"""Tubes cut into the gas grid (`gas.tube_shape = "cut"`, plain numpy at set-up): each tube is drawn as a
prism of TUBE_FACETS faces along its axis and handed to the meshes' cut-cell representation
(`tidem.gas.mesh`, `tidem.gas.apertures`), so that the gas sees the tube's own section on any grid: cells it
cuts hold their gas part, the faces it cuts their open share, and only cells it (nearly) fills drop out of
the solve. With `"cells"` (the staircase) a tube is the cells whose centre lies in it
(`tidem.gas.geometry.tube_cells`), which blocks between 0.56 (the coarse-graining slab's 5 mm cells) and 1.09
(fluidized_tube's 4 mm cells) of a 15 mm tube's section, depending on where the grid's lines fall.

The prism's corners lie on a circle of radius r sqrt(2 pi / (N sin(2 pi / N))), N = TUBE_FACETS, so that its
section has the tube's area pi r^2. It spans the domain along the tube's axis; a tube has no end caps: along
a periodic axis it spans the period (and is clipped to it, as a mesh spanning the period is), along a closed
one the box's side walls close it. Its wetted surface (`tidem.gas.mesh_convection.wetted_area`) is the
gas-tube convection's area, scaled to pi D L over the cells of the gas (`tube_cut_walls`).
"""

from __future__ import annotations

import numpy as np

from tidem.gas.mesh import GasCut
from tidem.gas.mesh_convection import wetted_area
from tidem.kernels.gas_grid import GasGrid

TUBE_FACETS = 64  # faces of the prism drawn for a tube: 0.74 mm each on a 15 mm tube


def tube_axis(tube: dict) -> int:
    """The axis a tube runs along (its mask is 0 there)."""
    return int(np.flatnonzero(np.asarray(tube["mask"]) == 0.0)[0])


def tube_triangles(gg: GasGrid, tube: dict) -> tuple[np.ndarray, np.ndarray]:
    """(triangles [2 N, 3, 3], clip [2 N, 3]): the tube's prism over the domain along its axis (module docstring)
    and, per triangle and axis, whether it is clipped to the period there (`gas.geometry.spans_period`)."""
    a = tube_axis(tube)
    u, v = [k for k in range(3) if k != a]
    n = TUBE_FACETS
    radius = tube["r"] * np.sqrt(2.0 * np.pi / (n * np.sin(2.0 * np.pi / n)))
    phi = 2.0 * np.pi * np.arange(n) / n
    ring = np.zeros((n, 3))
    ring[:, u] = tube["c"][u] + radius * np.cos(phi)
    ring[:, v] = tube["c"][v] + radius * np.sin(phi)
    lo, hi = ring.copy(), ring.copy()
    lo[:, a] = gg.lo[a]
    hi[:, a] = gg.lo[a] + gg.cells[a] * gg.h[a]
    nxt = np.roll(np.arange(n), -1)
    tri = np.concatenate([np.stack([lo, lo[nxt], hi[nxt]], 1), np.stack([lo, hi[nxt], hi], 1)])
    clip = np.zeros((len(tri), 3), bool)
    clip[:, a] = gg.periodic[a]
    return tri, clip


def tubes_triangles(gg: GasGrid, tubes: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """`tube_triangles` of every tube, in order (empty arrays without tubes)."""
    parts = [tube_triangles(gg, t) for t in tubes]
    if not parts:
        return np.zeros((0, 3, 3)), np.zeros((0, 3), bool)
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


def tube_cut_walls(gg: GasGrid, tubes: list[dict], cut: GasCut) -> dict[str, np.ndarray] | None:
    """`gas.geometry.tube_walls` for cut tubes: per cell the wetted surface of a heated tube (wall_A [m^2],
    scaled so that each tube's cells of the gas add up to pi D L), wall_T [K], wall_D [m], wall_k (tube index);
    a cell two tubes wet is the first's. None without a heated tube."""
    area = np.zeros(gg.cells)
    out = {"wall_T": np.zeros(gg.cells), "wall_D": np.ones(gg.cells), "wall_k": np.zeros(gg.cells, np.int32)}
    for k, t in enumerate(tubes):
        if t["T"] is None:
            continue
        tri, clip = tube_triangles(gg, t)
        wet = wetted_area(gg, cut, tri, clip)
        mine = (wet > 0.0) & ~cut.unreachable & (area == 0.0)
        if not mine.any():
            continue
        a = tube_axis(t)
        true_area = 2.0 * np.pi * t["r"] * gg.cells[a] * gg.h[a]
        area[mine] = wet[mine] * true_area / wet[mine].sum()
        out["wall_T"][mine], out["wall_D"][mine], out["wall_k"][mine] = t["T"], 2.0 * t["r"], k
    if not area.any():
        return None
    out["wall_A"] = area
    return out
