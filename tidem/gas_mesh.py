"""Mesh walls in the gas grid (scenes with `[[meshes]]` and `[gas]`, plain numpy at set-up): the
cell faces a mesh blocks, the cells the gas cannot reach, and the open volume of the cells a mesh
cuts (a first-order, "staircase" representation of the walls: the gas grid is not refined
along them).

Each gas cell is divided into s x s x s sub-cells (`subdivision`). Rays along each axis through
the sub-cells' centres are cut where they pierce a triangle (a triangle parallel to an axis is
found by the rays along the other two, so a sheet of any orientation is seen). Then
- a face between two cells is blocked (CLOSED for the gas) when at least half of the s^2 rays
  between the two cell centres cross a mesh; an inlet (bottom) or outlet (top) face likewise
  over the rays between the face and its cell's centre;
- a cell is solid for the gas, and drops out of the solve, where no path of open faces joins it
  to an open outlet face (a pocket sealed off by a sheet, even one the inlet feeds: gas could
  not leave it), or where less than half of its sub-cells are joined to an open outlet through
  sub-cell links no mesh cuts (a cell mostly inside a closed body, as a cell whose centre lies in
  a tube is solid; a round tube a few cells across also leaves gaps in the staircase of
  half-blocked faces); its inlet faces close;
- a cell's open fraction is the share of its sub-cells that a path of uncut sub-cell links
  joins to an open outlet; the voidage of a cut cell is taken over that open volume,
  eps = 1 - V_particles / (f V) (`kernels/gas_coupling.py`), with f at least MIN_OPEN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tidem.kernels.gas_grid import CLOSED, OUTLET, GasGrid

MIN_OPEN = 0.2  # smallest open fraction a reachable cell is given (a sliver cell's voidage stays bounded)
MAX_SUBCELLS = 4_000_000  # sub-cells of the whole grid at most: s = 4, else 2, else 1
BLOCKED_SHARE = 0.5  # share of a face's rays a mesh must cut to block it, and of a cell's volume a body must hold to fill it


@dataclass
class GasCut:
    """What the meshes do to the gas grid."""

    blocked: list[np.ndarray]  # per face component: bool [face_shape(c)], blocked by a mesh
    unreachable: np.ndarray  # bool [cells]: no open path to the outlet
    open_fraction: np.ndarray  # [cells] share of the cell the gas fills (1 where uncut)
    sub: int  # sub-cells per cell and axis
    wet: np.ndarray  # bool [cells x sub per axis]: sub-cells joined to the outlet by uncut links

    def open_sub_cells(self, solid: np.ndarray) -> np.ndarray:
        """bool [cells x sub per axis]: the sub-cells open past the meshes, those the gas reaches (`wet`) and all
        of a cell `solid` for another reason than the meshes (a tube's: its own test is analytic)."""
        return self.wet | _fine(solid.astype(bool) & ~self.unreachable.astype(bool), self.sub)

    def report_lines(self) -> list[str]:
        cut = (self.open_fraction < 1.0) & ~self.unreachable
        faces = sum(int(b.sum()) for b in self.blocked)
        cells = (f"{int(cut.sum())} cut cells (open fraction {self.open_fraction[cut].min():.2f}-"
                 f"{self.open_fraction[cut].max():.2f}, {self.sub}^3 sub-cells per cell)" if cut.any() else "no cut cells")
        return [f"gas grid: {faces} faces blocked by meshes, {int(self.unreachable.sum())} cells the gas cannot "
                f"reach (solid), {cells}"]


def subdivision(gg: GasGrid) -> int:
    cells = int(np.prod(gg.cells))
    return next(s for s in (4, 2, 1) if cells * s**3 <= MAX_SUBCELLS or s == 1)


def ray_crossings(gg: GasGrid, tri: np.ndarray, c: int, s: int,
                  clip: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Where rays along axis c through the sub-cell centres pierce the triangles tri [T, 3, 3]:
    (ia, ib, t, clip_c), the ray's sub-cell indices on the two other axes (wrapped on periodic
    axes), the coordinate along c [m] of each crossing, and whether it is to be clipped to the
    period along c rather than wrapped. `clip` [T, 3]: per triangle and periodic axis, whether its
    mesh spans the whole period there (`gas_walls`), so that what lies beyond the period is not part
    of the apparatus (as for the particles, `mesh_bins.triangle_table`). A ray through an edge or
    vertex counts for every triangle that holds it (a closed mesh has no gaps)."""
    if clip is None:
        clip = np.zeros((len(tri), 3), bool)
    a, b = [k for k in range(3) if k != c]
    ha, hb = gg.h[a] / s, gg.h[b] / s
    na, nb = gg.cells[a] * s, gg.cells[b] * s
    pa = (tri[:, :, a] - gg.lo[a]) / ha - 0.5  # vertices in sub-cell index units
    pb = (tri[:, :, b] - gg.lo[b]) / hb - 0.5
    area2 = (pa[:, 1] - pa[:, 0]) * (pb[:, 2] - pb[:, 0]) - (pa[:, 2] - pa[:, 0]) * (pb[:, 1] - pb[:, 0])
    keep = np.abs(area2) > 1e-12  # parallel to the axis: no ray pierces it
    tri, pa, pb, area2, clip = tri[keep], pa[keep], pb[keep], area2[keep], clip[keep]
    i0, i1 = np.ceil(pa.min(1) - 1e-9).astype(np.int64), np.floor(pa.max(1) + 1e-9).astype(np.int64)
    j0, j1 = np.ceil(pb.min(1) - 1e-9).astype(np.int64), np.floor(pb.max(1) + 1e-9).astype(np.int64)
    if not gg.periodic[a]:
        i0, i1 = np.maximum(i0, 0), np.minimum(i1, na - 1)
    if not gg.periodic[b]:
        j0, j1 = np.maximum(j0, 0), np.minimum(j1, nb - 1)
    wa, wb = np.maximum(i1 - i0 + 1, 0), np.maximum(j1 - j0 + 1, 0)
    count = wa * wb
    k = np.repeat(np.arange(len(count)), count)  # one row per (triangle, ray in its bounding box)
    local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    ia = i0[k] + local // np.maximum(wb[k], 1)
    ib = j0[k] + local % np.maximum(wb[k], 1)
    # barycentric coordinates of the ray in the projected triangle
    qa, qb = ia - pa[k, 0], ib - pb[k, 0]
    ea1, eb1, ea2, eb2 = pa[k, 1] - pa[k, 0], pb[k, 1] - pb[k, 0], pa[k, 2] - pa[k, 0], pb[k, 2] - pb[k, 0]
    u = (qa * eb2 - qb * ea2) / area2[k]
    v = (ea1 * qb - eb1 * qa) / area2[k]
    tol = 1e-9
    hit = (u >= -tol) & (v >= -tol) & (u + v <= 1.0 + tol)
    hit &= ~clip[k, a] | ((ia >= 0) & (ia < na))
    hit &= ~clip[k, b] | ((ib >= 0) & (ib < nb))
    k, ia, ib, u, v = k[hit], ia[hit], ib[hit], u[hit], v[hit]
    t = tri[k, 0, c] + u * (tri[k, 1, c] - tri[k, 0, c]) + v * (tri[k, 2, c] - tri[k, 0, c])
    return ia % na, ib % nb, t, clip[k, c]


def _links(gg: GasGrid, c: int, t: np.ndarray, clip: np.ndarray, spacing: float,
           n: int) -> tuple[np.ndarray, np.ndarray]:
    """Index of the link (between consecutive centres of spacing `spacing`, n of them along c)
    that each crossing t lies on, with whether it lies inside the domain (on a periodic axis: or
    is wrapped into it, unless `clip`). Open axis: link j + 1 joins centres j and j + 1, link 0 the
    low boundary to centre 0, link n centre n - 1 to the high boundary; periodic axis: link j joins
    centres j and j + 1 (mod n)."""
    x = (t - gg.lo[c]) / spacing - 0.5
    if gg.periodic[c]:
        return np.floor(x).astype(np.int64) % n, ~clip | ((x >= -0.5) & (x < n - 0.5))
    inside = (x >= -0.5) & (x <= n - 0.5)
    return np.clip(np.floor(x).astype(np.int64) + 1, 0, n), inside


def cut_links(gg: GasGrid, tri: np.ndarray, s: int, clip: np.ndarray | None) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per axis c: the sub-cell links a mesh cuts (bool, shape of the sub-grid with n_c s + 1
    links along an open c, n_c s periodic, numbered as `_links` does) and the cell-centre-to-centre
    rays it cuts (bool, numbered as the faces are, `gas_grid.GasGrid.face_shape`, sub-cells across)."""
    sub_cut, face_cut = [], []
    for c in range(3):
        a, b = [k for k in range(3) if k != c]
        ia, ib, t, clip_c = ray_crossings(gg, tri, c, s, clip)
        nf = gg.cells[c] * s
        shape = [gg.cells[k] * s for k in range(3)]
        fine = np.zeros([nf if (k == c and gg.periodic[c]) else (nf + 1 if k == c else shape[k]) for k in range(3)],
                        bool)
        coarse = np.zeros([gg.face_shape(c)[c] if k == c else shape[k] for k in range(3)], bool)
        for arr, spacing, n in ((fine, gg.h[c] / s, nf), (coarse, gg.h[c], gg.cells[c])):
            link, inside = _links(gg, c, t, clip_c, spacing, n)
            if arr is coarse and gg.periodic[c]:
                link = (link + 1) % n  # as the faces count: face j between cells j - 1 and j
            idx = [None, None, None]
            idx[c], idx[a], idx[b] = link[inside], ia[inside], ib[inside]
            arr[tuple(idx)] = True
        sub_cut.append(fine)
        face_cut.append(coarse)
    return sub_cut, face_cut


def components(n: int, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """Connected-component label (the smallest member) of each of n nodes joined by the edges
    (ea, eb): hooking of roots and full pointer jumping, a few numpy passes."""
    label = np.arange(n)
    while True:
        la, lb = label[ea], label[eb]
        lo, hi = np.minimum(la, lb), np.maximum(la, lb)
        join = lo != hi
        if not join.any():
            return label
        np.minimum.at(label, hi[join], lo[join])  # hi is a root: every label is one after jumping
        while True:
            nxt = label[label]
            if np.array_equal(nxt, label):
                break
            label = nxt


def reached(shape, open_links: list[np.ndarray], periodic, seeds: np.ndarray, skip: np.ndarray) -> np.ndarray:
    """Cells of a grid `shape` joined to a seed cell through open links (per axis c, bool over the
    links between consecutive cells: shape[c] - 1 of them, shape[c] on a periodic axis), never
    through a `skip` cell."""
    ids = np.arange(int(np.prod(shape))).reshape(shape)
    ea, eb = [], []
    for c in range(3):
        n = shape[c]
        lo = np.take(ids, range(n if periodic[c] else n - 1), axis=c)
        hi = np.take(ids, [(j + 1) % n for j in range(n if periodic[c] else n - 1)], axis=c)
        ok = open_links[c] & ~skip.flat[lo] & ~skip.flat[hi]
        ea.append(lo[ok])
        eb.append(hi[ok])
    label = components(ids.size, np.concatenate(ea), np.concatenate(eb))
    hit = np.zeros(ids.size, bool)
    hit[np.unique(label[seeds.ravel() & ~skip.ravel()])] = True
    return hit[label].reshape(shape)


def interior_links(links: np.ndarray, c: int, periodic: bool) -> np.ndarray:
    """The links between cells from an array that also holds the two boundary links (open axis)."""
    return links if periodic else np.take(links, range(1, links.shape[c] - 1), axis=c)




def gas_cut(gg: GasGrid, triangles: np.ndarray, solid: np.ndarray, kinds: list[np.ndarray],
            clip: np.ndarray | None = None) -> GasCut:
    """Cut the gas grid with the triangles [T, 3, 3] (scene coordinates, all meshes); `solid` the
    cells already solid (tubes) and `kinds` their face kinds (`gas_geometry.face_kinds`); `clip`
    [T, 3] as `ray_crossings` takes it (None: every mesh wraps across periodic boundaries)."""
    s = subdivision(gg)
    sub_cut, face_cut = cut_links(gg, np.asarray(triangles, float), s, clip)
    blocked = []
    for c in range(3):
        split = []  # the face array with each cross axis split into (cells, sub-cells)
        for k in range(3):
            split += [face_cut[c].shape[k]] if k == c else [gg.cells[k], s]
        share = face_cut[c].reshape(split).mean(axis=_sub_axes(c))
        blocked.append((share >= BLOCKED_SHARE) & (kinds[c] != CLOSED))
    kinds = [np.where(bl, CLOSED, kd) for bl, kd in zip(blocked, kinds)]
    # faces as links between consecutive cells (`reached`): on a periodic axis link j is face j + 1
    open_faces = [np.roll(kinds[c] != CLOSED, -1, axis=c) if gg.periodic[c]
                  else interior_links(kinds[c] != CLOSED, c, False) for c in range(3)]
    fine_shape = tuple(n * s for n in gg.cells)
    fine_open = [interior_links(~sub_cut[c], c, gg.periodic[c]) for c in range(3)]
    fine_seeds = np.zeros(fine_shape, bool)
    fine_seeds[:, :, -1] = np.repeat(np.repeat(kinds[2][:, :, -1] == OUTLET, s, 0), s, 1) & ~sub_cut[2][:, :, -1]
    # the sub-cells the gas reaches through links no mesh cuts, whatever their cell: a cell with less than
    # half of them is mostly inside a body, even where the staircase of half-blocked faces leaves it a way out
    wet = reached(fine_shape, fine_open, gg.periodic, fine_seeds, _fine(solid.astype(bool), s))
    dry = _coarse(wet, gg.cells, s).mean(axis=(1, 3, 5)) < BLOCKED_SHARE
    seeds = np.zeros(gg.cells, bool)
    seeds[:, :, -1] = kinds[2][:, :, -1] == OUTLET
    reach = reached(gg.cells, open_faces, gg.periodic, seeds, solid.astype(bool) | dry)
    unreachable = ~reach & ~solid.astype(bool)
    # sub-cells: the open fraction of each cell
    fine_reach = reached(fine_shape, fine_open, gg.periodic, fine_seeds, _fine(~reach, s))
    frac = _coarse(fine_reach, gg.cells, s).mean(axis=(1, 3, 5))
    frac = np.where(reach, np.clip(frac, MIN_OPEN, 1.0), 1.0)
    return GasCut(blocked=blocked, unreachable=unreachable, open_fraction=frac, sub=s, wet=wet)


def cell_index(gg: GasGrid, x: np.ndarray) -> np.ndarray:
    """[N, 3] index of the cell of `gg` holding each point x [N, 3]: wrapped on periodic axes, clamped into the
    grid on the others."""
    n = np.asarray(gg.cells)
    idx = np.floor((x - np.asarray(gg.lo)) / np.asarray(gg.h)).astype(np.int64)
    return np.where(gg.periodic, idx % n, np.clip(idx, 0, n - 1))


def sub_grid(gg: GasGrid, s: int) -> GasGrid:
    """The grid of `gg`'s sub-cells, s per cell and axis."""
    return GasGrid(gg.lo, tuple(n * s for n in gg.cells), tuple(h / s for h in gg.h), gg.periodic)


def _fine(cells: np.ndarray, s: int) -> np.ndarray:
    """A per-cell array repeated over each cell's s^3 sub-cells."""
    return np.repeat(np.repeat(np.repeat(cells, s, 0), s, 1), s, 2)


def _coarse(fine: np.ndarray, cells, s: int) -> np.ndarray:
    """A sub-cell array as (cells_x, s, cells_y, s, cells_z, s)."""
    return fine.reshape(cells[0], s, cells[1], s, cells[2], s)


def _sub_axes(c: int) -> tuple[int, ...]:
    """Positions of the sub-cell axes in a face array reshaped to (.., cells, s, ..) per cross axis."""
    return (2, 4) if c == 0 else ((1, 4) if c == 1 else (1, 3))
