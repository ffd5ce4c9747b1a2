"""The bed-to-tube correlations against hand calculations for fluidized_tube's bed (1 mm sand,
2500 kg/m3, 800 J/(kg K); air at 20 C: 1.2 kg/m3, 1.8e-5 Pa s, 0.026 W/(m K), 1005 J/(kg K);
U = 1.0 m/s, eps_mf = 0.45), worked on paper to four figures."""

import pytest

from tidem.analytic.fluidized_bed_heat import (cylinder_cross_flow, molerus, packed_bed_wall_convection,
                                               wen_yu_minimum_fluidization, zabrodsky_maximum)

SAND = dict(rho_p=2500.0, c_p=800.0, rho_g=1.2, mu=1.8e-5, k_g=0.026, c_g=1005.0)


def test_wen_yu_minimum_fluidization_of_1_mm_sand():
    """Ar = 90 790, Re_mf = sqrt(1135.7 + 3704) - 33.7 = 35.87, U_mf = Re_mf mu / (rho d)."""
    assert wen_yu_minimum_fluidization(1e-3, 2500.0, 1.2, 1.8e-5) == pytest.approx(0.538, rel=2e-3)


def test_molerus_parts_for_the_default_bed():
    """l_L = (1.8e-5 / (3.132 x 2498.8))^(2/3) = 1.742 um, k_g / l_L = 14 920 W/(m2 K);
    gas-convective Nu 0.165 x 0.886 x 0.0783 / 1.0587 = 0.01081 -> 161.5 W/(m2 K);
    particle-convective 0.125 x 0.55 x 0.722 / 18.3 = 0.00272 -> 40.6 W/(m2 K)."""
    ref = molerus(1.0, 0.538, 0.45, **SAND)
    assert ref.laminar_length == pytest.approx(1.742e-6, rel=2e-3)
    assert ref.gas_convective == pytest.approx(161.5, rel=5e-3)
    assert ref.particle_convective == pytest.approx(40.6, rel=1e-2)
    assert ref.total == pytest.approx(202.0, rel=5e-3)


def test_molerus_particle_part_vanishes_at_minimum_fluidization_and_refuses_below():
    assert molerus(0.538 * (1 + 1e-9), 0.538, 0.45, **SAND).particle_convective < 1e-3
    with pytest.raises(ValueError, match="bubbling bed"):
        molerus(0.5, 0.538, 0.45, **SAND)


def test_zabrodsky_maximum_for_1_mm_sand():
    """35.8 x 2500^0.2 x 0.026^0.6 x 0.001^-0.36 = 35.8 x 4.782 x 0.1119 x 12.02."""
    assert zabrodsky_maximum(0.026, 2500.0, 1e-3) == pytest.approx(230.3, rel=2e-3)


def test_packed_bed_wall_convection_and_the_bare_cylinder():
    """Martin-Nilles flow term at U0 = U_mf: Re_0 = 36.0, 0.19 x 36^0.75 x 0.886 = 2.474,
    x 26 W/(m2 K) per mm; Churchill-Bernstein: Nu = 0.3 at rest, 15.9 at Re = 1000, Pr = 0.696."""
    assert packed_bed_wall_convection(0.54, 1e-3, 1.2, 1.8e-5, 0.026, 1005.0) == pytest.approx(64.3, rel=5e-3)
    assert packed_bed_wall_convection(0.0, 1e-3, 1.2, 1.8e-5, 0.026, 1005.0) == 0.0
    assert cylinder_cross_flow(0.0, 0.696) == pytest.approx(0.3)
    assert cylinder_cross_flow(1000.0, 0.696) == pytest.approx(15.9, rel=5e-3)
