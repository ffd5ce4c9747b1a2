"""Live controls without a display (`tidem.runner.controls`, `tidem.runner.steering`): events put in the
queue while a run goes change the inlet velocity (the pressure gradient follows Ergun at the new one), a
drum's speed and a wall's temperature; pause holds the run, step takes exactly one step, resume lets it
go on; a value past a stability limit is refused; every change lands in steering.csv, run.json and
scene_steered.toml, whose run repeats the steered one bit for bit."""

import csv
import json

import numpy as np
import pytest

from tests.kernels.test_gas import RHO_G, ergun_gradient, packed_column
from tests.walls.test_mesh_runs import drum
from tidem.render.plots import plot_timeseries
from tidem.render.series_plots import change_marks
from tidem.runner import checkpoint
from tidem.runner.controls import Controls
from tidem.runner.loop import run
from tidem.runner.steering import SCENE_NAME, controls_for
from tidem.scene.load import load, validate
from tidem.sim.model import build_model


class Script:
    """A stand-in for a window: at each look of the run loop, puts the events whose time has come into
    the queue, and records what it saw (step, time, paused) at each look."""

    def __init__(self, controls: Controls, at: list[tuple[float, str, tuple]]):
        self.controls, self.at, self.seen = controls, list(at), []

    def update(self, solver, paused: bool = False) -> None:
        self.seen.append((solver.steps, solver.t, paused))
        while self.at and solver.t >= self.at[0][0]:
            _t, kind, args = self.at.pop(0)
            getattr(self.controls, kind)(*args)

    def attach(self, controls, steering) -> None:
        assert controls is self.controls

    def close(self) -> None:
        pass


def column(t_end):
    raw = packed_column(0.05)
    raw["numerics"]["t_end"] = t_end
    raw["output"] = {"timeseries_interval": 2e-4, "interval": 1e-3}
    return raw


def gradient(out):
    data = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    return data["time_s"], data["gas_pressure_drop_Pa"]


def test_a_queued_inlet_velocity_step_takes_effect_is_recorded_and_replays(tmp_path):
    controls = Controls()
    script = Script(controls, [(1e-3, "set", ("gas.inlet_velocity", 0.3))])
    steered = tmp_path / "steered"
    result = run(build_model(validate(column(3e-3))), steered, progress=False, view=script, controls=controls)
    assert result.status == "finished"
    (t_change, key, value), = controls.applied
    assert key == "gas.inlet_velocity" and value == 0.3 and 1e-3 <= t_change < 1e-3 + 6e-4
    rows = list(csv.reader(open(steered / "steering.csv")))
    assert rows == [["time_s", "key", "value"], [repr(t_change), key, "0.3"]]
    assert result.summary["steering"] == [{"time_s": t_change, "key": key, "value": 0.3}]

    s = result.summary
    t, dp = gradient(steered)
    eps = 0.4  # the packed column's mean voidage (tests/kernels/test_gas.py); Ergun sets the scale
    before, after = dp[(t > 5e-4) & (t < t_change)], dp[t > t_change + 1e-3]
    assert after.mean() / before.mean() == pytest.approx(
        (ergun_gradient(eps, 0.3) + RHO_G * 9.81) / (ergun_gradient(eps, 0.05) + RHO_G * 9.81), rel=0.1)
    assert s["status"] == "finished"

    replay = load(str(steered / SCENE_NAME))
    assert replay.name == "test_steered"
    meta, _arrays = checkpoint.load(steered)  # the steered run resumes with its steered scene
    checkpoint.check_scene(meta, replay.raw, "float64")
    plan = replay.scene.gas.inlet_velocity
    assert plan.times == [0.0, t_change] and plan.values == [0.05, 0.3] and plan.between == "hold"
    again = tmp_path / "again"
    assert run(build_model(replay), again, progress=False).status == "finished"
    assert (again / "timeseries.csv").read_text() == (steered / "timeseries.csv").read_text()
    for folder in (steered, again):  # the plots mark the change, live or scheduled
        run_json = json.loads((folder / "run.json").read_text())
        assert [t for t, _label in change_marks(run_json)] == [t_change]
    assert {p.name for p in plot_timeseries(steered)} >= {"hydrodynamics.png", "timeseries.png"}


def test_pause_holds_step_takes_one_step_and_resume_goes_on(tmp_path):
    controls = Controls()

    class Stepper(Script):
        def update(self, solver, paused=False):
            super().update(solver, paused)
            if paused and len([s for s in self.seen if s[2]]) in (3, 6):
                controls.step()
            if paused and len([s for s in self.seen if s[2]]) == 9:
                controls.resume()

    script = Stepper(controls, [(1e-3, "pause", ())])
    result = run(build_model(validate(column(2e-3))), tmp_path, progress=False, view=script, controls=controls)
    assert result.status == "finished"
    held = [steps for steps, _t, paused in script.seen if paused]
    first = held[0]
    assert held[:3] == [first] * 3 and held[3:6] == [first + 1] * 3 and held[6:9] == [first + 2] * 3
    assert result.steps == round(2e-3 / 1e-4)


def test_a_value_past_the_courant_limit_is_refused_and_the_run_goes_on(tmp_path):
    controls = Controls()
    model = build_model(validate(column(1e-3)))
    inlet = next(c for c in controls_for(model) if c.key == "gas.inlet_velocity")
    script = Script(controls, [(2e-4, "set", ("gas.inlet_velocity", 2 * inlet.ceiling)),
                               (2e-4, "set", ("tubes[3].temperature", 400.0))])
    assert run(model, tmp_path, progress=False, view=script, controls=controls).status == "finished"
    assert controls.applied == []
    assert controls.messages[0].startswith(f"gas.inlet_velocity = {2 * inlet.ceiling:g} m/s refused: above "
                                           f"{inlet.ceiling:.4g} m/s, the gas Courant limit 0.5")
    assert controls.messages[1].startswith("tubes[3].temperature: not a live control of this run")
    assert not (tmp_path / SCENE_NAME).exists()


def test_a_drum_speed_and_wall_temperature_change_live(tmp_path):
    """The drum's speed and its wall temperature through the queue: from the change on the contact
    kernels see the new speed, the surface table the new temperature, and the mesh turns through the
    angle of the steered schedule."""
    controls = Controls()
    raw = drum(tmp_path, 0.02)
    model = build_model(validate(raw))
    keys = {c.key for c in controls_for(model)}
    assert {"meshes[0].rotation.speed", "meshes[0].temperature"} <= keys
    seen = {}

    class Watch(Script):
        def update(self, solver, paused=False):
            super().update(solver, paused)
            seen[solver.t] = (solver.state.mesh_motion.to_numpy()[0, 1, 1], float(solver.state.surf_T.to_numpy()[-1]))

    script = Watch(controls, [(0.005, "set", ("meshes[0].rotation.speed", -2.0)),
                              (0.005, "set", ("meshes[0].temperature", 500.0))])
    out = tmp_path / "run"
    assert run(model, out, progress=False, view=script, controls=controls).status == "finished"
    t_change = controls.applied[0][0]
    late = [v for t, v in seen.items() if t >= t_change]
    early = [v for t, v in seen.items() if 0 < t < t_change]
    assert all(v == (4.0, 400.0) for v in early) and all(v == (-2.0, 500.0) for v in late)
    mesh = model.meshes[0]
    assert mesh.angle_at(0.02) == pytest.approx(4.0 * t_change - 2.0 * (0.02 - t_change), rel=1e-9)
    replay = load(str(out / SCENE_NAME))
    assert replay.scene.meshes[0].rotation.speed.values == [4.0, -2.0]
    assert replay.scene.meshes[0].file.startswith("/")  # the mesh file found from the run folder
