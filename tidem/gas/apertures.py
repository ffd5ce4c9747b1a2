"""Cut faces for mesh walls in the gas grid (plain numpy at set-up): each cell's gas part and the open share
(aperture) of each face, which the pressure equation and the gas energy carry (`kernels/gas_flow.py`).

Each gas cell is divided into s x s x s sub-cells (`tidem.gas.mesh.subdivision`); the wet ones are those
the gas reaches from the outlet through sub-cell links no mesh cuts (`GasCut.wet`).
- A cell's **gas part** is its largest set of wet sub-cells joined to each other, inside the cell, by
  links no mesh cuts. A sheet through a cell with gas on both sides leaves two such sets; the smaller is
  left out, so that the cell's one pressure never joins the sheet's two sides (a draft tube's wall, a
  baffle: no leak through it).
- A face's **aperture** a_f is the share of its s x s sub-faces where the sub-cell link across the face is
  not cut and the sub-cells on both sides lie in their cells' gas parts (one side at the inlet and outlet);
  a face with none open is closed.

With these, the finite-volume balance of a cell whose gas part is the share f of its volume V reads
    f V d(eps)/dt + sum_f a_f S_f (eps u)_f = 0
(S_f the face's area, u_f the gas velocity in the open part of the face): the cut-cell ("area and volume
fraction", FAVOR) form of Hirt & Sicilian 1985. The pressure equation keeps its symmetry, each face's
coefficient a_f eps_f A_f / h^2 shared by the two cells.
"""

from __future__ import annotations

import numpy as np

from tidem.gas.grid_graph import components
from tidem.kernels.gas_grid import GasGrid


def gas_parts(gg: GasGrid, s: int, wet: np.ndarray, fine_open: list[np.ndarray]) -> np.ndarray:
    """bool [cells x s per axis]: the sub-cells of each cell's gas part (module docstring); `fine_open` per
    axis the links between consecutive sub-cells no mesh cuts (n s - 1 along an open axis, n s periodic)."""
    shape = wet.shape
    ids = np.arange(wet.size).reshape(shape)
    ea, eb = [], []
    for c in range(3):
        j = np.arange(fine_open[c].shape[c])
        inner = j[(j + 1) % s != 0]  # links between two sub-cells of one cell
        lo = np.take(ids, inner, axis=c)
        hi = np.take(ids, (inner + 1) % shape[c], axis=c)
        ok = np.take(fine_open[c], inner, axis=c) & wet.flat[lo] & wet.flat[hi]
        ea.append(lo[ok])
        eb.append(hi[ok])
    label = components(wet.size, np.concatenate(ea), np.concatenate(eb))
    sub = np.indices(shape).reshape(3, -1) // s
    cell = np.ravel_multi_index(tuple(sub), tuple(gg.cells))
    wet_flat = wet.ravel()
    labels, size = np.unique(label[wet_flat], return_counts=True)  # each set lies in one cell: its smallest member's
    owner = cell[labels]
    order = np.lexsort((-size, owner))  # per cell, its largest set first (ties: the smallest label)
    first = order[np.r_[True, owner[order][1:] != owner[order][:-1]]]
    main = np.full(int(np.prod(gg.cells)), -1)
    main[owner[first]] = labels[first]
    return (wet_flat & (label == main[cell])).reshape(shape)


def face_apertures(gg: GasGrid, s: int, parts: np.ndarray, sub_cut: list[np.ndarray]) -> list[np.ndarray]:
    """Per axis c: the aperture of each face normal to c (shape `gg.face_shape(c)`, module docstring), from the
    gas parts and the sub-cell links a mesh cuts (`gas.mesh.cut_links`: along an open axis link L joins
    sub-cells L - 1 and L, link 0 and n s the boundaries; along a periodic one link j joins j and j + 1)."""
    out = []
    for c in range(3):
        ns = gg.cells[c] * s
        if gg.periodic[c]:
            f = np.arange(gg.cells[c]) * s
            cut = np.take(sub_cut[c], (f - 1) % ns, axis=c)
            lo, hi = np.take(parts, (f - 1) % ns, axis=c), np.take(parts, f % ns, axis=c)
        else:
            f = np.arange(gg.cells[c] + 1) * s
            pad = [(0, 0)] * 3
            pad[c] = (1, 1)
            padded = np.pad(parts, pad, constant_values=True)  # no cell beyond the boundary: its side is open
            cut = np.take(sub_cut[c], f, axis=c)
            lo, hi = np.take(padded, f, axis=c), np.take(padded, f + 1, axis=c)
        open_ = ~cut & lo & hi
        split = []  # the face array with each cross axis split into (cells, sub-cells)
        for k in range(3):
            split += [open_.shape[k]] if k == c else [gg.cells[k], s]
        cross = (2, 4) if c == 0 else ((1, 4) if c == 1 else (1, 3))
        out.append(open_.reshape(split).mean(axis=cross))
    return out
