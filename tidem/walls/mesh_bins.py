"""Mesh triangles as the contact kernels hold them, and their binning into the neighbour grid.

`triangle_table` lays the triangles of all meshes out in one table (rest vertices, mesh index)
and adds, for each periodic axis, shifted copies of the triangles within `reach` of either end of
the period, so that a mesh crossing a periodic boundary (a slice of a drum) continues seamlessly
there (`kernels/mesh_contact.py`). `bin_triangles` lists, for each cell of the neighbour grid,
the triangles that come within `inflate` of the cell (CSR: start [cells + 1], triangle ids): a
triangle's box grown by `inflate`, kept only in the cells its plane passes within `inflate` plus
half a cell diagonal of. The neighbour build then tests only the triangles of a particle's cell.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tidem.walls.mesh_geometry import flat_patches

MIN_CANDIDATES, MAX_CANDIDATES = 16, 128  # triangles listed per particle at a neighbour build (`candidate_slots`)
MESH_SLOTS = 4  # mesh contacts a particle can hold at once, each with its history


@dataclass
class MeshTable:
    """The triangles of all meshes as the kernels hold them, and their bins at t = 0."""

    rest: np.ndarray  # [T, 3, 3] vertices at t = 0, before the image shift [m]
    shift: np.ndarray  # [T, 3] periodic image offset [m]
    mesh_id: np.ndarray  # [T] int32
    patch: np.ndarray  # [T] int32, flat patch of each triangle (`mesh_geometry.flat_patches`); -1: a periodic image
    start: np.ndarray  # [cells + 1] int32, CSR starts of the bins
    tri: np.ndarray  # [entries] int32, triangle ids by cell
    inflate: float  # how far from a cell its triangles are listed [m], the moving meshes' `margin` included
    margin: float  # how far a moving mesh may move before it is binned anew [m] (0: none moves)
    bin_capacity: int  # room for the bins of a moving mesh, rebinned as it moves
    candidates: int  # triangles a particle can list (`candidate_slots`)
    list_reach: float  # how far beyond its radius a particle lists triangles [m] (`mesh_table`)

    def at(self, meshes, t: float) -> np.ndarray:
        """The triangles [T, 3, 3] at time t, image shifts included."""
        out = self.rest + self.shift[:, None, :]
        for k, m in enumerate(meshes):
            if m.moving:
                pick = self.mesh_id == k
                out[pick] = m.points_at(t, self.rest[pick]) + self.shift[pick][:, None, :]
        return out


def mesh_table(meshes, grid, radius: float, skin: float, lens: float, margin: float) -> MeshTable:
    """Triangles with their periodic images (within reach of a periodic end) and their bins, listed
    within reach + `margin` of each cell where a mesh moves (it is binned anew only after moving that
    far, `tidem.sim.solver`). A particle lists the triangles within its radius plus `list_reach` of its
    centre at each neighbour build: half the `skin` plus the gas `lens` where no mesh moves (a
    particle moves at most half the skin between two builds), the whole skin plus the lens where one
    does (the mesh moves up to half the skin too); reach = the largest `radius` plus that."""
    moving = any(m.moving for m in meshes)
    margin = margin if moving else 0.0
    list_reach = (skin if moving else 0.5 * skin) + lens
    reach = radius + list_reach
    rest, shift, mesh_id, patch = triangle_table(meshes, grid, reach + margin)
    start, tri = bin_triangles(rest + shift[:, None, :], grid, reach + margin)
    capacity = max(2 * len(tri), len(tri) + 4096) if moving else max(len(tri), 1)
    return MeshTable(rest, shift, mesh_id, patch, start, tri, reach + margin, margin, capacity, candidate_slots(rest, reach),
                     list_reach)


def candidate_slots(tri: np.ndarray, reach: float) -> int:
    """Room for the triangles within `reach` of a particle's centre: 1.5 times as many as a disc of
    radius reach plus a triangle's size holds of the finer triangles (the 10th percentile of their
    areas), between MIN_CANDIDATES and MAX_CANDIDATES (a particle with more counts in overflow[3])."""
    if not len(tri):
        return MIN_CANDIDATES
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    fine = float(np.percentile(area, 10))
    need = 1.5 * np.pi * (reach + np.sqrt(2.0 * fine)) ** 2 / fine
    return int(min(max(np.ceil(need), MIN_CANDIDATES), MAX_CANDIDATES))


def triangle_table(meshes, grid, reach: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(rest vertices [T, 3, 3] at t = 0 without the image shift, image shift [T, 3], mesh index [T],
    flat patch [T]) of every mesh's triangles, periodic images included (module docstring; an image
    is a patch of none, -1). A mesh that spans a whole period (a drum's slice drawn from one end of
    the period to the other) needs none along that axis: the particles' centres lie within the
    period, so their nearest points do too."""
    rest = [m.vertices[m.triangles] for m in meshes]
    ids = [np.full(len(m.triangles), k, np.int32) for k, m in enumerate(meshes)]
    first = np.cumsum([0] + [len(m.triangles) for m in meshes])
    patches = [first[k] + flat_patches(m.vertices, m.triangles) for k, m in enumerate(meshes)]
    verts = np.concatenate(rest) if rest else np.zeros((0, 3, 3))
    mesh_id = np.concatenate(ids) if ids else np.zeros(0, np.int32)
    originals = len(verts)
    shift = np.zeros((len(verts), 3))
    for a in range(3):
        if not grid.periodic[a]:
            continue
        lo, L = grid.lo[a], grid.length[a]
        spans = np.array([m.spans(a, lo, L) for m in meshes] + [False])
        moved = verts + shift[:, None, :]
        low, high = moved[:, :, a].min(axis=1), moved[:, :, a].max(axis=1)
        needed = ~spans[mesh_id]
        up = needed & (low < lo + reach)  # near the lower end: a copy one period up serves the upper end
        down = needed & (high > lo + L - reach)
        parts = [(verts, shift, mesh_id)]
        for pick, sign in ((up, 1.0), (down, -1.0)):
            s = shift[pick].copy()
            s[:, a] += sign * L
            parts.append((verts[pick], s, mesh_id[pick]))
        verts = np.concatenate([p[0] for p in parts])
        shift = np.concatenate([p[1] for p in parts])
        mesh_id = np.concatenate([p[2] for p in parts])
    patch = np.full(len(verts), -1, np.int32)
    patch[:originals] = np.concatenate(patches) if patches else []
    return verts, shift, mesh_id.astype(np.int32), patch


def bin_triangles(tri: np.ndarray, grid, inflate: float) -> tuple[np.ndarray, np.ndarray]:
    """CSR lists of the triangles [T, 3, 3] near each cell of `grid` (module docstring):
    start [n_cells + 1] int32, triangle indices int32."""
    cells = np.array(grid.cells)
    size = np.array(grid.cell_size)
    lo = np.array(grid.lo)
    if len(tri) == 0:
        return np.zeros(grid.n_cells + 1, np.int32), np.zeros(1, np.int32)
    c_lo = np.clip(np.floor((tri.min(axis=1) - inflate - lo) / size).astype(np.int64), 0, cells - 1)
    c_hi = np.clip(np.floor((tri.max(axis=1) + inflate - lo) / size).astype(np.int64), 0, cells - 1)
    span = c_hi - c_lo + 1
    count = span.prod(axis=1)
    owner = np.repeat(np.arange(len(tri)), count)
    local = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
    sy, sz = span[owner, 1], span[owner, 2]
    cx = c_lo[owner, 0] + local // (sy * sz)
    cy = c_lo[owner, 1] + (local // sz) % sy
    cz = c_lo[owner, 2] + local % sz
    centre = lo + (np.stack([cx, cy, cz], axis=1) + 0.5) * size
    a, b, c = tri[owner, 0], tri[owner, 1], tri[owner, 2]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    keep = np.abs(np.einsum("ij,ij->i", centre - a, normal)) <= inflate + 0.5 * np.linalg.norm(size)
    cell = ((cx * cells[1] + cy) * cells[2] + cz)[keep]
    owner = owner[keep]
    order = np.argsort(cell, kind="stable")
    start = np.zeros(grid.n_cells + 1, np.int64)
    np.add.at(start, cell + 1, 1)
    return np.cumsum(start).astype(np.int32), owner[order].astype(np.int32)


def mesh_field_bytes(model) -> int:
    """Bytes of the mesh fields of `tidem.sim.state` (0 without meshes): per particle the candidate list
    and the contact slots with their history, the triangles (and their rest positions where a mesh
    moves), the bins and the meshes' motion."""
    f, tab = model.features, model.mesh_table
    if not f.n_meshes or tab is None:
        return 0
    fb = f.float_bytes
    slot = 4 + 6 * fb + (3 * fb if f.rolling else 0) + (fb if f.hysteretic else 0)
    per_particle = 8 + 4 * tab.candidates + MESH_SLOTS * slot
    tri = len(tab.mesh_id) * (9 * fb + 8 + (12 * fb if f.moving_meshes else 0))
    bins = 4 * (model.grid.n_cells + 1) + 4 * tab.bin_capacity
    return per_particle * model.capacity + tri + bins + 12 * fb * len(model.meshes)
