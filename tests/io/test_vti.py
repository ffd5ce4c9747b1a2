"""Gas snapshots as VTK ImageData: what `write_vti` writes reads back unchanged, in VTK's
cell order, and ParaView's reader (VTK, through pyvista) sees the same cells and values."""

import numpy as np

from tidem.io.vtp import read_vti, write_vti


def test_vti_round_trip_and_vtk_reads_the_same_cells(tmp_path):
    import pyvista as pv

    cells = (4, 3, 5)
    rng = np.random.default_rng(3)
    scalar = rng.random(cells)
    vector = rng.random(cells + (3,))
    path = tmp_path / "g.vti"
    write_vti(path, (0.1, 0.0, -0.2), (0.01, 0.02, 0.03), cells, {"T": scalar, "u": vector,
                                                                   "solid": np.zeros(cells, np.int32)}, time=1.5)
    grid, back = read_vti(path)
    assert grid["cells"] == cells and grid["time"] == 1.5 and grid["spacing"] == [0.01, 0.02, 0.03]
    assert np.array_equal(back["T"], scalar) and np.array_equal(back["u"], vector)
    image = pv.read(path)
    assert image.dimensions == (5, 4, 6) and image.n_cells == 60
    centres = image.cell_centers().points
    i, j, k = 2, 1, 3  # the VTK cell at these indices sits where the array says
    at = np.argmin(np.linalg.norm(centres - np.array([0.1 + 0.025, 0.03, -0.2 + 0.105]), axis=1))
    assert image.cell_data["T"][at] == scalar[i, j, k]
    assert np.allclose(image.cell_data["u"][at], vector[i, j, k])
