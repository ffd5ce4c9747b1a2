"""The surface a heated mesh shows the gas, per gas cell: the wall area A_w of the gas-tube
convection (`kernels/gas_energy.py`) for a mesh, as `gas.geometry.tube_walls` gives it for a tube.

Each triangle is split into n^2 equal sub-triangles (n from its longest edge, so that they are at
most half a sub-cell of the meshes' gas cut across, `tidem.gas.mesh`), each standing for the area
A / n^2 at its centroid. Each of its two sides is probed one sub-cell width off the surface along
the triangle's normal: a side is wetted when the probe falls in a sub-cell joined to the outlet
through sub-cell links no mesh cuts (`GasCut.wet`), and its area goes to the gas cell
holding that sub-cell. The side of a triangle that faces its own mesh's inside (a closed mesh, or
a tube open at its ends: `inward_sides`) never counts, so a closed body shows the gas its outside
once however thin it is (a plate or fin exported as a solid), and a sheet in the gas (a baffle)
both its sides; a side facing a sealed pocket shows none. A cell the gas step leaves out (its
faces closed by the staircase of the cut) passes on its share: the area in the fluid cells is
scaled up to the whole wetted area (`gas.geometry.convection_walls`), as a tube's is to pi D L.
Along a periodic axis a mesh wraps, unless it spans the whole period, where what it holds beyond
the period is not part of the apparatus (`gas.geometry.spans_period`).
"""

from __future__ import annotations

import numpy as np

from tidem.gas.mesh import GasCut
from tidem.kernels.gas_grid import GasGrid
from tidem.walls.mesh_geometry import inside_mesh

CHUNK = 1_000_000  # sample points handled at once


def centroids(n: int) -> np.ndarray:
    """Barycentric (u, v) [n^2, 2] of the centroids of the n^2 sub-triangles of a triangle split
    n times along each edge."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = (i + j <= n - 1)
    down = (i + j <= n - 2)
    return np.concatenate([np.stack([i[up] + 1 / 3, j[up] + 1 / 3], 1),
                           np.stack([i[down] + 2 / 3, j[down] + 2 / 3], 1)]) / n


def inward_sides(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """[T] per triangle the side (+1 along its normal (b - a) x (c - a), -1 against it) that faces the
    inside of the mesh, 0 where it has none (an open sheet; `mesh_geometry.inside_mesh`, strict): a point
    a hair off its centroid on each side, tested for being inside."""
    tri = vertices[triangles]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.where(length > 0.0, length, 1.0)[:, None]
    hair = 1e-7 * float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    centre = tri.mean(axis=1)
    ahead = inside_mesh(centre + hair * unit, vertices, triangles, strict=True)
    if ahead is None:
        return np.zeros(len(triangles), np.int8)
    behind = inside_mesh(centre - hair * unit, vertices, triangles, strict=True)
    return np.where(ahead & ~behind, 1, np.where(behind & ~ahead, -1, 0)).astype(np.int8)


def _samples(tri: np.ndarray, splits: np.ndarray, keep: np.ndarray):
    """(rows, barycentric uv) blocks of at most about CHUNK sample points: every kept triangle's n^2
    sub-triangle centroids, n = splits of that triangle (a huge triangle's split over several blocks)."""
    for n in np.unique(splits[keep]):
        uv = centroids(int(n))
        rows = np.flatnonzero(keep & (splits == n))
        per = max(CHUNK // len(uv), 1)
        for start in range(0, len(rows), per):
            for u0 in range(0, len(uv), CHUNK):
                yield rows[start:start + per], uv[u0:u0 + CHUNK], len(uv)


def wetted_area(gg: GasGrid, cut: GasCut, tri: np.ndarray, clip: np.ndarray,
                inward: np.ndarray | None = None) -> np.ndarray:
    """[cells] the area [m^2] of the triangles tri [T, 3, 3] that the gas touches, by the cell of its
    gas side (module docstring; cells out of the gas step included); `clip` [T, 3] as
    `gas.geometry.spans_period` gives it; `inward` [T] (`inward_sides`): the side of each triangle that
    faces its mesh's inside, never wetted (0: none)."""
    lo = np.asarray(gg.lo, float)
    sub = np.asarray(gg.h, float) / cut.sub
    fine = np.asarray(gg.cells) * cut.sub
    period = np.asarray(gg.cells) * np.asarray(gg.h)
    inward = np.zeros(len(tri), np.int8) if inward is None else inward
    area = np.zeros(gg.cells)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    normal = np.cross(e1, e2)
    twice = np.linalg.norm(normal, axis=1)
    keep = twice > 0.0
    longest = np.max(np.linalg.norm(np.stack([e1, e2, tri[:, 2] - tri[:, 1]], 1), axis=2), axis=1)
    splits = np.maximum(np.ceil(longest / (0.5 * sub.min())), 1).astype(np.int64)
    for k, uv, count in _samples(tri, splits, keep):
        p = tri[k, None, 0] + uv[None, :, :1] * e1[k, None] + uv[None, :, 1:] * e2[k, None]
        unit = normal[k] / twice[k, None]
        weight = np.broadcast_to((0.5 * twice[k] / count)[:, None], p.shape[:2])
        inside = np.ones(p.shape[:2], bool)
        for a in range(3):
            if gg.periodic[a]:
                inside &= ~clip[k, None, a] | ((p[..., a] >= lo[a]) & (p[..., a] < lo[a] + period[a]))
        for side in (1, -1):
            q = p + side * sub.max() * unit[:, None]
            idx = np.floor((q - lo) / sub).astype(np.int64)
            ok = inside & (inward[k] != side)[:, None]
            for a in range(3):
                if gg.periodic[a]:
                    idx[..., a] %= fine[a]
                else:
                    ok &= (idx[..., a] >= 0) & (idx[..., a] < fine[a])
            i = idx[ok]
            wet = cut.wet[i[:, 0], i[:, 1], i[:, 2]]
            cell = i[wet] // cut.sub
            np.add.at(area, (cell[:, 0], cell[:, 1], cell[:, 2]), weight[ok][wet])
    return area
