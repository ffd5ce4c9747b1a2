"""Pouring, the moving-plate outlet and the recycling outlet: counts and kinematics against
the rates and speeds the scene sets."""

import numpy as np
import pytest

from tests.conftest import make_scene

SAND = {"density": 2600.0, "youngs_modulus": 1e8, "poisson_ratio": 0.3, "restitution": 0.3, "friction": 0.5}


def test_pour_inserts_at_the_set_rate_without_overlap(solver_for):
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.06], "periodic": ["x", "y"], "walls": ["z-"],
                "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "poured", "material": "sand", "count": 200, "seed": 3,
                    "diameter": {"distribution": "uniform", "min": 0.0015, "max": 0.002},
                    "pour": {"region": {"min": [0, 0, 0.04], "max": [0.02, 0.02, 0.06]}, "rate": 2000.0}}],
        numerics={"dt_fraction": 0.2},
    )
    s = solver_for(raw)
    assert s.state.active.to_numpy().sum() == 0
    while s.t < 0.05:
        s.step()
    active = s.state.active.to_numpy().astype(bool)
    assert active.sum() == pytest.approx(2000 * 0.05, abs=3)
    while s.t < 0.15:
        s.step()
    assert s.state.active.to_numpy().sum() == 200, "all poured once count is reached"
    assert s.state.ovl.to_numpy().max() < 0.05


def plate_bed(speed) -> dict:
    """A periodic bed of 2 mm grains on a moving plate that sinks at `speed` (a number or a schedule) from
    t = 0.1 s, from z = 0 down to -0.01 m."""
    return make_scene(
        domain={"min": [0, 0, -0.01], "max": [0.01, 0.01, 0.03], "periodic": ["x", "y"], "walls": "none",
                "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"distribution": "mono", "value": 0.002},
                    "region": {"min": [0, 0, 0], "max": [0.01, 0.01, 0.01]}}],
        outlet={"type": "moving_plate", "speed": speed, "start": 0.1, "height": 0.0, "stop_height": -0.01},
        numerics={"dt_fraction": 0.2},
    )


def test_moving_plate_carries_the_bed_down_at_its_speed(solver_for):
    speed = 0.01
    s = solver_for(plate_bed(speed))
    while s.t < 0.15:
        s.step()
    z0 = s.state.x.to_numpy()[:, 2].mean()
    while s.t < 0.35:
        s.step()
    z1 = s.state.x.to_numpy()[:, 2].mean()
    v = s.state.v.to_numpy()[:, 2]
    assert (z1 - z0) / 0.2 == pytest.approx(-speed, rel=0.05)
    assert np.median(v) == pytest.approx(-speed, rel=0.05)


def test_recycle_outlet_keeps_every_particle(solver_for):
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.01, 0.01, 0.05], "periodic": ["x", "y"], "walls": "none",
                "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "rain", "material": "sand", "diameter": {"distribution": "mono", "value": 0.002},
                    "region": {"min": [0, 0, 0.03], "max": [0.01, 0.01, 0.04]}}],
        outlet={"type": "recycle", "height": 0.005, "reinsert_height": 0.045},
        numerics={"dt_fraction": 0.2},
    )
    s = solver_for(raw)
    n0 = s.state.active.to_numpy().sum()
    seen_low, seen_back = False, False
    while s.t < 0.15:
        s.step()
        z = s.state.x.to_numpy()[:, 2]
        seen_low |= bool((z < 0.01).any())
        seen_back |= bool(((z > 0.044) & (s.state.v.to_numpy()[:, 2] < -0.5)).any())
    assert s.state.active.to_numpy().sum() == n0
    assert seen_low and seen_back, "particles fell through the outlet and re-entered at the top"
    moved = s.outlet_summary()  # counted as they pass, for discharge_rate
    assert moved["discharged_particles"] >= 1
    assert moved["discharged_mass_kg"] == pytest.approx(moved["discharged_particles"] * s.model.mass[0], rel=1e-12)
    assert (s.state.x.to_numpy()[:, 2] >= 0.005 - 0.01).all()


def test_sink_outlet_counts_the_mass_that_leaves(solver_for):
    """Particles raining through a sink: each leaves once, and the mass counted gone plus the mass
    still in the run is the mass at the start (to rounding)."""
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.01, 0.01, 0.05], "periodic": ["x", "y"], "walls": "none",
                "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "rain", "material": "sand", "diameter": {"distribution": "uniform", "min": 0.0015,
                                                                        "max": 0.002},
                    "region": {"min": [0, 0, 0.01], "max": [0.01, 0.01, 0.045]}}],
        outlet={"type": "sink", "height": 0.005},
        numerics={"dt_fraction": 0.2},
    )
    s = solver_for(raw)
    mass = s.model.mass
    total = mass.sum()
    gone = []
    while s.t < 0.12:
        s.advance(20)
        out = s.outlet_summary()
        active = s.state.active.to_numpy().astype(bool)
        ident = s.state.ident.to_numpy()
        assert out["discharged_mass_kg"] + mass[ident[active]].sum() == pytest.approx(total, rel=1e-12)
        assert out["discharged_particles"] + active.sum() == len(mass)
        gone.append(out["discharged_mass_kg"])
    assert 0 < gone[-1] < total and (s.state.x.to_numpy()[active][:, 2] >= 0.005 - 0.002).all()
