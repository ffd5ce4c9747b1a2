"""Schumann's series against direct quadrature of its Bessel-integral form, its limits and
its heat balance; source 4's explicit scheme converges to it and enforces its limits."""

import numpy as np
import pytest

from tidem.analytic.kruczek import explicit_profiles
from tidem.analytic.packed_bed import PackedBed
from tidem.analytic.schumann import gas_temperature, schumann_theta, solid_temperature

BED = PackedBed(ha=35000.0, rho_c_solid=1.48e6, g_c=555.0, rho_c_gas=370.0, t_in=500.0, t_0=298.0)


def theta_quadrature(xi, eta, n=20000):
    """exp(-xi) int_0^eta exp(-tau) I0(2 sqrt(xi tau)) dtau by Simpson's rule (np.i0)."""
    tau = np.linspace(0.0, eta, n + 1)
    f = np.exp(-xi - tau) * np.i0(2.0 * np.sqrt(xi * tau))
    w = np.ones(n + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    return float((w * f).sum() * eta / n / 3.0)


@pytest.mark.parametrize("xi, eta", [(1.0, 1.0), (5.0, 3.0), (10.0, 10.0), (25.0, 9.8), (30.0, 40.0), (2.0, 0.1)])
def test_series_equals_the_bessel_integral(xi, eta):
    solid = theta_quadrature(xi, eta)
    gas = solid + np.exp(-xi - eta) * np.i0(2.0 * np.sqrt(xi * eta))
    assert schumann_theta(xi, eta) == pytest.approx(solid, abs=1e-12)
    assert schumann_theta(xi, eta, gas=True) == pytest.approx(gas, abs=1e-12)


def test_limits():
    eta = np.array([0.1, 1.0, 5.0])
    assert schumann_theta(0.0, eta) == pytest.approx(1.0 - np.exp(-eta), abs=1e-14)  # inlet layer: lumped
    assert schumann_theta(0.0, eta, gas=True) == pytest.approx(1.0)
    assert schumann_theta(3.0, -1.0) == 0.0  # before the gas arrives
    assert schumann_theta(5.0, 400.0) == pytest.approx(1.0, abs=1e-12)
    assert 0.0 < schumann_theta(1000.0, 990.0) < 1.0  # large arguments stay finite


def test_heat_stored_equals_heat_delivered():
    """Over a bed long enough to hold the whole front: rho_c_solid int (T_s - T_0) dz (+ the gas
    holdup) = G c_g (T_in - T_0) t minus what leaves (nothing)."""
    t = 200.0
    z = np.linspace(0.0, 0.6, 12001)
    stored = np.trapezoid(BED.rho_c_solid * (solid_temperature(BED, z, t) - BED.t_0)
                          + BED.rho_c_gas * (gas_temperature(BED, z, t) - BED.t_0), z)
    assert gas_temperature(BED, 0.6, t) - BED.t_0 < 1e-4  # nothing leaves the bed
    assert stored == pytest.approx(BED.g_c * (BED.t_in - BED.t_0) * t, rel=1e-3)


def test_explicit_scheme_converges_to_schumann():
    bed = PackedBed(**{**BED.__dict__, "rho_c_gas": 0.0})  # the scheme has no gas holdup
    z = np.linspace(0.0, 0.2, 41)
    exact = solid_temperature(bed, z, 160.0)
    errors = [np.abs(explicit_profiles(bed, 0.3, [160.0], z, elements=n, dt_fraction=f)[0] - exact).max()
              for n, f in ((100, 0.2), (400, 0.05), (1600, 0.0125))]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.005 * (bed.t_in - bed.t_0)


def test_explicit_scheme_refuses_coarse_elements():
    with pytest.raises(ValueError, match="eq. 12"):
        explicit_profiles(BED, 0.3, [10.0], [0.0], elements=10)
