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
    axis; cell_size: per axis [m] (>= the largest interaction range).
    """

    lo: tuple[float, float, float]
    length: tuple[float, float, float]
    periodic: tuple[bool, bool, bool]
    cells: tuple[int, int, int]

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
