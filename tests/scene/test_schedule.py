"""Schedules (`tidem.scene.schedule`): the value at a time, held or ramped, its exact integral (a
moving mesh's angle and offset), the first time it passes a limit, and one clear message per bad
schedule in a scene file."""

import pytest

from tests.conftest import make_scene
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.scene.schedule import Schedule, VectorSchedule, first_above, integral, is_scheduled, value_at


def test_ramp_interpolates_and_holds_its_ends():
    s = Schedule(times=[1.0, 2.0, 4.0], values=[0.0, 2.0, 1.0])
    assert [s.at(t) for t in (0.0, 1.0, 1.5, 2.0, 3.0, 4.0, 9.0)] == [0.0, 0.0, 1.0, 2.0, 1.5, 1.0, 1.0]


def test_hold_steps_at_each_time():
    s = Schedule(times=[0.0, 1.0, 2.0], values=[3.0, 5.0, 4.0], between="hold")
    assert [s.at(t) for t in (0.0, 0.999, 1.0, 1.5, 2.0, 7.0)] == [3.0, 3.0, 5.0, 5.0, 4.0, 4.0]


@pytest.mark.parametrize("between", ["ramp", "hold"])
def test_integral_is_exact_against_a_fine_midpoint_sum(between):
    s = Schedule(times=[0.5, 1.0, 2.5], values=[1.0, -3.0, 2.0], between=between)
    for t in (0.3, 0.75, 1.0, 2.0, 3.0):
        n = 200_000
        h = t / n
        riemann = sum(s.at((i + 0.5) * h) for i in range(n)) * h  # exact for a linear piece, off only at a step
        assert s.integral(t) == pytest.approx(riemann, abs=2 * 4 * h)
    assert s.integral(0.5) == pytest.approx(0.5)  # the first value holds before the first time
    if between == "ramp":  # 0.5 + (1 - 3) / 2 * 0.5 + (-3 + 2) / 2 * 1.5 + 2 * 0.5
        assert s.integral(3.0) == pytest.approx(0.5 - 0.5 - 0.75 + 1.0)
    else:  # 0.5 + 1 * 0.5 - 3 * 1.5 + 2 * 0.5
        assert s.integral(3.0) == pytest.approx(0.5 + 0.5 - 4.5 + 1.0)


def test_between_may_differ_per_interval():
    s = Schedule(times=[0.0, 1.0, 2.0], values=[0.0, 2.0, 5.0], between=["ramp", "hold"])
    assert [s.at(t) for t in (0.5, 1.0, 1.5, 2.0)] == [1.0, 2.0, 2.0, 5.0]
    assert s.integral(3.0) == pytest.approx(1.0 + 2.0 + 5.0)
    assert s.first_above(2.5) == 2.0 and s.first_above(1.0) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="one entry per interval, 2 for 3 times"):
        Schedule(times=[0.0, 1.0, 2.0], values=[0.0, 2.0, 5.0], between=["ramp"])


def test_constant_keys_integrate_to_value_times_time():
    assert integral(2.5, 4.0) == 10.0
    assert integral((1.0, 0.0, -2.0), 0.5) == (0.5, 0.0, -1.0)
    assert value_at(None, 3.0) is None and not is_scheduled(1.0)


def test_first_time_above_a_limit():
    ramp = Schedule(times=[1.0, 3.0], values=[0.0, 4.0])
    assert ramp.first_above(1.0) == pytest.approx(1.5)
    assert ramp.first_above(4.0) is None
    down = Schedule(times=[0.0, 2.0], values=[0.0, -4.0])
    assert down.first_above(1.0) is None and first_above(down, 1.0) == pytest.approx(0.5)  # by magnitude
    held = Schedule(times=[0.0, 2.0], values=[1.0, 3.0], between="hold")
    assert held.first_above(2.0) == 2.0 and first_above(5.0, 2.0) == 0.0 and first_above(1.0, 2.0) is None
    vec = VectorSchedule(times=[0.0, 1.0], values=[(0.0, 0.0, 0.0), (3.0, 4.0, 0.0)])
    assert vec.at(0.5) == (1.5, 2.0, 0.0) and vec.first_above(2.5) == pytest.approx(0.5, abs=1e-9)


def scene_with(**gas):
    return make_scene(domain={"min": [0, 0, 0], "max": [0.06, 0.06, 0.12], "walls": "auto", "gravity": [0, 0, -9.81]},
                      particles=[{"name": "p", "material": "steel", "diameter": {"value": 0.001},
                                  "positions": [[0.03, 0.03, 0.01]]}],
                      gas={"cell_size": 0.01, **gas})


def test_a_schedule_is_accepted_where_a_number_is():
    loaded = validate(scene_with(inlet_velocity={"times": [0.0, 0.5], "values": [0.1, 0.3], "between": "hold"}))
    assert loaded.scene.gas.inlet_velocity.at(0.6) == 0.3
    assert validate(scene_with(inlet_velocity=0.2)).scene.gas.inlet_velocity == 0.2


@pytest.mark.parametrize("value, message", [
    ({"times": [0.0, 0.5], "values": [0.1]}, "gas.inlet_velocity: 'times' and 'values' need one entry each per point "
                                              "(got 2 times and 1 values)"),
    ({"times": [0.5, 0.5], "values": [0.1, 0.2]}, "gas.inlet_velocity: 'times' must rise strictly (0.5 follows 0.5)"),
    ({"times": [0.0, 1.0], "values": [0.1, -0.2]}, "gas.inlet_velocity.values[1]: must be >= 0 (got -0.2)"),
    ({"times": [0.0], "values": [0.1], "between": "step"}, "gas.inlet_velocity.between: input should be 'ramp' or "
                                                            "'hold' (got 'step')"),
    ({"times": [0.0], "values": [0.1], "value": 1.0}, "gas.inlet_velocity: unknown key 'value'; did you mean 'values'?"),
    ("fast", "gas.inlet_velocity: expected a number, got the text 'fast'"),
])
def test_a_bad_schedule_gets_one_message_naming_the_key(value, message):
    with pytest.raises(SceneError) as err:
        validate(scene_with(inlet_velocity=value))
    assert len(err.value.messages) == 1, err.value.messages
    assert err.value.messages[0].startswith(message), err.value.messages


def test_inlet_ramp_and_a_velocity_schedule_are_not_both_given():
    with pytest.raises(SceneError, match="gas.inlet_ramp: gas.inlet_velocity is a schedule"):
        validate(scene_with(inlet_ramp=0.1, inlet_velocity={"times": [0.0, 1.0], "values": [0.0, 0.2]}))
