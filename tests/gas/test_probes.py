"""Pressure probes (`tidem.gas.probes`): a point reads the trilinear interpolation of the cell
centres around it, over the cells that hold gas; a height the mean of a layer's fluid cells."""

import numpy as np
import pytest

from tidem.gas.probes import probe_column, probe_pressures
from tidem.scene.load import SceneError, load

LO, H = (0.0, 0.0, 0.0), (0.005, 0.004, 0.005)
SHAPE = (6, 2, 8)


def centred(f):
    """f at every cell centre of the test grid."""
    x, y, z = (LO[a] + (np.arange(SHAPE[a]) + 0.5) * H[a] for a in range(3))
    return f(*np.meshgrid(x, y, z, indexing="ij"))


def linear(x, y, z):
    return 100.0 + 2000.0 * x - 500.0 * y - 8000.0 * z


def test_a_point_probe_reads_a_linear_field_exactly_and_holds_beyond_the_outer_centres():
    """Trilinear interpolation reproduces a linear field at any point between centres (1e-12); beyond
    the outermost centres it reads the value on them (the wall-side half cell)."""
    p, fluid = centred(linear), np.ones(SHAPE, bool)
    inside = (0.0123, 0.0031, 0.0217)
    edge = (0.0, 0.008, 0.0217)
    out = probe_pressures([inside, edge], p, fluid, LO, H)
    assert probe_column(inside) == "gas_pressure_x12.3_y3.1_z21.7mm_Pa"
    assert out[probe_column(inside)] == pytest.approx(linear(*inside), rel=1e-12)
    assert out[probe_column(edge)] == pytest.approx(linear(0.0025, 0.006, 0.0217), rel=1e-12)


def test_a_point_probe_leaves_out_solid_cells_and_a_height_reads_its_layers_fluid_mean():
    """A solid cell among the eight drops out with the others' weights renormalised; a height on a
    layer's centre reads the mean of that layer's fluid cells, between centres the linear interpolation."""
    p, fluid = centred(linear), np.ones(SHAPE, bool)
    p[2, 0, 3] = 1e9  # a solid cell's pressure must not be read
    fluid[2, 0, 3] = False
    point = (0.010, 0.004, 0.015)  # the corner shared by cells x 1-2, y 0-1, z 2-3
    around = [(1 + i, j, 2 + k) for i, j, k in np.ndindex(2, 2, 2)]
    others = [p[c] for c in around if c != (2, 0, 3)]
    out = probe_pressures([point, 0.0175, 0.015], p, fluid, LO, H)
    assert out[probe_column(point)] == pytest.approx(np.mean(others), rel=1e-12)
    layer = [np.mean(p[:, :, k][fluid[:, :, k]]) for k in (2, 3)]
    assert out[probe_column(0.0175)] == pytest.approx(layer[1], rel=1e-12)
    assert out[probe_column(0.015)] == pytest.approx(0.5 * (layer[0] + layer[1]), rel=1e-12)


def test_a_point_among_solid_cells_reads_the_nearest_fluid_cell_and_a_point_in_a_tube_is_refused():
    """Eight solid cells around a point: the nearest fluid cell's pressure; a point inside a tube is
    refused by name before the run."""
    p, fluid = centred(linear), np.ones(SHAPE, bool)
    fluid[1:4, :, 1:6] = False
    point = (0.011, 0.002, 0.0175)  # nearest fluid centre: cell (0, 0, 3), 8.5 mm off along x
    assert probe_pressures([point], p, fluid, LO, H)[probe_column(point)] == p[0, 0, 3]
    with pytest.raises(SceneError, match=r"gas.pressure_probes\[1\]: the point \[0.04, 0.002, 0.04\] lies inside tubes\[0\]"):
        load("fluidized_tube", ["gas.pressure_probes=[0.045, [0.04, 0.002, 0.04]]"])
