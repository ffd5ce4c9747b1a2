"""Tubes cut into the gas grid (`gas.tube_shape = "cut"`, `tidem.gas.tube_cut`): the section the gas loses to a
tube on any grid, the convection surface, continuity past a cut tube and a uniform bed read as uniform beside
it, against geometry worked out by hand."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.gas.geometry import convection_walls, cut_share, gas_walls, solid_cells
from tidem.gas.tube_cut import TUBE_FACETS, tube_triangles
from tidem.kernels.gas_grid import GasGrid

TUBE = {"c": [0.03, 0.0, 0.035], "mask": [1.0, 0.0, 1.0], "r": 0.0075, "T": 353.15}  # the slab's 15 mm tube


def slab_grid(h: float) -> GasGrid:
    """The coarse-graining slab's grid (60 x 12 x 198 mm, periodic in depth) on cells of about h."""
    n = (round(0.06 / h), round(0.012 / h), round(0.198 / h))
    return GasGrid(lo=(0.0, 0.0, 0.0), cells=n, h=(0.06 / n[0], 0.012 / n[1], 0.198 / n[2]),
                   periodic=(False, True, False))


def test_the_prism_has_the_tube_section_and_spans_the_domain_along_its_axis():
    gg = slab_grid(0.004)
    tri, clip = tube_triangles(gg, TUBE)
    assert len(tri) == 2 * TUBE_FACETS and clip[:, 1].all() and not clip[:, [0, 2]].any()
    assert tri[:, :, 1].min() == 0.0 and tri[:, :, 1].max() == pytest.approx(0.012, rel=1e-12)
    ring = tri[:TUBE_FACETS, 0][:, [0, 2]] - np.array([0.03, 0.035])  # the corners at y = 0, in order
    nxt = np.roll(ring, -1, axis=0)
    area = 0.5 * np.sum(ring[:, 0] * nxt[:, 1] - nxt[:, 0] * ring[:, 1])  # the shoelace formula
    assert area == pytest.approx(np.pi * 0.0075**2, rel=1e-12)


@pytest.mark.parametrize("h", [0.003, 0.004, 0.005, 0.006])
def test_the_gas_loses_the_tube_section_on_any_grid(h):
    """The section the gas loses to the tube: the sealed cells and the cut cells' part outside their gas part.
    Cut: 1.02-1.04 of pi r^2 (measured; the cells with less than a third of their sub-cells outside the tube
    are sealed whole, `gas.mesh.MIN_PART`) on cells of 3 to 6 mm. The staircase of cells whose centre lies in
    the tube: 0.56 (5 mm cells) to 0.92 (3 mm) of it, as the grid's lines fall."""
    gg = slab_grid(h)
    cell_area = gg.h[0] * gg.h[2]
    section = np.pi * TUBE["r"] ** 2
    solid, _, cut = gas_walls(gg, [TUBE], [], cut_tubes=True)
    lost = (solid[:, 0, :].sum() + ((1.0 - cut.open_fraction[:, 0, :]) * (solid[:, 0, :] == 0)).sum()) * cell_area
    assert lost / section == pytest.approx(1.0, abs=0.05)
    assert cut_share(gg, TUBE, cut) == pytest.approx(lost / section, rel=1e-9)  # `tidem check`'s share
    staircase = solid_cells(gg, [TUBE])[:, 0, :].sum() * cell_area / section
    assert abs(staircase - 1.0) > 0.07  # what the cut replaces: 8 to 44 % off on these grids


def test_a_cut_tube_gives_the_gas_its_whole_surface_in_the_cells_beside_it():
    """wall_A adds up to pi D L over cells of the gas, each within a cell's diagonal of the tube's surface."""
    gg = slab_grid(0.005)
    solid, _, cut = gas_walls(gg, [TUBE], [], cut_tubes=True)
    walls = convection_walls(gg, [TUBE], [], cut, cut_tubes=True)
    mine = walls["wall_A"] > 0.0
    assert walls["wall_A"].sum() == pytest.approx(np.pi * 0.015 * 0.012, rel=1e-12)
    assert not (mine & (solid == 1)).any()
    assert (walls["wall_T"][mine] == 353.15).all() and (walls["wall_D"][mine] == 0.015).all()
    idx = np.argwhere(mine)
    centres = (idx + 0.5) * np.asarray(gg.h)
    distance = np.hypot(centres[:, 0] - 0.03, centres[:, 2] - 0.035)
    assert (np.abs(distance - 0.0075) < np.linalg.norm(gg.h)).all()


def cut_tube_bed(u: float):
    """Gas at u through a periodic slab 60 x 12 x 100 mm on 5 mm cells round the 15 mm tube, cut, with one fixed
    grain far above it."""
    sand = {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.9, "friction": 0.3}
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.06, 0.012, 0.1], "periodic": ["y"], "walls": "auto",
                "gravity": [0, 0, -9.81]},
        materials={"sand": sand},
        tubes=[{"center": [0.03, 0.0, 0.035], "axis": "y", "diameter": 0.015}],
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": 0.001}, "fixed": True,
                    "positions": [[0.01, 0.006, 0.09]]}],
        gas={"cell_size": 0.005, "inlet_velocity": u, "coupling_interval": 1, "tube_shape": "cut"},
        numerics={"dt": 1e-4, "force_dt": True},
    )


def test_gas_past_a_cut_tube_keeps_its_flux_through_every_level(solver_for):
    """Continuity with cut faces: the flux a_f eps_f u_f S_f through each row of horizontal faces equals the
    inlet's U A (1e-6), the rows through the tube included, where the gas passes beside it faster (up to 1.8 U
    measured in a cell beside the tube)."""
    u = 0.2
    s = solver_for(cut_tube_bed(u))
    for _ in range(10):
        s.step()
    G, gas = s.gas.G, s.gas
    assert gas.cut is not None and gas.cut.open_fraction.min() < 1.0
    uz, a = G.u[2].to_numpy(), gas.cut.aperture[2]
    eps_face = np.ones_like(uz)  # voidage 1: the one grain lies above the rows checked
    flux = (a * eps_face * uz).sum(axis=(0, 1)) * gas.gg.h[0] * gas.gg.h[1]
    area = 0.06 * 0.012
    for k in range(1, 16):  # the faces from 5 to 75 mm, the tube's (27.5-42.5 mm) among them
        assert flux[k] == pytest.approx(u * area, rel=1e-6), k
    through = [k for k in range(gas.gg.cells[2]) if (a[:, :, k] < 1.0).any()]
    assert through and max(uz[:, :, k].max() for k in through) > 1.2 * u


def test_a_uniform_bed_around_a_cut_tube_reads_its_solid_fraction_beside_it(solver_for):
    """The lattice bed of `test_open_volume` round fluidized_tube's tube, cut into its 4 mm cells: every gas
    cell, the cut ones included, holds the bed's solid fraction within 6 % (0.959 to 1.000 measured, as round the tube
    drawn as a mesh)."""
    from tests.gas.test_open_volume import lattice_bed

    _, raw = lattice_bed(tube_shape="cut")
    solver = solver_for(raw)
    solver.step()
    gas = solver.gas
    assert gas.cut is not None and ((gas.cut.open_fraction < 1.0) & (gas.solid == 0)).any()
    fluid = gas.solid == 0
    solid_fraction = (1.0 - gas.G.eps.to_numpy())[fluid]
    expected = np.pi / 6 * 1e-12 / 0.0005**3
    assert np.abs(solid_fraction / expected - 1.0).max() < 0.06


def test_check_notes_a_tube_far_from_its_section_and_what_resolves_it():
    """`tidem check` notes a tube that blocks the gas more than 10 % away from its section. As the staircase: the
    slab's tube on 5 mm cells (0.56), with the cut as the fix; not on 3 mm cells (0.92). A 10 mm tube on 11.1 mm
    cells (lab_fluidized_bundle's) blocks 1.57 of it either way (the cut seals the cells it nearly fills), with
    finer cells as the fix, one note for equal tubes; the slab's tube cut into 5 mm cells (1.02) gets none."""
    from tidem.runner.check_report import tube_section_notes

    (note,) = tube_section_notes(slab_grid(0.005), [TUBE])
    assert "tubes[0] is the cells whose centre lies in it, 0.56 of the section" in note and "tube_shape" in note
    assert tube_section_notes(slab_grid(0.003), [TUBE]) == []
    five = slab_grid(0.005)
    assert tube_section_notes(five, [TUBE], gas_walls(five, [TUBE], [], cut_tubes=True)[2]) == []
    lab = GasGrid(lo=(0.0, 0.0, 0.0), cells=(9, 9, 22), h=(0.1 / 9, 0.1 / 9, 0.2444 / 22),
                  periodic=(False, False, False))
    tubes = [{"c": [x, 0.0, 0.0611], "mask": [1.0, 0.0, 1.0], "r": 0.005, "T": 353.15} for x in (0.0278, 0.0722)]
    (note,) = tube_section_notes(lab, tubes)
    assert "tubes[0], tubes[1] are" in note and "1.57 of the section" in note and "a third of the diameter" in note
    (note,) = tube_section_notes(lab, tubes, gas_walls(lab, tubes, [], cut_tubes=True)[2])
    assert "tubes[0], tubes[1] cut into these cells block 1.57 of the section" in note and "a third" in note


def test_a_cut_tube_across_the_whole_width_is_refused_by_name():
    """A 15 mm tube spanning a 15 mm wide slab leaves the gas no way past it: the refusal names the tubes, not the
    meshes the scene does not have."""
    from tidem.scene.errors import SceneError
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    raw = cut_tube_bed(0.2)
    raw["domain"]["max"][0] = 0.015
    raw["tubes"][0]["center"][0] = 0.0075
    raw["particles"][0]["positions"] = [[0.005, 0.006, 0.09]]
    with pytest.raises(SceneError) as exc:
        build_model(validate(raw))
    (msg,) = exc.value.messages
    assert msg.startswith("tubes: the tubes close every inlet face of the gas grid, or every path from the inlet")
    assert "open the distributor under the tubes" in msg
