"""Domain geometry shared by the kernels: periodic minimum image and cell indexing.

`Grid` is a plain description (no Taichi state) of the uniform cell grid used by the broad
phase; its values are compile-time constants of the kernels that capture it.
"""

from dataclasses import dataclass

import taichi as ti


@dataclass(frozen=True)
class Grid:
    """Uniform cell grid over the domain.

    lo, length: domain corner and extents [m]; periodic: per axis; cells: cell counts per
    axis; cell_size: per axis [m] (>= the largest interaction range); slab_axis: the axis the
    contact pass cuts into slabs (`slab_layout`, `slab_axis_for`).
    """

    lo: tuple[float, float, float]
    length: tuple[float, float, float]
    periodic: tuple[bool, bool, bool]
    cells: tuple[int, int, int]
    slab_axis: int = 0

    @property
    def cell_size(self) -> tuple[float, float, float]:
        return tuple(L / n for L, n in zip(self.length, self.cells))

    @property
    def n_cells(self) -> int:
        return self.cells[0] * self.cells[1] * self.cells[2]


def make_geometry(grid: Grid):
    """Return (min_image, wrap, cell_coord, cell_id) Taichi functions for `grid`."""
    lo = ti.Vector(list(grid.lo))
    length = ti.Vector(list(grid.length))
    per = grid.periodic
    cells = grid.cells
    inv_cell = ti.Vector([1.0 / s for s in grid.cell_size])
    inv_length = ti.Vector([1.0 / L for L in grid.length])

    @ti.func
    def min_image(d):
        """Shortest periodic image of a separation vector d = x_j - x_i."""
        for a in ti.static(range(3)):
            if ti.static(per[a]):
                d[a] -= length[a] * ti.round(d[a] * inv_length[a])
        return d

    @ti.func
    def wrap(x):
        """Map a position back into the periodic box."""
        for a in ti.static(range(3)):
            if ti.static(per[a]):
                x[a] = lo[a] + (x[a] - lo[a]) - length[a] * ti.floor((x[a] - lo[a]) / length[a])
        return x

    @ti.func
    def cell_coord(x):
        """Integer cell coordinates of a position, clamped to the grid on open axes."""
        c = ti.Vector([0, 0, 0])
        for a in ti.static(range(3)):
            c[a] = ti.cast(ti.floor((x[a] - lo[a]) * inv_cell[a]), ti.i32)
            if ti.static(per[a]):
                c[a] = c[a] % cells[a]
            c[a] = ti.min(ti.max(c[a], 0), cells[a] - 1)
        return c

    @ti.func
    def cell_id(c):
        return (c[0] * cells[1] + c[1]) * cells[2] + c[2]

    return min_image, wrap, cell_coord, cell_id


ACROSS_MIN = 16  # cells across gravity that make eight blocks of two slabs (`kernels/contact.py`)


def slab_axis_for(cells, gravity) -> int:
    """The axis to cut into slabs: the one with the most cells across gravity (a bed is about as
    dense everywhere across it, while along gravity it may fill the lower part only; and where it is
    x, each slab is one stretch of storage, which `tidem.particles.storage_order` sorts x, then y, then z), unless
    that has fewer than ACROSS_MIN cells and the axis along gravity more (a tall, narrow column).
    Slabs along gravity cut through the storage order: the bubbling and moving beds ran 1.2-1.4x
    faster with slabs across it (whole runs from the fill, alternating with slabs along gravity,
    2026-11-26)."""
    down = max(range(3), key=lambda a: abs(gravity[a])) if any(gravity) else None
    axis = max((a for a in range(3) if a != down), key=lambda a: cells[a])
    return down if down is not None and cells[axis] < ACROSS_MIN and cells[down] > cells[axis] else axis


def slab_layout(grid: Grid) -> tuple[int, int]:
    """(axis, count) of the slabs that the contact pass sweeps (`kernels/contact.py`): one slab per
    layer of cells along the grid's slab axis, whose cell count `tidem.sim.model.neighbour_grid` makes
    even (or one or two). A slab is a cell wide, so a listed pair's particles lie in the same slab
    or in neighbouring ones. The layout depends on the grid only (never on the thread count), so the
    sums, and a float64 run, are the same on any number of threads."""
    cells = grid.cells[grid.slab_axis]
    if cells > 2 and cells % 2:
        raise ValueError(f"slab axis of {cells} cells: the passes need an even count (tidem.sim.model.neighbour_grid)")
    return grid.slab_axis, cells


def make_slabs(grid: Grid):
    """Return (count, slab_of, succ, pred): the slab count of `slab_layout` and Taichi funcs for the
    slab of a position (its cell's layer) and the slab after and before slab s along the axis
    (wrapped on a periodic axis; -1 past the ends of an open one)."""
    axis, count = slab_layout(grid)
    periodic = grid.periodic[axis]
    _min_image, _wrap, cell_coord, _cell_id = make_geometry(grid)

    @ti.func
    def slab_of(x):
        return cell_coord(x)[axis]

    @ti.func
    def succ(s):
        t = s + 1
        if ti.static(periodic):
            t = t % count
        elif t >= count:
            t = -1
        return t

    @ti.func
    def pred(s):
        t = s - 1
        if ti.static(periodic):
            t = (t + count) % count
        return t

    return count, slab_of, succ, pred
