"""Heat passed in one Hertzian impact: the analytic estimates of tidem.heat.impact_conduction, and a
simulated impact against the quasi-static integral."""

import math

import pytest

from tests.conftest import make_scene
from tidem.heat.impact_conduction import (CONTACT_TIME_FACTOR, SPOT_INTEGRAL_FACTOR, hertz_impact,
                                          quasi_static_impact_heat, sun_chen_impact_heat)
from tidem.particles.timestep import hertz_contact_time

# SUS304 spheres of source 1: d = 19.1 mm, 7729.6 kg/m^3, E = 184.365 GPa, nu = 0.305
R, RHO, E, NU, K, C = 0.00955, 7729.6, 184.365e9, 0.305, 16.2, 500.0
M = RHO * 4 / 3 * math.pi * R**3
E_STAR = E / (2 * (1 - NU**2))


def test_hertz_constants_against_a_numerical_integration():
    """t_c = 2.943 delta_max / v and int a dt = 0.7541 a_max t_c, from the Hertz equation of
    motion m* d2(delta)/dt2 = -4/3 E* sqrt(R*) delta^1.5 integrated with small steps."""
    m, r, v = 1.0, 1.0, 1.0  # and E* = 1

    def acc(delta):
        return -4 / 3 * math.sqrt(r) * delta**1.5 / m

    delta, speed, t, spot, dt = 0.0, v, 0.0, 0.0, 1e-4
    while True:  # velocity Verlet, trapezoidal rule for int a dt
        speed_half = speed + 0.5 * dt * acc(delta)
        new = delta + dt * speed_half
        if new < 0.0:  # release within this step: linear interpolation
            frac = delta / (delta - new)
            t += frac * dt
            spot += 0.5 * frac * dt * math.sqrt(r * delta)
            break
        spot += 0.5 * dt * (math.sqrt(r * delta) + math.sqrt(r * new))
        delta = new
        speed = speed_half + 0.5 * dt * acc(delta)
        t += dt
    impact = hertz_impact(m, r, 1.0, v)
    assert impact.contact_time == pytest.approx(t, rel=1e-4)
    assert spot == pytest.approx(SPOT_INTEGRAL_FACTOR * impact.a_max * impact.contact_time, rel=1e-4)
    assert CONTACT_TIME_FACTOR == pytest.approx(2.943, abs=1e-3)
    assert SPOT_INTEGRAL_FACTOR == pytest.approx(0.7541, abs=1e-4)


def test_sus304_impact_hand_calculation():
    # m* = 14.10 g, R* = 4.775 mm, E* = 1.0163e11 Pa, v = 1.69 m/s:
    # delta_max = (15 m* v^2 / (16 E* sqrt(R*)))^0.4 = 3.107e-5 m; a_max = sqrt(R* delta_max) = 3.852e-4 m;
    # t_c = 2.943 delta_max / v = 5.41e-5 s (= 2.868 (m*^2/(R* E*^2 v))^(1/5));
    # Q_qs = 2 k 0.7541 a_max t_c dT = 2 * 16.2 * 0.7541 * 3.852e-4 * 5.41e-5 * 130 = 6.62e-5 J;
    # sqrt(rho c k) = sqrt(7729.6 * 500 * 16.2) = 7913; Q_SC = 0.87 * 130 * pi a_max^2 sqrt(t_c) * 7913 / 2
    #   = 1.53e-3 J
    impact = hertz_impact(M / 2, R / 2, E_STAR, 1.69)
    assert impact.delta_max == pytest.approx(3.107e-5, rel=2e-3)
    assert impact.a_max == pytest.approx(3.852e-4, rel=2e-3)
    assert impact.contact_time == pytest.approx(hertz_contact_time(M / 2, R / 2, E_STAR, 1.69), rel=1e-3)
    assert quasi_static_impact_heat(K, impact, 130.0) == pytest.approx(6.62e-5, rel=3e-3)
    eff = math.sqrt(RHO * C * K)
    assert sun_chen_impact_heat(impact, 130.0, eff, eff) == pytest.approx(1.53e-3, rel=3e-3)


def test_simulated_impact_passes_the_quasi_static_heat(solver_for):
    """A hot (150 C) and a cold (20 C) elastic SUS304 sphere meet head-on at 1.69 m/s: the heat
    the cold one gains equals 2 k a(t) integrated over the Hertz impact within 0.5 % (measured: 0.1 %)."""
    steel = {"density": RHO, "youngs_modulus": E, "poisson_ratio": NU, "restitution": 1.0, "friction": 0.3,
             "conductivity": K, "heat_capacity": C}
    sphere = {"material": "steel", "diameter": {"distribution": "mono", "value": 2 * R}}
    raw = make_scene(
        materials={"steel": steel},
        particles=[{**sphere, "name": "hot", "positions": [[-R - 1e-5, 0, 0]], "velocities": [[0.845, 0, 0]],
                    "temperature": 423.15},
                   {**sphere, "name": "cold", "positions": [[R + 1e-5, 0, 0]], "velocities": [[-0.845, 0, 0]]}],
        heat={"fluid_layer": 0.0},  # the contact spot only, as the analytic integral
        numerics={"dt_fraction": 0.1},
    )
    s = solver_for(raw)
    impact = hertz_impact(M / 2, R / 2, E_STAR, 1.69)
    while s.t < 1e-5 / 0.845 + 1.3 * impact.contact_time:
        s.step()
    x = s.state.x.to_numpy()
    assert x[1, 0] - x[0, 0] > 2 * R, "the spheres have separated"
    gained = M * C * (s.state.T.to_numpy()[1] - 293.15)
    assert gained == pytest.approx(quasi_static_impact_heat(K, impact, 130.0), rel=0.005)
