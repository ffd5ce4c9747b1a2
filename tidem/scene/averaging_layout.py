"""The control volumes of a scene's [averaging] table (source 3, Bartsch 2020, eq. 34-36):
cells in the x-z plane and ring sectors around tubes, sized from the scene alone, so that the
scene checks and the Model see the same layout. Sampling and output: `tidem.results.averaging`.
"""

from __future__ import annotations

from dataclasses import dataclass

from tidem.scene.sizes import max_diameter


@dataclass(frozen=True)
class AveragingLayout:
    """The control volumes and cadence of a scene's [averaging] table."""

    lo: tuple[float, float]  # lower x and z corner of the cells [m]
    cells: tuple[int, int]  # cells along x and z
    size: tuple[float, float]  # cell size along x and z [m] (a whole number of cells spans the domain)
    depth: float  # domain extent along y [m]
    ring_width: float  # radial thickness of a ring [m]
    rings: int
    sectors: int
    start: float  # first sample [s]
    interval: float | None  # between samples [s]; None: the time-series interval

    @property
    def cell_volume(self) -> float:
        return self.size[0] * self.depth * self.size[1]


def cell_grid(scene) -> tuple[tuple[int, int], tuple[float, float]]:
    """Cells along x and z and their sizes [m]: `averaging.cell_size` (default 3 of the largest
    particle diameters) rounded so that a whole number of cells spans the domain."""
    dom, avg = scene.domain, scene.averaging
    wanted = avg.cell_size or (3.0 * max_diameter(scene),) * 2
    counts, sizes = [], []
    for a, want in zip((0, 2), wanted):
        length = dom.max[a] - dom.min[a]
        counts.append(max(1, round(length / want)))
        sizes.append(length / counts[-1])
    return tuple(counts), tuple(sizes)


def averaging_layout(scene) -> AveragingLayout | None:
    """The layout of the scene's [averaging] table, or None without one."""
    avg = scene.averaging
    if avg is None:
        return None
    dom = scene.domain
    cells, size = cell_grid(scene)
    return AveragingLayout(lo=(dom.min[0], dom.min[2]), cells=cells, size=size, depth=dom.max[1] - dom.min[1],
                           ring_width=avg.ring_width or max_diameter(scene), rings=avg.rings,
                           sectors=avg.ring_sectors, start=avg.start, interval=avg.interval)
