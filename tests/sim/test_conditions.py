"""Conditions that follow a schedule in a run (`tidem.sim.conditions`, `tidem.gas.phase.set_inlet`): a
step in the inlet velocity moves the pressure drop to Ergun's at the new velocity and fluidizes a
settled bed, a ramped drum turns through the ramp's exact angle, a step in a heated wall's
temperature reaches the heat flow at the next conduction evaluation, a resumed run is the unbroken
run bit for bit, and a schedule that would pass a stability limit is refused with the time."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene
from tests.kernels.test_gas import RHO_G, ergun_gradient, fluid_bed, packed_column, wen_yu_umf
from tests.kernels.test_heat import STEEL, R
from tests.runner.test_checkpoint import snapshots
from tests.walls.test_mesh_runs import drum
from tidem.runner import checkpoint
from tidem.runner.loop import run
from tidem.runtime.startup import restart
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.sim.model import build_model


def held(times, values):
    return {"times": times, "values": values, "between": "hold"}


def column_gradient(s):
    p = s.gas.G.p.to_numpy().mean(axis=(0, 1))
    eps = s.gas.G.eps.to_numpy().mean(axis=(0, 1))
    return (p[1] - p[4]) / (3 * 0.004), eps[1:5].mean()


def test_a_step_in_inlet_velocity_moves_the_packed_bed_pressure_gradient_to_ergun(solver_for):
    """Fixed bed: 0.05 m/s for 10 steps, then 0.3 m/s; each gradient within 5 % of Ergun's at its velocity
    (the gas step takes the new velocity at the first gas step after the switch)."""
    s = solver_for(packed_column(held([0.0, 0.001], [0.05, 0.3])))
    for _ in range(9):
        s.step()
    grad, eps = column_gradient(s)
    assert grad == pytest.approx(ergun_gradient(eps, 0.05) + RHO_G * 9.81, rel=0.05)
    for _ in range(21):
        s.step()
    grad, eps = column_gradient(s)
    assert grad == pytest.approx(ergun_gradient(eps, 0.3) + RHO_G * 9.81, rel=0.05)


def test_a_step_in_inlet_velocity_fluidizes_a_settled_bed(solver_for):
    """Half Wen-Yu's u_mf for 0.1 s: the bed rests, its pressure drop short of its weight per area (Ergun
    below u_mf). Then 1.5 u_mf: the gas lifts the bed (the pressure drop reaches its weight; this
    16 mm column slugs, so it swings about it) and the bed expands (its top rises by more than a grain
    diameter on average)."""
    umf = wen_yu_umf()
    s = solver_for(fluid_bed(held([0.0, 0.1], [0.5 * umf, 1.5 * umf])))
    weight = float(s.model.mass.sum()) * 9.81 / (0.016 * 0.004)
    rows = []
    while s.t < 0.25:
        for _ in range(50):
            s.step()
        rows.append((s.t, s.gas.pressure_drop() - RHO_G * 9.81 * 0.06, np.percentile(s.state.x.to_numpy()[: s.n, 2], 99)))
    t, dp, top = (np.array(c) for c in zip(*rows))
    before, after = (t > 0.05) & (t <= 0.1), t > 0.1
    print(f"dp/weight before {dp[before].max() / weight:.2f} (max), after {dp[after].max() / weight:.2f} (max); "
          f"top before {1e3 * top[before].mean():.2f} mm, after {1e3 * top[after].mean():.2f} mm (means)")
    assert dp[before].max() < 0.7 * weight
    assert dp[after].max() > weight
    assert top[after].mean() > top[before].mean() + 0.001


def test_a_ramped_drum_turns_through_the_ramp_angle(tmp_path, solver_for):
    """Speed 0 -> 6 rad/s over 20 ms, then held: each triangle of the drum sits where the exact integral
    of the ramp puts it (150 t^2 rad on the ramp, then 0.06 rad + 6 (t - 0.02)), and the contact kernels'
    wall velocity is the scheduled speed's."""
    raw = drum(tmp_path, 0.04)
    raw["meshes"][0]["rotation"]["speed"] = {"times": [0.0, 0.02], "values": [0.0, 6.0]}
    s = solver_for(raw)
    mesh = s.model.meshes[0]
    angle = {0.01: 0.5 * 300.0 * 0.01**2, 0.03: 0.5 * 6.0 * 0.02 + 6.0 * 0.01}  # ramp 300 rad/s^2
    for t_check, expected in angle.items():
        while s.t < t_check - 0.5 * s.dt:
            s.step()
        assert mesh.angle_at(s.t) == pytest.approx(expected + (s.t - t_check) * mesh.speed_at(t_check), abs=1e-6)
        tri = s.state.tri_v.to_numpy()
        rest = s.model.mesh_table.at(s.model.meshes, s.t)
        assert np.abs(tri - rest).max() < 1e-12
        v0 = (tri[0, 0] - np.asarray(mesh.center)) * [1.0, 0.0, 1.0]  # across the axis (y)
        r0 = (s.model.mesh_table.rest[0, 0] - np.asarray(mesh.center)) * [1.0, 0.0, 1.0]
        turned = math.atan2(np.cross(r0, v0)[1], r0 @ v0)
        assert turned == pytest.approx(mesh.angle_at(s.t), abs=1e-9)
        omega = s.state.mesh_motion.to_numpy()[0, 1]
        assert omega[1] == pytest.approx(mesh.speed_at(s.t), rel=1e-12)


def test_a_heated_wall_temperature_step_reaches_the_heat_flow_within_one_conduction_interval(solver_for):
    """A fixed sphere pressed into a wall at 400 K; at t = 0.5 ms the wall drops to 250 K. With conduction
    every 5 steps the heat flow into the sphere is h (400 K - T) up to the step and h (250 K - T) from the
    first evaluation after it, at most 5 steps later."""
    overlap = 1e-5
    raw = make_scene(
        domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "walls": ["z-"],
                "wall_temperature": held([0.0, 5e-4], [400.0, 250.0]), "gravity": [0, 0, 0]},
        materials={"steel": STEEL},
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0, 0, -0.1 + R - overlap]], "temperature": 300.0, "fixed": True}],
        heat={"gas_conductivity": 0.03, "gas_mean_free_path": 7e-8, "roughness": 2e-6, "conduction_interval": 5},
        numerics={"dt": 1e-4, "force_dt": True},
    )
    s = solver_for(raw)
    seen = []
    for _ in range(12):
        s.step()
        seen.append((s.steps, float(s.state.surf_rate.to_numpy()[0]), float(s.state.T.to_numpy()[0])))
    h = seen[0][1] / (400.0 - 300.0)
    for step, rate, temp in seen:
        wall = 400.0 if step < 6 else 250.0  # evaluations at steps 1, 6, 11; the wall steps at step 5
        assert rate == pytest.approx(h * (wall - temp), rel=1e-3), step


def test_an_outlet_plate_follows_its_speed_schedule(solver_for):
    """A moving plate that sinks at 10 mm/s from t = 0.1 s and at 20 mm/s from t = 0.25 s carries the bed
    down at each speed (as the constant plate does: tests/particles/test_inflow_outflow.py); its height
    is the integral of the schedule."""
    from tests.particles.test_inflow_outflow import plate_bed
    from tidem.walls.surfaces import plate_z

    s = solver_for(plate_bed(held([0.0, 0.25], [0.01, 0.02])))
    plate = next(p for p in s.model.planes if p["name"] == "outlet plate")
    assert plate_z(plate, 0.3) == pytest.approx(-0.01 * 0.15 - 0.02 * 0.05, rel=1e-12)
    heights = {}
    for t_mark in (0.15, 0.25, 0.3, 0.4):
        while s.t < t_mark:
            s.step()
        heights[t_mark] = s.state.x.to_numpy()[:, 2].mean()
    assert (heights[0.25] - heights[0.15]) / 0.1 == pytest.approx(-0.01, rel=0.05)
    assert (heights[0.4] - heights[0.3]) / 0.1 == pytest.approx(-0.02, rel=0.05)
    assert np.median(s.state.v.to_numpy()[:, 2]) == pytest.approx(-0.02, rel=0.05)


def test_resuming_in_the_middle_of_schedules_gives_the_unbroken_run(tmp_path):
    """A drum whose speed ramps and whose wall temperature steps, checkpointed between the ramp's points,
    resumes to the same snapshots and time series as the unbroken run, bit for bit (float64)."""
    def scene(t_end):
        raw = drum(tmp_path, t_end)
        raw["meshes"][0]["rotation"]["speed"] = {"times": [0.0, 0.03], "values": [1.0, 8.0]}
        raw["meshes"][0]["temperature"] = held([0.0, 0.025], [400.0, 450.0])
        return raw

    whole, half = tmp_path / "whole", tmp_path / "half"
    assert run(build_model(validate(scene(0.04))), whole, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    assert run(build_model(validate(scene(0.02))), half, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    meta, arrays = checkpoint.load(half)
    assert run(build_model(validate(scene(0.04))), half, progress=False, resume=(meta, arrays)).status == "finished"
    sa, sb = snapshots(whole), snapshots(half)
    assert len(sa) == len(sb) == 5
    for (pa, da), (pb, db) in zip(sa, sb):
        assert np.array_equal(pa, pb) and all(np.array_equal(da[k], db[k]) for k in da)
    assert (whole / "timeseries.csv").read_text() == (half / "timeseries.csv").read_text()
    for i in range(5):  # the mesh files carry the scheduled temperature of their time
        assert (whole / f"meshes/mesh0_{i:05d}.vtp").read_bytes() == (half / f"meshes/mesh0_{i:05d}.vtp").read_bytes()


def test_an_inlet_schedule_past_the_gas_courant_limit_is_refused_with_its_time():
    raw = packed_column(0.3)
    raw["gas"]["inlet_velocity"] = {"times": [0.0, 1.0], "values": [0.1, 200.0]}
    with pytest.raises(SceneError, match=r"gas.coupling_interval: .* that gas.inlet_velocity reaches at t = 0\.\d+ s "
                                         r"on its schedule .* or keep gas.inlet_velocity below"):
        build_model(validate(raw))


def test_a_drum_schedule_too_fast_for_the_step_is_refused_with_its_time(tmp_path):
    raw = drum(tmp_path, 0.04)
    raw["meshes"][0]["rotation"]["speed"] = {"times": [0.0, 1.0], "values": [4.0, 4000.0]}
    with pytest.raises(SceneError, match=r"meshes\[0\]: a particle could close .* from t = 0\.\d+ s on \(its schedule\)"):
        build_model(validate(raw))
