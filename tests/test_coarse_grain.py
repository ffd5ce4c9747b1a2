"""Coarse-grained parcels (particles[i].coarse_grain = k: a parcel of diameter k d stands for
k^3 grains of diameter d) keep the grains' restitution, terminal velocity and lumped heating
time; combinations whose scaling is not implemented are refused naming the key."""

import math

import pytest

from tests.conftest import make_scene
from tests.kernels.test_gas import MU, RHO_G, SAND, cd_schiller_naumann, nu_ranz_marshall
from tidem.scene.errors import SceneError


def falling(k: float, d: float = 3e-4) -> dict:
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 3.0], "walls": "none", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": d}, "coarse_grain": k,
                    "positions": [[0.01, 0.01, 2.9]]}],
        gas={"cell_size": 0.02, "coupling_interval": 5},
        numerics={"dt": 2e-4, "force_dt": True},
    )


def terminal_velocity(d: float, rho_p: float = 2500.0) -> float:
    """(rho_p - rho_g) V g = C_D(Re) (pi d^2/4) rho_g v^2 / 2 (Schiller-Naumann), by bisection."""
    lo, hi = 0.01, 20.0
    for _ in range(100):
        vt = 0.5 * (lo + hi)
        drag = cd_schiller_naumann(RHO_G * vt * d / MU) * math.pi * d * d / 8 * RHO_G * vt * vt
        lo, hi = (vt, hi) if drag < (rho_p - RHO_G) * math.pi * d**3 / 6 * 9.81 else (lo, vt)
    return vt


def test_a_parcel_falls_at_its_grains_terminal_velocity(solver_for):
    s = solver_for(falling(2.0))
    assert 2 * s.state.radius.to_numpy()[0] == pytest.approx(6e-4), "the parcel is twice the grain"
    while s.t < 1.4:
        s.step()
    v = -s.state.v.to_numpy()[0, 2]
    grain, parcel_sized = terminal_velocity(3e-4), terminal_velocity(6e-4)
    assert parcel_sized > 1.3 * grain, "a grain of the parcel's size would fall clearly faster"
    assert v == pytest.approx(grain, rel=0.02)


def test_a_parcel_heats_in_its_grains_lumped_time(solver_for):
    d, u, t_gas, t_p, k = 2e-3, 1.0, 400.0, 300.0, 2.0
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.1], "walls": "none", "gravity": [0, 0, -9.81]},
        materials={"sand": {**SAND, "heat_capacity": 100.0}},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": d}, "coarse_grain": k,
                    "positions": [[0.01, 0.01, 0.05]], "fixed": True, "temperature": t_p}],
        heat={"gas_conductivity": 0.026, "initial_temperature": t_gas, "fluid_layer": 0.0},
        gas={"cell_size": 0.02, "inlet_velocity": u, "inlet_temperature": t_gas, "coupling_interval": 1},
        numerics={"dt": 1e-3, "force_dt": True},
    )
    s = solver_for(raw)
    for _ in range(3000):
        s.step()
    re = RHO_G * u * d / MU
    h = nu_ranz_marshall(re, 1005.0 * MU / 0.026) * 0.026 / d
    rate = h * math.pi * d * d / (2500 * math.pi * d**3 / 6 * 100.0)  # the grain's H / (m c)
    assert rate * s.t > 1.0, "the test covers most of the heating"
    expected = t_gas - (t_gas - t_p) * math.exp(-rate * s.t)
    assert s.state.T.to_numpy()[0] - t_p == pytest.approx(expected - t_p, rel=0.01)


@pytest.mark.parametrize("law", ["hertz_mindlin", "linear"])
def test_parcels_rebound_with_their_grains_restitution(solver_for, law):
    """Head-on impact of two equal particles at 0.5 m/s each: rebound / impact speed."""
    ratios = []
    for k in (1.0, 2.0):
        d = 1e-3 * k
        raw = make_scene(
            contact={"model": law},
            materials={"sand": {**SAND, "restitution": 0.6}},
            particles=[{"name": "p", "material": "sand", "diameter": {"value": 1e-3}, "coarse_grain": k,
                        "positions": [[-0.51 * d, 0, 0], [0.51 * d, 0, 0]],
                        "velocities": [[0.5, 0, 0], [-0.5, 0, 0]]}],
            numerics={"dt_fraction": 0.02},
        )
        s = solver_for(raw)
        for _ in range(20000):
            s.step()
            if s.state.ncontact.to_numpy()[0] == 0 and s.state.v.to_numpy()[0, 0] < 0.0:
                break
        ratios.append(-s.state.v.to_numpy()[0, 0] / 0.5)
    assert ratios[0] == pytest.approx(0.6, rel=0.02)
    assert ratios[1] == pytest.approx(ratios[0], rel=0.01)


def heated_bed(**group) -> dict:
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.04], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": 1e-3},
                    "region": {"min": [0, 0, 0], "max": [0.02, 0.02, 0.01]}, **group}],
        heat={"gas_conductivity": 0.026, "initial_temperature": 300.0, "fluid_layer": 0.0},
    )


@pytest.mark.parametrize("edit, fragment", [
    ({"coarse_grain": 0.5}, "particles[0].coarse_grain"),
    ({"coarse_grain": float("nan")}, "particles[0].coarse_grain"),
    ({"coarse_grain": 20.0}, "particles[0].coarse_grain"),
    ({"coarse_grain": "2x"}, "particles[0].coarse_grain"),
])
def test_bad_coarse_grain_values_are_named(edit, fragment):
    from tidem.scene.load import validate

    with pytest.raises(SceneError) as err:
        validate(heated_bed(**edit))
    assert fragment in str(err.value)


def test_unscaled_models_with_parcels_are_refused():
    from tidem.scene.load import validate

    raw = heated_bed(coarse_grain=2.0)
    raw["heat"]["fluid_layer"] = 0.4
    raw["domain"]["wall_temperature"] = 350.0
    with pytest.raises(SceneError) as err:
        validate(raw)
    msg = str(err.value)
    assert "particles[0].coarse_grain: heat from walls and tubes (domain.wall_temperature)" in msg
    assert "particles[0].coarse_grain: the gas-lens conduction between parcels is not scaled yet" in msg
    raw["heat"]["fluid_layer"] = 0.0
    del raw["domain"]["wall_temperature"]
    validate(raw)  # contact-spot conduction alone is scaled
