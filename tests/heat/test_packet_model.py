"""Schluender's packet model against a hand calculation."""

import pytest

from tidem.heat.packet_model import packet_alpha, tube_residence_time, zehner_schluender_conductivity


def test_zehner_schluender_hand_calculation():
    # quartz 3.0 W/(m K) in air 0.026 W/(m K), porosity 0.4: kappa = 115.38,
    # B = 1.25 * 1.5^(10/9) = 1.9614, N = 1 - B/kappa = 0.98300,
    # k_c = (2/N) [B (kappa-1)/(N^2 kappa) ln(kappa/B) - (B+1)/2 - (B-1)/N] = 11.679,
    # lambda_bed = 0.026 (1 - sqrt(0.6) + sqrt(0.6) * 11.679) = 0.2411 W/(m K)
    assert zehner_schluender_conductivity(3.0, 0.026, 0.4) == pytest.approx(0.2411, rel=1e-3)


def test_packet_alpha_hand_calculation():
    # TA3 tube D = 27 mm at u_ref = 5 mm/s: t = pi 0.027 / (2 * 0.005) = 8.482 s;
    # alpha_S0 = (2/sqrt(pi)) sqrt(0.2411 * 0.6 * 2600 * 800 / 8.482) = 212.5 W/(m^2 K);
    # alpha_c = 0.8 * 537.1 = 429.7 (alpha_WP of 1 mm sand in air, l + h_R = 1.068 um);
    # alpha = 1 / (1/429.7 + 1/212.5) = 142.2 W/(m^2 K)
    ref = packet_alpha(tube_diameter=0.027, speed=0.005, particle_diameter=1e-3, solid_density=2600.0,
                       solid_conductivity=3.0, heat_capacity=800.0, gas_conductivity=0.026, gap=1.068e-6)
    assert ref.residence_time_s == pytest.approx(8.482, rel=1e-3)
    assert ref.penetration_alpha_W_m2K == pytest.approx(212.5, rel=1e-3)
    assert ref.contact_alpha_W_m2K == pytest.approx(429.7, rel=1e-3)
    assert ref.alpha_W_m2K == pytest.approx(142.2, rel=1e-3)


def test_alpha_falls_as_the_square_root_of_the_residence_time_when_the_bulk_limits():
    slow, fast = (packet_alpha(tube_diameter=0.027, speed=u, particle_diameter=1e-3, solid_density=2600.0,
                               solid_conductivity=3.0, heat_capacity=800.0, gas_conductivity=0.026, gap=1.068e-6)
                  for u in (0.0015, 0.006))
    assert fast.penetration_alpha_W_m2K / slow.penetration_alpha_W_m2K == pytest.approx(2.0, rel=1e-9)
    assert slow.alpha_W_m2K < fast.alpha_W_m2K < fast.contact_alpha_W_m2K


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="speed"):
        tube_residence_time(0.027, 0.0)
    with pytest.raises(ValueError, match="porosity"):
        zehner_schluender_conductivity(3.0, 0.026, 1.0)
