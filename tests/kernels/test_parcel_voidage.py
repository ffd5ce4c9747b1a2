"""The voidage a parcel sees on layers one grain high (`gas.parcel_voidage = "grain_layers"`,
`kernels/layered_voidage.py`): its volume stands in rows of its grains, each row the sphere's volume between
its planes (eq. (1)), and its own share of what it reads back is eq. (2)."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tests.kernels.test_gas_voidage import SAND

D_GRAIN, K = 0.001, 3
L = (0.012, 0.012, 0.06)


def parcels(positions, parcel_voidage="grain_layers", averaging="cells") -> dict:
    return make_scene(domain={"min": [0, 0, 0], "max": list(L), "periodic": ["x", "y"], "walls": ["z-"],
                              "gravity": [0, 0, -9.81]}, materials={"sand": SAND},
                      particles=[{"name": "p", "material": "sand", "diameter": {"value": D_GRAIN}, "coarse_grain": K,
                                  "fixed": True, "positions": positions}],
                      gas={"cell_size": 0.006, "parcel_voidage": parcel_voidage, "averaging_length": averaging},
                      contact={"parcel_restitution": "grains"}, numerics={"dt": 1e-4, "force_dt": True})


def cap_share(u: float) -> float:
    """The share of a sphere's volume below u radii from its centre: the spherical cap pi h^2 (3 r - h) / 3."""
    h = 1.0 + u
    return h * h * (3.0 - h) / 4.0


@pytest.mark.parametrize("averaging", ["cells", None])
def test_a_parcels_volume_stands_on_grain_high_layers_in_rows_of_the_spheres_slices(solver_for, averaging):
    """A parcel of k = 3 (3 mm) centred on a 1 mm layer: its three rows sit on three layers' centres, so the
    layers (summed across, which the averaging-length filter keeps) hold the sphere's slices between
    z - r, z - r/3, z + r/3 and z + r: 7/27, 13/27, 7/27 of its volume, to round-off."""
    s = solver_for(parcels([[0.0031, 0.0047, 0.0125]], averaging=averaging))
    assert s.gas.layers == 6  # 6 mm cells, 1 mm grains; parcel_layers: 2
    vp = np.pi / 6 * (K * D_GRAIN) ** 3
    held = s.gas.G.solid_layer.to_numpy().sum(axis=(0, 1)) / vp
    expected = np.zeros_like(held)
    expected[11:14] = [cap_share(-1 / 3), cap_share(1 / 3) - cap_share(-1 / 3), 1 - cap_share(1 / 3)]
    print(f"layers 10-14 hold {held[10:15]} of the parcel's volume")
    assert expected[11:14] == pytest.approx([7 / 27, 13 / 27, 7 / 27], rel=1e-12)
    assert held == pytest.approx(expected, abs=1e-12)


def test_a_lone_parcel_in_rows_sees_the_cell_voidage(solver_for):
    """Alone in its cells (S0 = 1) a parcel reads its own volume at the cell scale: its rows' voidage less its own
    share of eq. (2) is 1, so it sees what gas.voidage = "cell" gives, to round-off, at any height: on the floor
    (its lowest row below the first layer's centre, where the weights fold back), its rows on layers' centres,
    between two; three parcels over two cells apart, over the cells' own averaging."""
    lone = [[0.0031, 0.0047, 0.00145], [0.0031, 0.0047, 0.0205], [0.0089, 0.0023, 0.0401]]
    seen = {}
    for voidage in ("cell", "layered"):
        raw = parcels(lone)
        raw["gas"]["voidage"] = voidage
        s = solver_for(raw)
        s.gas.step(s.t)
        seen[voidage] = s.state.geps.to_numpy()[: len(lone)]
    print(f"seen: {seen}")
    assert (seen["cell"] < 1.0).all()
    assert seen["layered"] == pytest.approx(seen["cell"], rel=1e-12)
