"""The lattice sites of a filled region that a grain could reach from the top of the domain without
passing through a mesh (`particles[i].skip_pockets`): the pockets behind a hopper's, wedge's or cone's
walls, which a pour would leave empty, are not filled.

The domain is divided into voxels of at most half the lattice spacing. A voxel is joined to each of its
six neighbours (across a periodic side too) unless a triangle cuts the segment between their centres (the
ray casting of `tidem.gas.mesh`, one sub-cell per voxel, a mesh spanning a period clipped to it as the
gas cut does), and the voxels joined to the domain's top layer are found by connected components. A site
keeps at least half a spacing from every mesh (`placement.clear_of_obstacles`), and its voxel's centre
lies at most 0.43 spacings from it, so no wall passes between them: the site is judged exactly. A domain of
more than MAX_VOXELS such voxels takes larger ones, and a site within a voxel of a wall may then be judged
by the voxel on the wall's other side.
"""

from __future__ import annotations

import numpy as np

from tidem.gas.geometry import spans_period
from tidem.gas.grid_graph import interior_links, reached
from tidem.gas.mesh import cell_index, cut_links
from tidem.kernels.gas_grid import GasGrid

MAX_VOXELS = 4_000_000  # as the gas cut's sub-cells (`gas.mesh.MAX_SUBCELLS`)


def joined_to_top(lo, lengths, periodic, spacing: float, meshes, sites: np.ndarray) -> np.ndarray:
    """Mask of the `sites` [N, 3] joined to the top of the domain (lower corner `lo`, `lengths`, `periodic`
    per axis) by a path that crosses no triangle of `meshes` (`tidem.walls.mesh_walls.MeshWall`, at t = 0)."""
    lengths = np.asarray(lengths, float)
    h = max(0.5 * spacing, float(np.prod(lengths) / MAX_VOXELS) ** (1.0 / 3.0))
    cells = tuple(int(n) for n in np.maximum(np.ceil(lengths / h - 1e-9), 1))
    grid = GasGrid(tuple(float(x) for x in lo), cells, tuple(lengths / cells), tuple(bool(p) for p in periodic))
    triangles = np.concatenate([m.vertices[m.triangles] for m in meshes])
    cut = cut_links(grid, triangles, 1, spans_period(grid, meshes))
    links = [interior_links(~cut[c], c, grid.periodic[c]) for c in range(3)]
    seeds = np.zeros(cells, bool)
    seeds[:, :, -1] = True
    joined = reached(cells, links, grid.periodic, seeds, np.zeros(cells, bool))
    return joined[tuple(cell_index(grid, sites).T)]
