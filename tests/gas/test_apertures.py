"""Cut faces of mesh walls in the gas grid (`tidem.gas.apertures`): the open share of each face and the gas
part of each cell, against geometry whose open areas are known (plain numpy, no solver)."""

import numpy as np

from tests.gas.test_mesh import cut, grid, sheet
from tidem.gas.grid_graph import reached


def upright_sheet(x, y0, y1, z0, z1) -> np.ndarray:
    """A vertical rectangle at x, across y and z, as two triangles."""
    a, b, c, d = (x, y0, z0), (x, y1, z0), (x, y1, z1), (x, y0, z1)
    return np.array([[a, b, c], [a, c, d]], float)


def test_a_slot_narrower_than_half_a_cell_passes_gas_through_its_share_of_the_face():
    """A sheet at z = 41 mm over the whole slab but for a slot 5 mm wide (x from 30 to 35 mm, half a 10 mm
    cell; 2.5 mm sub-cells): the face over the slot opens half, every other face of that row closes, and
    the cells below stay joined to the outlet through the slot alone. The staircase of whole faces closed
    such a slot (half of its rays cut) and sealed everything below it."""
    gg = grid(n=(8, 2, 8), periodic=(True, True, False))
    c = cut(gg, np.concatenate([sheet(0.0, 0.03, 0.0, 0.02, 0.041), sheet(0.035, 0.08, 0.0, 0.02, 0.041)]))
    row = c.aperture[2][:, :, 4]  # the faces between layers 3 and 4 (z = 0.04)
    assert (row[3] == 0.5).all() and (np.delete(row, 3, axis=0) == 0.0).all()
    assert row.sum() * 0.01 * 0.01 == np.float64(0.005 * 0.02)  # the slot's area, exactly
    assert not c.unreachable.any()


def test_a_sheet_with_gas_on_both_sides_never_joins_them_through_the_cells_it_cuts():
    """A baffle (one sheet, no thickness) upright at x = 43 mm, from the distributor to 60 mm, the slab open
    above it: both sides are wet, and the cells it cuts (x from 40 to 50 mm) hold both. Each such cell keeps
    its larger side (7 of its 10 mm) as its gas part, so its face towards the smaller side's neighbour
    closes: below 60 mm no path of open faces joins the two sides, as no gas crosses a baffle. Over it they
    join."""
    gg = grid(n=(8, 1, 8), periodic=(False, True, False))
    c = cut(gg, upright_sheet(0.043, -0.01, 0.02, 0.0, 0.06))
    assert not c.unreachable.any()
    assert np.allclose(c.open_fraction[4, :, :6], 0.75)  # 3 of its 4 sub-cell columns, right of the sheet
    assert (c.aperture[0][4, :, :6] == 0.0).all() and (c.aperture[0][5, :, :6] == 1.0).all()
    assert (c.aperture[0][4, :, 6:] == 1.0).all()
    # the faces below 60 mm join the left side (cells 0-3) to nothing right of it
    links = [c.aperture[0][1:-1, :, :6] > 0.0, np.ones((8, 1, 6), bool), c.aperture[2][:, :, 1:6] > 0.0]
    seeds = np.zeros((8, 1, 6), bool)
    seeds[0] = True
    joined = reached((8, 1, 6), links, (False, True, False), seeds, np.zeros((8, 1, 6), bool))
    assert joined[:4].all() and not joined[4:].any()


def test_gas_at_one_temperature_stays_at_it_through_the_cut_cells(tmp_path, solver_for):
    """Gas at 350 K flowing at 0.3 m/s through the wedge's bed (4 mm cells, leaning plates: cut cells of gas
    parts down to a half and cut faces), grains and inlet at 350 K too, the lattice settling (the voidage
    changes by up to 9e-4 in 30 steps): every cell stays at 350 K to 1e-9 (3e-12 measured). The gas energy
    of a cut cell takes the continuity's fluxes a_f eps_f u_f S_f and its volume f V; with its whole volume
    V instead, the cut cells drift 0.2 K."""
    from tests.gas.test_mesh import wedge_bed

    raw, _, _ = wedge_bed(tmp_path, cell=0.004)
    raw["heat"] = {"initial_temperature": 350.0}
    raw["gas"].update(initial_temperature=350.0, inlet_temperature=350.0)
    raw["materials"]["sand"].update(conductivity=3.0, heat_capacity=800.0)
    raw["particles"][0]["fixed"] = False  # the lattice settles: the voidage changes
    solver = solver_for(raw)
    gas = solver.gas
    part = gas.cut.open_fraction[gas.solid == 0]
    assert part.min() == 0.5 and (gas.cut.aperture[2] % 1.0 > 0.0).any()
    eps0 = gas.G.eps.to_numpy()
    for _ in range(30):
        solver.step()
    assert np.abs(gas.G.eps.to_numpy() - eps0).max() > 5e-4
    assert np.abs(gas.G.T.to_numpy()[gas.solid == 0] - 350.0).max() < 1e-9
