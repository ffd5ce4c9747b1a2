"""The gas grid: a staggered (MAC) Eulerian grid over the domain, and the particle <-> grid
weights that both interpolation and deposition use.

Cells carry voidage, pressure and gas temperature at their centres; face component c
(0 = x, 1 = y, 2 = z) carries the gas velocity u_c and the pressure gradient at the centres of
the faces normal to axis c. On a periodic axis the last face is the first one, so face
arrays have n_c faces there and n_c + 1 on an open axis.

Cloud-in-cell (trilinear) weights: a particle at x sees the 8 lattice points around it with
weights that sum to 1; on an open axis an index past the end is clamped to the boundary point
(its weight folds back, so deposited volume is conserved), on a periodic axis it wraps.
Interpolating a field with these weights and depositing with the same weights are adjoint,
which is what makes the drag reaction on the gas equal and opposite to the drag on the
particles (see `kernels/gas_coupling.py`).
"""

from dataclasses import dataclass

import taichi as ti

from .ordered import in_order

CLOSED, INTERIOR, INLET, OUTLET = 0, 1, 2, 3  # kinds of a face: wall, between cells, inlet, outlet
# The 8 corners of a CIC cube (0/1 per axis, the last axis fastest). Loops over them as
# Corners as Python tuples (`make_cic`'s corners) keep o a compile-time constant, so the weights
# fold; `ti.static(ti.grouped(ti.ndrange(2, 2, 2)))` left them run-time values: the deposit of
# `gas_coupling.couple` took 2.25 against 1.53 ms a gas step of fluidized_tube (measured).
CORNERS = [(q // 4, q // 2 % 2, q % 2) for q in range(8)]


@dataclass(frozen=True)
class GasGrid:
    """lo [m], cells per axis, cell size h per axis [m], periodic flags (z is never periodic)."""

    lo: tuple[float, float, float]
    cells: tuple[int, int, int]
    h: tuple[float, float, float]
    periodic: tuple[bool, bool, bool]

    @property
    def volume(self) -> float:
        return self.h[0] * self.h[1] * self.h[2]

    def face_shape(self, c: int) -> tuple[int, int, int]:
        n = list(self.cells)
        if not self.periodic[c]:
            n[c] += 1
        return tuple(n)

    def center(self, idx) -> tuple[float, float, float]:
        return tuple(self.lo[a] + (idx[a] + 0.5) * self.h[a] for a in range(3))


SERIAL_GRID_CELLS = 4096  # grids up to this size take their per-cell and per-face loops in one thread on the CPU


def serial_loops(gg: GasGrid) -> bool:
    """Whether the per-cell and per-face loops of grid `gg` run in one thread, in cell order: grids of up to
    SERIAL_GRID_CELLS cells on the CPU, where waking Taichi's thread pool for a loop costs more than the
    loop's work (about 50 us a loop on 2 cores against a few us for 1000 cells, `benchmarks/README.md`). Their
    sums (the tubes' heat flows, |b|^2) are then taken in one order: the same bits on any thread count."""
    return gg.cells[0] * gg.cells[1] * gg.cells[2] <= SERIAL_GRID_CELLS and in_order()


def layer_grid(gg: GasGrid, layers: int) -> GasGrid:
    """The grid of horizontal layers: the cells of gg across, each cut into `layers` along z."""
    nx, ny, nz = gg.cells
    return GasGrid(gg.lo, (nx, ny, nz * layers), (gg.h[0], gg.h[1], gg.h[2] / layers), gg.periodic)


def make_cic(gg: GasGrid):
    """Return cic(x, stagger) -> (base index vector, fraction vector), corner(base, o, stagger) -> lattice
    index, weight(frac, o, stagger) and corners(stagger), the CIC cube's corners o (0/1 per axis) as
    compile-time tuples: `for o in ti.static(corners(stagger))` visits each lattice point a particle reaches.

    stagger = -1 for cell centres, c (0..2) for faces normal to axis c. An axis across (x or y) with a
    single lattice point (one cell, periodic or between walls; faces along it: one, periodic) puts both
    corners on that point: it is visited once with weight 1 instead of twice with 1 - f and f, the same
    value in exact arithmetic at half the loads and adds (a one-cell slice such as fluidized_tube's 20 x 1
    x 50 grid). Never z, whose corner below the bottom cell may take a mirrored value (`below_inlet`).
    """
    lo = ti.Vector(list(gg.lo))
    inv_h = ti.Vector([1.0 / v for v in gg.h])
    per = gg.periodic
    n = gg.cells

    @ti.func
    def cic(x, stagger: ti.template()):
        g = (x - lo) * inv_h - 0.5
        if ti.static(stagger >= 0):
            g[stagger] += 0.5
        base = ti.floor(g)
        return ti.cast(base, ti.i32), g - base

    @ti.func
    def corner(base, o, stagger: ti.template()):
        """Lattice index of corner o (0/1 per axis) of the CIC cube, clamped or wrapped."""
        idx = base + o
        for a in ti.static(range(3)):
            if ti.static(per[a]):
                idx[a] = idx[a] % n[a]
            else:
                top = n[a] - 1
                if ti.static(stagger == a):
                    top = n[a]
                idx[a] = ti.min(ti.max(idx[a], 0), top)
        return idx

    def single(a: int, stagger: int) -> bool:
        """Axis a has a single lattice point for this stagger (docstring)."""
        return a < 2 and n[a] == 1 and (per[a] or stagger != a)

    def corners(stagger: int) -> list[tuple[int, int, int]]:
        return [o for o in CORNERS if not any(o[a] and single(a, stagger) for a in range(3))]

    @ti.func
    def weight(frac, o, stagger: ti.template()):
        w = 1.0
        for a in ti.static(range(3)):
            if ti.static(not single(a, stagger)):
                w *= frac[a] if o[a] == 1 else 1.0 - frac[a]
        return w

    return cic, corner, weight, corners
