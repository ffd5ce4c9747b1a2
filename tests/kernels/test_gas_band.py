"""The direct pressure solve of thin gas grids (banded Cholesky, `kernels/gas_band.py`) against the
conjugate gradients it replaces: the same pressure to the CG's tolerance, on grids with solid
(tube) cells, a two-cell periodic axis and a wrapping axis inside the band."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.kernels.gas_grid import GasGrid

SAND = {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.9, "friction": 0.3}


def bubbling_slab(depth, periodic):
    """A 32 x depth x 48 mm slab of 1 mm grains with an 8 mm tube, air at 1 m/s on 4 mm cells."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.032, depth, 0.048], "periodic": periodic, "walls": "auto",
                "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": 0.001},
                    "region": {"min": [0, 0, 0], "max": [0.032, depth, 0.012]}}],
        tubes=[{"center": [0.016, 0.0, 0.03], "axis": "y", "diameter": 0.008}],
        gas={"cell_size": 0.004, "inlet_velocity": 1.0, "coupling_interval": 5},
        numerics={"max_overlap": 0.1},
    )


@pytest.mark.parametrize("depth, periodic", [(0.008, ["y"]), (0.004, ["x", "y"])])
def test_direct_pressure_solve_is_the_cg_solution(solver_for, depth, periodic):
    """After 100 steps of a bubbling slab (its pressure solved directly every gas step: 0 iterations),
    the direct solve of one pressure system and the CG run from p = 0 to a relative residual of 1e-13
    agree to 1e-9 of the largest pressure, and the direct solve's own residual is
    round-off (1e-11 of |b|). Grids: 8 x 2 x 12 cells periodic in y (each cell coupled twice to its
    one neighbour across), and 8 x 1 x 12 periodic in x (the wrap couples cells 7 apart)."""
    s = solver_for(bubbling_slab(depth, periodic))
    g, f, G = s.gas, s.gas.flow, s.gas.G
    assert g.band == 8 * round(depth / 0.004)
    assert (g.solid == 1).any(), "the tube's cells are solid"
    for _ in range(100):
        s.step()
    assert g.iterations == 0 and g.residual < 1e-11
    bb = f["assemble"](g.dt)  # the last gas step's system, whose solution G.p holds: the CG starts from 0
    rr = f["band_solve"]()
    direct = G.p.to_numpy()
    assert 0.0 <= math.sqrt(rr) <= 1e-11 * math.sqrt(bb)
    G.p.fill(0.0)
    g.band, g.tol = 0, 1e-13
    g._project(g.dt)
    assert g.iterations > 10
    fluid = g.solid == 0
    cg = G.p.to_numpy()[fluid]
    assert np.abs(direct[fluid] - cg).max() <= 1e-9 * np.abs(cg).max()


def test_a_singular_system_falls_back_to_the_cg(solver_for):
    """With the outlet closed the pressure is defined only up to a constant (M is singular): the
    direct solve reports it (-1) and leaves p alone. A gas step whose direct solve reports that solves
    by CG, and keeps the CG from then on."""
    from tidem.kernels.gas_grid import CLOSED, OUTLET

    s = solver_for(bubbling_slab(0.004, ["y"]))
    g, f, G = s.gas, s.gas.flow, s.gas.G
    s.step()
    kinds = G.kind[2].to_numpy()
    G.kind[2].from_numpy(np.where(kinds == OUTLET, CLOSED, kinds))
    f["assemble"](g.dt)
    before = G.p.to_numpy()
    assert f["band_solve"]() == -1.0
    assert np.array_equal(G.p.to_numpy(), before)
    G.kind[2].from_numpy(kinds)
    f["band_solve"] = lambda: -1.0
    g._project(g.dt)
    assert g.band == 0 and g.iterations > 0 and g.residual <= g.tol


def test_band_width_takes_thin_grids_on_the_cpu(monkeypatch):
    """The band is the cells across the longest axis; wide bands, a wrapping slowest axis and the GPU
    keep the CG."""
    import tidem.kernels.gas_band as gas_band

    def grid(cells, periodic=(False, False, False)):
        return GasGrid((0.0, 0.0, 0.0), cells, (0.004, 0.004, 0.004), periodic)

    assert gas_band.band_width(grid((20, 1, 50), (False, True, False))) == 20  # fluidized_tube
    assert gas_band.band_width(grid((18, 2, 100))) == 36  # pseudo2d_bubbling_bed
    assert gas_band.band_width(grid((50, 1, 20))) == 20  # wide and low: x numbered slowest
    assert gas_band.band_width(grid((50, 1, 20), (True, False, False))) == 0  # x wraps: outside the band
    assert gas_band.band_width(grid((9, 9, 22))) == 0  # lab_fluidized_bundle: 81 across
    monkeypatch.setattr(gas_band, "in_order", lambda: False)
    assert gas_band.band_width(grid((20, 1, 50))) == 0
