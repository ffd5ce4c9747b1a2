"""Direct pressure solve of thin gas grids on the CPU: banded Cholesky factorisation.

The pressure system of `kernels/gas_flow.py` is M p = b with M = -L (`apply` there): on a fluid
cell I, M_II = sum of C_f over its faces f that open to a fluid neighbour J != I or to the outlet,
and M_IJ = -C_f summed over the faces f between I and J; a solid cell's row is the identity.
M is symmetric, and positive definite wherever every fluid region reaches the outlet.
Numbered with the grid's longest axis slowest (cell I -> I_s w + I_a1 n_a2 + I_a2), every coupling
of M lies within w = cells / n_s of the diagonal, periodic wraps across the two other axes
included, so the Cholesky factor M = L L^T keeps that band (Golub & Van Loan, Matrix
Computations, sec. 4.3.5): about cells w^2 / 2 multiply-adds to factor and 2 cells w to solve,
exact to round-off and in one fixed order (bit-reproducible). For the pseudo-2-D beds of 1-4 cells
in depth (fluidized_tube: 20 x 1 x 50 cells, w = 20) that is a fraction of the Jacobi-
preconditioned CG's cost, about 140 iterations over every cell (`benchmarks/README.md`).
`band_width` decides: on the CPU, for a band of at most MAX_BAND cells, and not where the
slowest axis wraps (its wrap would leave the band); else the CG solves. A fluid region with no
outlet makes M singular: the factorisation then reports failure and the step falls back to CG.
"""

import taichi as ti

from .gas_grid import OUTLET
from .ordered import in_order

MAX_BAND = 48  # widest band solved directly: cells w^2 / 2 stays below ~60 CG iterations' cost
SINGULAR = 1e-12  # a pivot below this share of its row's diagonal: the system is singular


def slowest_axis(cells) -> int:
    """The axis numbered slowest: the one with most cells (ties: the later axis, z before x)."""
    return max(range(3), key=lambda a: (cells[a], a))


def band_width(gg, cpu: bool | None = None) -> int:
    """Half-bandwidth w of the direct solve of grid `gg`, or 0 where the CG solves (see the module); `cpu`:
    whether the steps run on the CPU (None: on Taichi's present backend)."""
    n = gg.cells
    s = slowest_axis(n)
    width = n[0] * n[1] * n[2] // n[s]
    if cpu is None:
        cpu = in_order()
    if not cpu or width > MAX_BAND or (gg.periodic[s] and n[s] > 2):
        return 0
    return width


def make_band_solve(gg, G, index, width: int):
    """Return band_solve() -> |b - M p|^2 after solving M p = b (G.rhs) directly into G.p's fluid cells,
    or -1 where M is singular (G.p untouched). Uses G.band (cells x width + 1, the factor's rows, the
    diagonal first) and G.band_y (cells)."""
    n = gg.cells
    s = slowest_axis(n)
    a1, a2 = [a for a in range(3) if a != s]
    w = width
    cells = n[0] * n[1] * n[2]
    unit, cell_index, face_index, apply = index.unit, index.cell_index, index.face_index, index.apply
    C, K = G.C, G.kind

    @ti.func
    def number(I):
        return I[s] * w + I[a1] * n[a2] + I[a2]

    @ti.func
    def cell(m):
        I = ti.Vector([0, 0, 0])
        I[s] = m // w
        I[a1] = m % w // n[a2]
        I[a2] = m % n[a2]
        return I

    @ti.func
    def add_face(m, J, cf, kind):
        """Row m's share of a face of kind `kind` and coefficient cf towards cell J."""
        if kind == OUTLET:
            G.band[m, 0] += cf
        elif cf > 0.0:
            mj = number(J)
            if mj != m:
                G.band[m, 0] += cf
                if mj < m:
                    G.band[m, m - mj] -= cf

    @ti.kernel
    def band_solve() -> ti.f64:
        rr = -1.0
        ti.loop_config(serialize=True)
        for _ in range(1):
            for m in range(cells):  # the lower half of M, row by row
                for d in range(w + 1):
                    G.band[m, d] = 0.0
                I = cell(m)
                if G.solid[I] == 1:
                    G.band[m, 0] = 1.0
                else:
                    for c in ti.static(range(3)):
                        e = unit(c)
                        add_face(m, cell_index(I - e), C[c][I], K[c][I])
                        f = face_index(I + e, c)
                        add_face(m, cell_index(I + e), C[c][f], K[c][f])
            ok = 1
            for m in range(cells):  # M = L L^T, L's row m in G.band[m, m - k] for k = m - w .. m
                if ok == 1:
                    lo = ti.max(m - w, 0)
                    for q in range(lo, m):
                        acc = G.band[m, m - q]
                        for k in range(lo, q):
                            acc -= G.band[m, m - k] * G.band[q, q - k]
                        G.band[m, m - q] = acc / G.band[q, 0]
                    pivot = G.band[m, 0]
                    for k in range(lo, m):
                        pivot -= G.band[m, m - k] * G.band[m, m - k]
                    if pivot <= SINGULAR * G.band[m, 0]:
                        ok = 0
                    G.band[m, 0] = ti.sqrt(ti.max(pivot, 0.0))
            if ok == 1:
                for m in range(cells):  # L y = b
                    acc = G.rhs[cell(m)]
                    for k in range(ti.max(m - w, 0), m):
                        acc -= G.band[m, m - k] * G.band_y[k]
                    G.band_y[m] = acc / G.band[m, 0]
                for r in range(cells):  # L^T p = y, from the last row up
                    m = cells - 1 - r
                    acc = G.band_y[m]
                    for k in range(m + 1, ti.min(m + w + 1, cells)):
                        acc -= G.band[k, k - m] * G.band_y[k]
                    G.band_y[m] = acc / G.band[m, 0]
                for m in range(cells):
                    I = cell(m)
                    if G.solid[I] == 0:
                        G.p[I] = G.band_y[m]
                rr = 0.0
                for m in range(cells):
                    I = cell(m)
                    if G.solid[I] == 0:
                        r = G.rhs[I] - apply(G.p, I)
                        rr += r * r
        return rr

    return band_solve
