"""The colour range is known before the run: from the scene's temperatures or speed scale."""

import math

import pytest

from tests.conftest import make_scene
from tidem.render.settings import default_range, render_settings
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.sim.model import build_model

STEEL = {"density": 7800.0, "youngs_modulus": 2e9, "poisson_ratio": 0.3, "restitution": 0.5, "friction": 0.3,
         "conductivity": 16.0, "heat_capacity": 500.0}


def model_of(**tables):
    return build_model(validate(make_scene(**tables)))


def test_temperature_range_spans_particles_and_heated_surfaces():
    model = model_of(materials={"steel": STEEL}, heat={"initial_temperature": 300.0},
                     particles=[{"name": "a", "material": "steel", "diameter": {"value": 0.01},
                                 "positions": [[0.0, 0.0, 0.0]]},
                                {"name": "b", "material": "steel", "diameter": {"value": 0.01},
                                 "positions": [[0.05, 0.0, 0.0]], "temperature": 350.0}],
                     tubes=[{"center": [0.0, 0.0, 0.06], "diameter": 0.02, "temperature": 420.0}])
    settings = render_settings(model)
    assert settings["field"] == "temperature"
    assert settings["range"] == [300.0, 420.0]


def test_speed_range_from_initial_speeds_and_free_fall():
    still = model_of(particles=[{"name": "p", "material": "steel", "diameter": {"value": 0.01},
                                 "positions": [[0.0, 0.0, 0.0], [0.05, 0, 0]],
                                 "velocities": [[0.0, 0.0, 0.0], [0.0, 3.0, 4.0]]}])
    assert default_range(still, "speed") == (0.0, 5.0)
    falling = model_of(domain={"gravity": [0.0, 0.0, -9.81]})
    assert default_range(falling, "speed") == pytest.approx((0.0, math.sqrt(2 * 9.81 * 0.2)))


def test_scene_range_wins_and_flat_ranges_are_widened():
    model = model_of(render={"range": [0.0, 0.04]})
    assert render_settings(model)["range"] == [0.0, 0.04]
    lo, hi = default_range(model, "radius")
    assert lo < 0.005 < hi


def test_temperature_colour_needs_heat():
    with pytest.raises(SceneError, match="render.field: 'temperature' needs a \\[heat\\] table"):
        model_of(render={"field": "temperature"})
