"""`gas.cell_size` as one size or [x, y, z]: the grid each gives, and the checks on it."""

import pytest

from tidem.gas.geometry import gas_grid
from tidem.runner.check_report import gas_notes
from tidem.scene.load import SceneError, load


def test_a_cell_size_per_axis_sets_each_axis_and_is_checked_per_axis():
    """pseudo2d_bubbling_bed (90 x 8 x 500 mm, 1.545 mm beads): 0.005 gives 18 x 2 x 100 cells of 5 x 4 x 5 mm;
    [0.005, 0.008, 0.005] one cell of 8 mm across the depth, which `tidem check` notes; a cell under two grain
    diameters along any axis is refused by name."""
    one = gas_grid(load("pseudo2d_bubbling_bed").scene)
    assert one.cells == (18, 2, 100) and one.h == pytest.approx((0.005, 0.004, 0.005))
    deep = load("pseudo2d_bubbling_bed", ["gas.cell_size=[0.005, 0.008, 0.005]"]).scene
    grid = gas_grid(deep)
    assert grid.cells == (18, 1, 100) and grid.h == pytest.approx((0.005, 0.008, 0.005))

    class Model:
        scene = deep
        tubes = []
    assert any("one cell across y between walls" in note and "[0.005, 0.008, 0.005]" in note for note in gas_notes(Model))
    with pytest.raises(SceneError, match=r"gas.cell_size: cells of 0.0025 m are smaller than 2 particle diameters"):
        load("pseudo2d_bubbling_bed", ["gas.cell_size=[0.0025, 0.008, 0.005]"])


def test_a_size_per_axis_that_is_not_positive_is_refused_in_one_line():
    """A non-positive size per axis or alone: one message naming gas.cell_size, not one per form of the key."""
    for bad, shown in (("[0.005, -0.008, 0.005]", r"every size must be > 0 \(got \[0.005, -0.008, 0.005\]\)"),
                       ("-0.005", r"must be > 0 \(got -0.005\)")):
        with pytest.raises(SceneError, match=r"1 error in the scene\n  gas.cell_size: " + shown):
            load("pseudo2d_bubbling_bed", [f"gas.cell_size={bad}"])
