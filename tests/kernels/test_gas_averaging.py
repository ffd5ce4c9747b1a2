"""The voidage's averaging length (`gas.averaging_length`, `kernels/gas_smoothing.py`): the filter keeps the
solid volume, spreads a grain to exactly the variance of eq. (1), leaves a packed bed's Ergun gradient, and makes
the voidage the grains of a bed with a bubble see nearly independent of the gas cell. The drag balance with a
length: tests/kernels/test_gas.py."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tests.kernels.test_gas import ergun_gradient, packed_column
from tidem.kernels.gas_smoothing import plan_filter

SAND = {"density": 2500.0, "youngs_modulus": 2e6, "poisson_ratio": 0.3, "restitution": 0.3, "friction": 0.3}
D = 0.001


def fixed_grains(x, cell, length, voidage="layered", tube=False, box=(0.03, 0.004, 0.06)):
    gas = {"cell_size": cell, "inlet_velocity": 0.1, "coupling_interval": 1, "voidage": voidage}
    if length is not None:
        gas["averaging_length"] = length
    return make_scene(domain={"min": [0, 0, 0], "max": list(box), "periodic": ["y"], "walls": "auto",
                              "gravity": [0, 0, -9.81]},
                      materials={"sand": SAND},
                      particles=[{"name": "b", "material": "sand", "diameter": {"value": D}, "fixed": True,
                                  "positions": np.asarray(x).tolist()}],
                      tubes=[{"center": [0.015, 0.0, 0.03], "axis": "y", "diameter": 0.008, "material": "sand"}]
                      if tube else [],
                      gas=gas, numerics={"dt": 1e-5, "force_dt": True})


def lattice_bed(seed=1, keep=0.8, hole=None):
    """Grains on a 1.3 mm lattice filling the box (two across its 4 mm depth), `keep` of them kept at random,
    none within `hole` = (x, z, radius) [m]."""
    g = np.stack(np.meshgrid(np.arange(0.001, 0.0295, 0.0013), [0.001, 0.003], np.arange(0.001, 0.0595, 0.0013),
                             indexing="ij"), -1).reshape(-1, 3)
    if hole is not None:
        g = g[np.hypot(g[:, 0] - hole[0], g[:, 2] - hole[1]) > hole[2]]
    rng = np.random.default_rng(seed)
    return g[rng.random(len(g)) < keep]


def test_the_filter_keeps_the_solid_volume_beside_a_tube(solver_for):
    x = lattice_bed(hole=(0.015, 0.03, 0.0046))
    s = solver_for(fixed_grains(x, 0.003, length=0.012, tube=True))
    s.step()
    assert all(f is not None for f in s.gas.filters[:2])
    grains = len(x) * np.pi / 6 * D**3
    assert s.gas.G.solid_vol.to_numpy().sum() == pytest.approx(grains, rel=1e-12)
    assert s.gas.G.solid_layer.to_numpy().sum() == pytest.approx(grains, rel=1e-12)


def test_one_grain_spreads_to_the_variance_of_the_averaging_length(solver_for):
    """A grain at fraction f of a cell along an axis has deposit variance f (1 - f) h^2 (CIC); the filter adds
    2 tau = L^2 / 12 - h^2 / 3 (eq. 1), exactly while it stays clear of the walls (7 standard deviations here)."""
    h, length = 0.003, 0.015
    x = np.array([[0.0292, 0.002, 0.0296]])
    s = solver_for(fixed_grains(x, h, length=length, voidage="cell", box=(0.06, 0.004, 0.06)))
    s.step()
    vol = s.gas.G.solid_vol.to_numpy()
    gg = s.gas.gg
    for a in (0, 2):
        centres = gg.lo[a] + (np.arange(gg.cells[a]) + 0.5) * gg.h[a]
        w = vol.sum(axis=tuple(b for b in range(3) if b != a)) / vol.sum()
        f = (x[0, a] - centres[0]) / gg.h[a] % 1.0
        variance = (w * (centres - x[0, a]) ** 2).sum()
        assert variance == pytest.approx(f * (1 - f) * gg.h[a] ** 2 + length**2 / 12 - gg.h[a] ** 2 / 3, rel=1e-9)


def test_no_filter_where_the_cells_are_coarser_than_half_the_length():
    assert plan_filter((0.005, 0.005, 0.005), (10, 1, 10), 0.008) is None
    plan = plan_filter((0.003, 0.004, 0.003), (10, 1, 10), 0.012)
    assert plan.lam[1] == 0.0 and plan.steps % 2 == 0 and 2 * sum(plan.lam) <= 0.5


def test_a_packed_beds_gradient_stays_ergun(solver_for):
    s = solver_for(packed_column(0.3))  # the default, 12 d
    for _ in range(30):
        s.step()
    eps = 1 - s.gas.G.solid_vol.to_numpy()[:, :, 1:4].sum() / (0.008 * 0.008 * 0.012)
    gp = -s.gas.G.gp[2].to_numpy()[:, :, 2].mean()
    assert gp == pytest.approx(ergun_gradient(eps, 0.3), rel=0.05)


def seen_voidage(solver_for, x, cell, length):
    s = solver_for(fixed_grains(x, cell, length=length))
    s.step()
    return s.state.geps.to_numpy()[: len(x)][np.argsort(s.state.ident.to_numpy()[: len(x)])]


def test_the_voidage_a_grain_sees_hangs_less_on_the_cell(solver_for):
    """A bed with a 6 mm bubble: the voidage each grain sees on cells of 3 and 5 grain diameters. Over the cells'
    own averaging ("cells") the two differ by it (RMS 0.011); at the default L = 12 d by the remaining shape of the
    kernels only (RMS 0.0027)."""
    x = lattice_bed(hole=(0.015, 0.03, 0.006))
    def rms(length):
        return np.sqrt(np.mean((seen_voidage(solver_for, x, 0.003, length) - seen_voidage(solver_for, x, 0.005, length))**2))

    plain, kept = rms("cells"), rms(None)
    assert kept < 0.4 * plain  # measured: RMS 0.0107 over the cells, 0.0027 at 12 d


def test_cells_average_alone_over_the_cells_own_reach(solver_for):
    s = solver_for(fixed_grains([[0.015, 0.002, 0.02]], 0.003, "cells"))
    assert s.gas.filters == (None, None, None)


def test_the_default_length_is_twelve_diameters_of_the_largest_grain():
    """No key: 12 diameters of the largest grain of any group, the grains of a parcel and not the parcel (so a
    bed of grains and one of k = 3 parcels average alike); "cells": the cells' own averaging; a length given
    holds."""
    from tidem.gas.geometry import averaging_length
    from tidem.scene.load import validate

    raw = packed_column(0.1)
    raw["materials"]["coarse_sand"] = raw["materials"]["sand"]  # parcels: a material of their own k
    raw["particles"].append({"name": "big", "material": "coarse_sand", "diameter": {"value": 0.0015}, "coarse_grain": 1.3,
                             "positions": [[0.004, 0.004, 0.03]]})
    assert averaging_length(validate(raw).scene) == pytest.approx(0.018, rel=1e-12)
    raw["gas"]["averaging_length"] = "cells"
    assert averaging_length(validate(raw).scene) is None
    raw["gas"]["averaging_length"] = 0.02
    assert averaging_length(validate(raw).scene) == 0.02


@pytest.mark.parametrize("voidage", ["layered", "cell"])
def test_the_filtered_drag_balances_beside_a_tube(solver_for, voidage):
    """`gas.drag_averaging = "length"` beside a tube, whose cut faces carry open shares below 1: the drag the gas
    feels, sum_f B_f u_f - Bv_f, is minus the grains' (eqs. (3)-(4) of `kernels/exchange_filter.py`: the read
    through D^-1 A D is the deposit's transpose only with the open shares in D)."""
    x = lattice_bed(hole=(0.015, 0.03, 0.0046))
    raw = fixed_grains(x, 0.003, length=0.012, voidage=voidage, tube=True)
    raw["gas"]["drag_averaging"] = "length"
    s = solver_for(raw)
    for _ in range(3):
        s.step()
    S, G = s.state, s.gas.G
    assert s.gas.filters[2] is not None
    open_face = G.open_face[2].to_numpy()
    assert ((open_face > 0.05) & (open_face < 0.95)).any(), "faces cut by the tube"
    on_particles = (S.gK.to_numpy()[:, None] * (S.gu.to_numpy() - S.v.to_numpy())).sum(axis=0)
    on_gas = np.array([(G.B[c].to_numpy() * G.u[c].to_numpy() - G.Bv[c].to_numpy()).sum() for c in range(3)])
    assert abs(on_particles[2]) > 1e-5, "the grains hold the gas back"
    assert on_gas == pytest.approx(on_particles, rel=1e-9, abs=1e-14)


def test_one_grains_drag_spreads_to_the_variance_of_the_averaging_length(solver_for):
    """`gas.drag_averaging = "length"`: a grain's drag coefficient on the vertical faces, B_z, has the CIC deposit's
    variance f (1 - f) h^2 plus 2 tau = L^2 / 12 - h^2 / 3 along each axis (eq. (3) of `kernels/exchange_filter.py`,
    eq. (1) of `kernels/gas_smoothing.py`), and its total is the grain's K_p."""
    h, length = 0.003, 0.015
    x = np.array([[0.0292, 0.002, 0.0296]])
    raw = fixed_grains(x, h, length=length, voidage="cell", box=(0.06, 0.004, 0.06))
    raw["gas"]["drag_averaging"] = "length"
    s = solver_for(raw)
    s.step()
    b = s.gas.G.B[2].to_numpy()
    assert b.sum() == pytest.approx(s.state.gK.to_numpy()[0], rel=1e-12)
    gg = s.gas.gg
    for a in (0, 2):
        points = gg.lo[a] + (np.arange(b.shape[a]) + (0.0 if a == 2 else 0.5)) * gg.h[a]
        w = b.sum(axis=tuple(c for c in range(3) if c != a)) / b.sum()
        f = (x[0, a] - points[0]) / gg.h[a] % 1.0
        variance = (w * (points - x[0, a]) ** 2).sum()
        assert variance == pytest.approx(f * (1 - f) * gg.h[a] ** 2 + length**2 / 12 - gg.h[a] ** 2 / 3, rel=1e-9)
