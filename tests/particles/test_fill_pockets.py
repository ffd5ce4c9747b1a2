"""A filled region with `skip_pockets` (`tidem.particles.fill_pockets`): the lattice sites a grain could not reach from
the domain's top, behind a wedge's leaning plates or under a lid, stay empty; every other site is kept."""

import numpy as np
import pytest
import pyvista as pv

from tidem.particles.placement import place_groups
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.walls.mesh_load import load_mesh_walls

W, SLOT, TOP, DEPTH = 0.1, 0.016, 0.1, 0.004  # the wedge: plates from a 16 mm slot to the side walls 100 mm up


def save(path, quads):
    """Quads [(x_a, z_a), (x_b, z_b)], each drawn across y past the slab's period, as an STL."""
    tri = []
    for (xa, za), (xb, zb) in quads:
        a, b, c, e = (xa, -0.001, za), (xa, DEPTH + 0.001, za), (xb, DEPTH + 0.001, zb), (xb, -0.001, zb)
        tri += [[a, b, c], [a, c, e]]
    tri = np.array(tri, float)
    pv.PolyData.from_regular_faces(tri.reshape(-1, 3), np.arange(len(tri) * 3).reshape(-1, 3)).save(str(path))


def place(tmp_path, quads, skip: bool, top: float = 0.07, right: float = W, bottom: float = 0.0):
    """(placed, errors) of a 1 mm fill of the slab from `bottom` to `top`, left of `right`, among the plates
    `quads`."""
    save(tmp_path / "plates.stl", quads)
    group = {"name": "bed", "material": "sand", "diameter": 0.001, "skip_pockets": skip,
             "region": {"min": [0.0, 0.0, bottom], "max": [right, DEPTH, top]}}
    raw = {"domain": {"min": [0.0, 0.0, 0.0], "max": [W, DEPTH, 0.25], "periodic": ["y"]},
           "materials": {"sand": {"density": 2600.0, "youngs_modulus": 1e7}},
           "particles": [group], "meshes": [{"file": "plates.stl"}]}
    scene = validate(raw).scene
    walls, errs = load_mesh_walls(scene, tmp_path / "scene.toml", "sand")
    assert errs == []
    return place_groups(scene, [], [], [W, DEPTH, 0.25], (False, True, False), walls)


def fill(tmp_path, quads, skip: bool):
    """The sites of `place`'s fill below 70 mm."""
    placed, errors = place(tmp_path, quads, skip)
    assert errors == [], errors
    return placed.x0


def test_a_wedge_is_filled_between_its_plates_and_its_pockets_stay_empty(tmp_path):
    """The plates lean from the slot's edges to the side walls and close the two pockets behind them, even
    where the region's top (70 mm) cuts across them: with `skip_pockets` every site lies between the plates,
    and every site between them is kept (the fill without it, less those behind the plates, whose number is
    reported)."""
    x0 = (W - SLOT) / 2
    quads = [((x0, 0.0), (0.0, TOP)), ((W - x0, 0.0), (W, TOP))]
    placed, _ = place(tmp_path, quads, True)
    kept, every = placed.x0, fill(tmp_path, quads, False)
    def between(x):
        return np.abs(x[:, 0] - W / 2) < SLOT / 2 + x0 * x[:, 2] / TOP

    assert (~between(every)).sum() > 0.5 * len(every)  # the pockets hold more than half of the plain fill
    assert between(kept).all() and len(kept) == between(every).sum()  # (the sites' jitter differs)
    assert placed.pocket_sites == {0: len(every) - len(kept)}  # reported by `tidem check`


def test_a_pocket_under_a_lid_is_skipped_and_one_open_above_is_not(tmp_path):
    """A shelf against the left wall (a floor at 20 mm, a rim 20 mm high) is filled, as a pour would fill
    it. With its rim raised to 50 mm and a lid from the rim to the wall, the wall and the plates seal it (no
    closed mesh: no body the fill skips anyway), and it stays empty; without `skip_pockets` it is filled."""
    shelf = [((0.0, 0.02), (0.04, 0.02)), ((0.04, 0.02), (0.04, 0.04))]

    def on_shelf(x):
        return (x[:, 0] < 0.04) & (x[:, 2] > 0.02) & (x[:, 2] < 0.04)

    assert on_shelf(fill(tmp_path, shelf, True)).sum() > 500
    sealed = [shelf[0], ((0.04, 0.02), (0.04, 0.05)), ((0.0, 0.05), (0.04, 0.05))]
    assert on_shelf(fill(tmp_path, sealed, True)).sum() == 0
    assert on_shelf(fill(tmp_path, sealed, False)).sum() > 500
    placed, errors = place(tmp_path, sealed, True, top=0.05, right=0.04, bottom=0.02)  # all pocket
    assert placed is None and errors[0].startswith("particles[0]: the region holds at most 0 particles")
    assert "fill it with 'inside_mesh'" in errors[0]


def test_skip_pockets_needs_a_region():
    raw = {"domain": {"min": [0.0, 0.0, 0.0], "max": [0.1, 0.1, 0.1]},
           "materials": {"sand": {"density": 2600.0, "youngs_modulus": 1e7}},
           "particles": [{"name": "bed", "material": "sand", "diameter": 0.001, "skip_pockets": True,
                          "positions": [[0.05, 0.05, 0.05]]}]}
    with pytest.raises(SceneError, match="'skip_pockets' leaves the pockets of a filled 'region' empty; give"):
        validate(raw)
