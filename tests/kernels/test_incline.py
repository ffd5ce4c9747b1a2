"""A sphere on an inclined wall: rolling without slipping (a = 5/7 g sin), sliding
(a = g (sin - mu cos)) above tan = 3.5 mu, and rolling resistance holding it at rest below
tan = mu_roll (model C). The incline is a floor with gravity tilted by the angle."""

import math

import pytest

from tests.conftest import make_scene

R = 0.005
G = 9.81


def incline(solver_for, tan_angle, mu, mu_roll=0.0, t_settle=0.05, t_end=0.25):
    theta = math.atan(tan_angle)
    raw = make_scene(
        domain={"min": [-1.0, -0.1, -0.1], "max": [1.0, 0.1, 0.1], "walls": ["z-"],
                "gravity": [G * math.sin(theta), 0.0, -G * math.cos(theta)]},
        contact={"model": "linear"},
        materials={"m": {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.3,
                         "friction": mu, "rolling_friction": mu_roll}},
        particles=[{"name": "ball", "material": "m", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0.0, 0.0, -0.1 + R]]}],
        numerics={"dt_fraction": 0.1, "t_end": 1.0},
    )
    s = solver_for(raw)
    while s.t < t_settle:
        s.step()
    t1, v1 = s.t, s.state.v[0][0]
    while s.t < t_end:
        s.step()
    return (s.state.v[0][0] - v1) / (s.t - t1), s.state.v[0][0], theta


def test_rolls_without_slipping_below_3_5_mu(solver_for):
    a, _, theta = incline(solver_for, tan_angle=0.5, mu=0.5)  # 0.5 < 3.5 * 0.5
    assert a == pytest.approx(5.0 / 7.0 * G * math.sin(theta), rel=0.02)


def test_slides_above_3_5_mu(solver_for):
    mu = 0.1
    a, _, theta = incline(solver_for, tan_angle=0.5, mu=mu)  # 0.5 > 3.5 * 0.1
    assert a == pytest.approx(G * (math.sin(theta) - mu * math.cos(theta)), rel=0.02)


def test_rolling_resistance_holds_below_mu_roll(solver_for):
    mu_r = 0.2
    a, v, _ = incline(solver_for, tan_angle=0.98 * mu_r, mu=0.5, mu_roll=mu_r)
    assert abs(v) < 1e-4 and abs(a) < 1e-3, "at rest below tan = mu_roll"


def test_rolling_resistance_gives_way_above_mu_roll(solver_for):
    mu_r = 0.2
    a, v, theta = incline(solver_for, tan_angle=1.02 * mu_r, mu=0.5, mu_roll=mu_r)
    expected = 5.0 / 7.0 * G * (math.sin(theta) - mu_r * math.cos(theta))
    assert v > 1e-3
    assert a == pytest.approx(expected, rel=0.2)
