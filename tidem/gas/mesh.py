"""Mesh walls in the gas grid (scenes with `[[meshes]]` and `[gas]`, plain numpy at set-up): the
cells the gas cannot reach, the gas part of the cells a mesh cuts, and the open share (aperture) of
each face (a cut-cell representation of the walls on the fixed grid, `tidem.gas.apertures`).

Each gas cell is divided into s x s x s sub-cells (`subdivision`). Rays along each axis through
the sub-cells' centres are cut where they pierce a triangle (a triangle parallel to an axis is
found by the rays along the other two, so a sheet of any orientation is seen). Then
- the wet sub-cells are those joined to an open outlet face through sub-cell links no mesh cuts;
- a cell's gas part is its largest set of wet sub-cells joined inside it, and a face's aperture the
  share of its sub-faces open between the two cells' gas parts (`tidem.gas.apertures`); a face with
  none open is closed (blocked) for the gas;
- a cell is solid for the gas, and drops out of the solve, where its gas part is less than MIN_PART
  of it (a sliver, or a cell inside a closed body) or where no path of open faces joins it to an open
  outlet face (a pocket sealed off by a sheet, even one the inlet feeds: gas could not leave it); its
  faces close;
- a cell's open fraction f is its gas part's share of it: the continuity and the gas energy of a cut
  cell hold f V of gas (`kernels/gas_flow.py`). The voidage of a cut cell is taken over the open
  volume of `tidem.gas.open_volume`, which counts the wet sub-cells on a finer subdivision
  (`fine_wet`, `refinement`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tidem.gas.apertures import face_apertures, gas_parts
from tidem.gas.grid_graph import bordering, interior_links, reached
from tidem.kernels.gas_grid import CLOSED, OUTLET, GasGrid

MIN_OPEN = 0.2  # smallest open volume share a cell's voidage is taken over (`tidem.gas.open_volume`)
MIN_PART = 1.0 / 3.0  # smallest gas part a cell in the solve has (`tidem.gas.apertures`): a sliver past it is left out
MAX_SUBCELLS = 4_000_000  # sub-cells of the whole grid at most: s = 4, else 2, else 1


@dataclass
class GasCut:
    """What the meshes do to the gas grid."""

    blocked: list[np.ndarray]  # per face component: bool [face_shape(c)], closed by a mesh beside a cell of the gas
    unreachable: np.ndarray  # bool [cells]: no open path to the outlet
    open_fraction: np.ndarray  # [cells] share of the cell the gas fills (1 where uncut)
    sub: int  # sub-cells per cell and axis
    wet: np.ndarray  # bool [cells x sub per axis]: sub-cells joined to the outlet by uncut links
    fine: int  # the finer subdivision of `fine_wet` (sub times 3, 2 or 1, `refinement`)
    fine_wet: np.ndarray  # bool [cells x fine per axis]: `wet` on the finer subdivision (the open volumes')
    aperture: list[np.ndarray]  # per face component [face_shape(c)]: the open share of each face (`tidem.gas.apertures`)

    def open_sub_cells(self, solid: np.ndarray) -> np.ndarray:
        """bool [cells x fine per axis]: the fine sub-cells open past the meshes, those the gas reaches
        (`fine_wet`) and all of a cell `solid` for another reason than the meshes (a tube's: its own test is
        analytic)."""
        return self.fine_wet | _fine(solid.astype(bool) & ~self.unreachable.astype(bool), self.fine)

    def mixed_cells(self) -> np.ndarray:
        """bool [cells]: the cells a mesh cuts, some of their fine sub-cells wet and some not."""
        share = _coarse(self.fine_wet, self.unreachable.shape, self.fine).mean(axis=(1, 3, 5))
        return (share > 0.0) & (share < 1.0)

    def report_lines(self, walls: str = "meshes") -> list[str]:
        """`tidem check`'s line on the cut; `walls` names what cut the grid."""
        cut = (self.open_fraction < 1.0) & ~self.unreachable
        faces = sum(int(b.sum()) for b in self.blocked)
        shares = np.concatenate([a[(a > 0.0) & (a < 1.0) & ~b].ravel() for a, b in zip(self.aperture, self.blocked)])
        cells = (f"{int(cut.sum())} cut cells (open fraction {self.open_fraction[cut].min():.2f}-"
                 f"{self.open_fraction[cut].max():.2f}, {self.sub}^3 sub-cells per cell)" if cut.any() else "no cut cells")
        cut_faces = (f"{len(shares)} cut faces (open share {shares.min():.2f}-{shares.max():.2f})" if len(shares)
                     else "no cut faces")
        return [f"gas grid: {faces} faces blocked by {walls}, {int(self.unreachable.sum())} cells the gas cannot "
                f"reach (solid), {cells}, {cut_faces}"]


def subdivision(gg: GasGrid) -> int:
    cells = int(np.prod(gg.cells))
    return next(s for s in (4, 2, 1) if cells * s**3 <= MAX_SUBCELLS or s == 1)


def refinement(gg: GasGrid, s: int) -> int:
    """Children per sub-cell and axis of the open volumes' finer subdivision (`GasCut.fine_wet`): 3 or 2 within
    MAX_SUBCELLS, else 1."""
    cells = int(np.prod(gg.cells))
    return next(r for r in (3, 2, 1) if cells * (s * r) ** 3 <= MAX_SUBCELLS or r == 1)


def wet_sub_cells(gg: GasGrid, tri: np.ndarray, solid: np.ndarray, kinds: list[np.ndarray], s: int,
                  clip: np.ndarray | None) -> tuple[np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """(wet, the sub-cell links a mesh cuts, the interior ones it does not): the sub-cells (s per cell and axis)
    joined to an outlet face through links no mesh cuts, never through a `solid` cell."""
    sub_cut = cut_links(gg, tri, s, clip)
    shape = tuple(n * s for n in gg.cells)
    fine_open = [interior_links(~sub_cut[c], c, gg.periodic[c]) for c in range(3)]
    seeds = np.zeros(shape, bool)
    seeds[:, :, -1] = np.repeat(np.repeat(kinds[2][:, :, -1] == OUTLET, s, 0), s, 1) & ~sub_cut[2][:, :, -1]
    return reached(shape, fine_open, gg.periodic, seeds, _fine(solid.astype(bool), s)), sub_cut, fine_open


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


def cut_links(gg: GasGrid, tri: np.ndarray, s: int, clip: np.ndarray | None) -> list[np.ndarray]:
    """Per axis c: the sub-cell links a mesh cuts (bool, shape of the sub-grid with n_c s + 1 links along an
    open c, n_c s periodic, numbered as `_links` does)."""
    sub_cut = []
    for c in range(3):
        a, b = [k for k in range(3) if k != c]
        ia, ib, t, clip_c = ray_crossings(gg, tri, c, s, clip)
        nf = gg.cells[c] * s
        shape = [gg.cells[k] * s for k in range(3)]
        fine = np.zeros([nf if (k == c and gg.periodic[c]) else (nf + 1 if k == c else shape[k]) for k in range(3)],
                        bool)
        link, inside = _links(gg, c, t, clip_c, gg.h[c] / s, nf)
        idx = [None, None, None]
        idx[c], idx[a], idx[b] = link[inside], ia[inside], ib[inside]
        fine[tuple(idx)] = True
        sub_cut.append(fine)
    return sub_cut


def gas_cut(gg: GasGrid, triangles: np.ndarray, solid: np.ndarray, kinds: list[np.ndarray],
            clip: np.ndarray | None = None) -> GasCut:
    """Cut the gas grid with the triangles [T, 3, 3] (scene coordinates, all meshes); `solid` the
    cells already solid (tubes) and `kinds` their face kinds (`gas.geometry.face_kinds`); `clip`
    [T, 3] as `ray_crossings` takes it (None: every mesh wraps across periodic boundaries)."""
    s = subdivision(gg)
    tri = np.asarray(triangles, float)
    wet, sub_cut, fine_open = wet_sub_cells(gg, tri, solid, kinds, s, clip)
    r = refinement(gg, s)
    fine_wet = wet if r == 1 else wet_sub_cells(gg, tri, solid, kinds, s * r, clip)[0]
    parts = gas_parts(gg, s, wet, fine_open)
    share = _coarse(parts, gg.cells, s).mean(axis=(1, 3, 5))
    aperture = face_apertures(gg, s, parts, sub_cut)
    closed = [(aperture[c] == 0.0) & (kinds[c] != CLOSED) for c in range(3)]
    kinds = [np.where(bl, CLOSED, kd) for bl, kd in zip(closed, kinds)]
    # faces as links between consecutive cells (`reached`): on a periodic axis link j is face j + 1
    open_faces = [np.roll(kinds[c] != CLOSED, -1, axis=c) if gg.periodic[c]
                  else interior_links(kinds[c] != CLOSED, c, False) for c in range(3)]
    seeds = np.zeros(gg.cells, bool)
    seeds[:, :, -1] = kinds[2][:, :, -1] == OUTLET
    reach = reached(gg.cells, open_faces, gg.periodic, seeds, solid.astype(bool) | (share < MIN_PART))
    unreachable = ~reach & ~solid.astype(bool)
    blocked = [closed[c] & bordering(reach, c, gg.periodic[c]) for c in range(3)]
    return GasCut(blocked=blocked, unreachable=unreachable, open_fraction=np.where(reach, share, 1.0), sub=s,
                  wet=wet, fine=s * r, fine_wet=fine_wet, aperture=aperture)


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


