"""The observables registry: each observable on a hand-checkable case, a single impact run
end to end (restitution and kinetic energy against the material's e), and the scene errors
for unknown or impossible observables."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.results import observables as obs
from tidem.scene.errors import SceneError
from tidem.scene.load import load
from tidem.scene.observable_names import NEEDS

runner = CliRunner()
DOC = Path(__file__).resolve().parents[2] / "docs" / "scenes.md"


def lattice_record(u=0.0, spacing=0.002, layers=5, side=10, floor=0.0):
    """A cubic lattice of 1 mm-radius spheres resting on the floor, all sinking at speed u."""
    i, j, k = np.meshgrid(np.arange(side), np.arange(side), np.arange(layers), indexing="ij")
    x = np.stack([i.ravel(), j.ravel(), k.ravel() + 0.5], axis=1) * spacing + [0.0, 0.0, floor]
    n = len(x)
    v = np.tile([0.0, 0.0, -u], (n, 1))
    return obs.RunRecord(time_s=1.0, x=x, v=v, mass=np.full(n, 1e-5), radius=np.full(n, 0.5 * spacing),
                         v0=np.zeros((n, 3)), floor_z=floor)


def test_bed_height_of_a_lattice_is_its_top_layer():
    rec = lattice_record(spacing=0.002, layers=5)
    assert obs.bed_height(rec)["bed_height_m"] == pytest.approx(4.5 * 0.002)


def test_bed_height_time_mean_takes_the_second_half_of_the_column():
    rec = lattice_record(spacing=0.002, layers=5)
    t = np.linspace(0.0, 1.0, 11)
    rec.series = {"time_s": t, "bed_height_m": np.where(t < 0.5, 0.2, 0.05 + 0.01 * (t > 0.75))}
    got = obs.bed_height(rec)
    assert got["bed_height_m"] == pytest.approx(4.5 * 0.002), "the end value stays the end state's"
    assert got["bed_height_mean_m"] == pytest.approx((3 * 0.05 + 3 * 0.06) / 6)
    rec.series = {"time_s": t}  # a series without the column (resumed from a run before it existed)
    assert obs.bed_height(rec)["bed_height_mean_m"] is None


def test_pressure_fluctuation_std_and_frequency_only_with_five_periods():
    """A 2 s record: a 12 Hz sine of 40 Pa amplitude over a drifting 500 Pa has std 40/sqrt(2) and
    12 periods in the second half; at 3 Hz the second half holds 3 periods: no frequency, a note,
    and tradeoff's table keeps only the numbers."""
    rec = lattice_record()
    t = np.linspace(0.0, 2.0, 2001)
    for f, resolved in ((12.0, True), (3.0, False)):
        rec.series = {"time_s": t, "gas_pressure_drop_Pa": 500.0 + 40.0 * np.sin(2 * np.pi * f * t)
                      + np.where(t < 1.0, 300.0 * (1.0 - t), 0.0)}
        got = obs.pressure_fluctuation(rec)
        assert got["pressure_drop_std_Pa"] == pytest.approx(40.0 / np.sqrt(2.0), rel=0.01)
        if resolved:
            assert got["pressure_drop_frequency_Hz"] == pytest.approx(12.0, abs=0.05)
            assert "pressure_drop_frequency_note" not in got
        else:
            assert got["pressure_drop_frequency_Hz"] is None
            assert "fewer than 5" in got["pressure_drop_frequency_note"]
            assert obs.flatten({"pressure_fluctuation": got}) == {"pressure_drop_std_Pa": got["pressure_drop_std_Pa"]}


def test_plug_flow_gives_mass_times_speed_over_height():
    u, floor = 0.02, -0.01
    rec = lattice_record(u=u, spacing=0.002, layers=5, floor=floor)
    # a plug of mass M filling 5 layers of 2 mm sinks at u: M u / (5 x 2 mm) through any section
    expected = rec.mass.sum() * u / (5 * 0.002)
    assert obs.outlet_mass_flow(rec)["outlet_mass_flow_kg_s"] == pytest.approx(expected)


def test_kinetic_energy_restitution_and_temperature_by_hand():
    rec = lattice_record(u=0.5, layers=1, side=2)
    rec.v0 = -rec.v / 0.8  # came in at 0.625 m/s the other way: rebound / impact = 0.8
    rec.temperature = np.array([300.0, 310.0, 320.0, 330.0])
    assert obs.kinetic_energy(rec)["kinetic_energy_J"] == pytest.approx(4 * 0.5 * 1e-5 * 0.25)
    assert obs.restitution(rec)["restitution"] == pytest.approx(0.8)
    assert obs.mean_temperature(rec)["mean_temperature_K"] == pytest.approx(315.0)


def test_time_means_take_the_second_half():
    rec = lattice_record()
    t = np.linspace(0.0, 1.0, 11)
    rec.series = {"time_s": t, "tubes1_heat_W": np.where(t < 0.5, 100.0, 2.0),
                  "gas_pressure_drop_Pa": np.where(t < 0.5, 0.0, 500.0)}
    assert obs.tube_heat(rec) == {"tubes1_heat_W": pytest.approx(2.0)}
    assert obs.pressure_drop(rec)["pressure_drop_Pa"] == pytest.approx(500.0)
    rec.alpha_means = [{"tube": 1, "mean_alpha_W_m2K": 55.0, "averaged_over_s": 1.0}]
    assert obs.tube_mean_alpha(rec) == {"tube1_mean_alpha_W_m2K": 55.0}


def test_single_impact_run_writes_restitution_of_the_material(tmp_path):
    out = tmp_path / "impact"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render",
                                 "--set", "materials.sus304.restitution=0.5", "--set", ('observables=["contact_time", '
                                 '"impact_heat", "restitution", "kinetic_energy", "granular_temperature"]')])
    assert result.exit_code == 0, result.output
    run = json.loads((out / "run.json").read_text())
    found = obs.flatten(run["observables"])
    assert set(run["observables"]) == {"contact_time", "impact_heat", "restitution", "kinetic_energy",
                                       "granular_temperature"}
    # after the impacts each sphere moves off at half its speed; cubes of 6 diameters (114.6 mm from the domain's
    # corner) hold the first two pairs in one cell and the third in the next: n/(n - 1) of each cell's spread
    a, b, c = 0.5 * 0.845, 0.5 * 1.01, 0.5 * 1.125
    theta = (4 / 3 * 2 * (a**2 + b**2) + 2 * 2 * c**2) / (3 * 6)
    assert found["granular_temperature_m2_s2"] == pytest.approx(theta, rel=0.02)
    gains = [row["heat_gained_J"] for row in run["impact_heat"]]
    assert min(gains) < 0 < max(gains), "hot spheres lose what cold ones gain"
    assert found["restitution"] == pytest.approx(0.5, rel=0.01)
    speeds = np.array([0.845, 1.01, 1.125])  # each sphere's initial speed (half the impact speed)
    ke0 = 2 * 0.5 * 2.82e-2 * np.sum(speeds ** 2)
    assert found["kinetic_energy_J"] == pytest.approx(0.25 * ke0, rel=0.02)
    assert found["contact_time_s"] > 0


def test_unknown_and_impossible_observables_are_scene_errors():
    with pytest.raises(SceneError, match="unknown observable 'bed_hieght'; did you mean 'bed_height'"):
        load("sphere_impact", ['observables=["bed_hieght"]'])
    with pytest.raises(SceneError, match="'pressure_drop' needs \\[gas\\]"):
        load("sphere_impact", ['observables=["pressure_drop"]'])


def test_every_observable_is_documented():
    text = DOC.read_text()
    missing = [name for name in obs.OBSERVABLES if not re.search(rf"\| `{name}` \|", text)]
    assert not missing, f"observables missing from docs/scenes.md: {missing}"


def test_every_listed_name_has_a_compute_function():
    assert list(obs.OBSERVABLES) == list(NEEDS)


def test_discharge_rate_is_the_slope_of_the_steady_window():
    """A bin that starts draining at 0.1 s at 2 kg/s until 1 s (empty), after a surge in the first
    quarter: the rate is 2 in both halves of the window; a rate that grows with time (m = t^2) shows
    in the halves."""
    t = np.linspace(0.0, 1.2, 121)
    steady = np.clip(2.0 * (t - 0.1), 0.0, 1.8) + np.clip(0.5 * t, 0.0, 0.1)  # the surge ends at 0.2 s
    rec = obs.RunRecord(time_s=1.2, x=np.zeros((0, 3)), v=np.zeros((0, 3)), mass=np.zeros(0), radius=np.zeros(0),
                        v0=np.zeros((0, 3)), floor_z=0.0, series={"time_s": t, "discharged_mass_kg": steady})
    got = obs.discharge_rate(rec)
    assert got["discharge_rate_kg_s"] == pytest.approx(2.0, rel=1e-9)
    assert got["discharge_rate_early_kg_s"] == pytest.approx(2.0, rel=1e-9)
    assert got["discharge_rate_late_kg_s"] == pytest.approx(2.0, rel=1e-9)
    rec.series["discharged_mass_kg"] = t**2
    got = obs.discharge_rate(rec)
    assert got["discharge_rate_late_kg_s"] > 1.2 * got["discharge_rate_early_kg_s"]


def test_centre_of_mass_of_a_lattice_and_its_time_mean_from_the_potential_energy():
    rec = lattice_record(spacing=0.002, layers=5)
    mass = rec.mass.sum()
    t = np.linspace(0.0, 1.0, 11)
    z_c = np.where(t < 0.5, 0.1, 0.004 + 0.002 * (t > 0.75))
    rec.series = {"time_s": t, "potential_energy_J": mass * 9.81 * z_c}
    got = obs.centre_of_mass(rec)
    assert got["centre_of_mass_m"] == pytest.approx(2.5 * 0.002), "the mean of the layers' centres"
    assert got["centre_of_mass_mean_m"] == pytest.approx((3 * 0.004 + 3 * 0.006) / 6)


def test_granular_temperature_by_hand_and_of_a_maxwellian_gas_in_a_shearing_flow():
    from tidem.results.granular import granular_temperature

    # two particles of 1 kg at +-1 m/s (spread 2, x 2/1); three of 2 kg at 0, 0, 3 m/s (mean 1, spread 12, x 3/2);
    # one alone in its cell (left out)
    x = np.array([[0.1, 0.1, 0.1], [0.2, 0.2, 0.2], [1.1, 0.1, 0.1], [1.2, 0.3, 0.4], [1.5, 0.5, 0.5], [0.5, 1.5, 0.5]])
    v = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 3], [7, 7, 7]])
    m = np.array([1.0, 1, 2, 2, 2, 5])
    assert granular_temperature(x, v, m, np.zeros(3), 1.0, (2, 2, 1)) == pytest.approx((4 + 18) / (3 * 8))
    # velocities of variance theta0 per component about a mean flow that shears with height: the cells' means
    # take the flow out and n/(n - 1) the bias of a mean from few particles (about 5 a cell)
    rng = np.random.default_rng(1)
    x = rng.uniform(0.0, 0.1, (40_000, 3))
    theta0 = 0.01
    v = rng.normal(0.0, np.sqrt(theta0), x.shape) + np.stack([50 * np.floor(x[:, 2] / 0.005) * 0.005, 0 * x[:, 0],
                                                              0 * x[:, 0]], axis=1)
    got = granular_temperature(x, v, rng.uniform(1.0, 2.0, len(x)), np.zeros(3), 0.005, (20, 20, 20))
    assert got == pytest.approx(theta0, rel=0.02)


def test_centre_of_mass_needs_a_closed_bed_under_gravity_along_minus_z():
    from tidem.scene.observable_names import requirement

    scene = load("fluidized_tube").scene
    assert requirement("centre_of_mass", scene) is None
    sideways = scene.model_copy(update={"domain": scene.domain.model_copy(update={"gravity": (9.81, 0.0, 0.0)})})
    assert "gravity along -z" in requirement("centre_of_mass", sideways)
    assert "no [outlet]" in requirement("centre_of_mass", load("hopper_discharge").scene)


def write_heights(folder: Path, times, heights, ids=None) -> list[tuple[float, Path]]:
    """Snapshots at `times` of particles at heights[i] (x = y = 0), ids 0.. unless given; [(time, file)]."""
    from tidem.io.vtp import write_vtp

    out = []
    for i, (t, z) in enumerate(zip(times, heights)):
        n = len(z)
        idx = np.arange(n) if ids is None else ids[i]
        x = np.zeros((n, 3))
        x[:, 2] = z
        path = folder / f"snap_{i:05d}.vtp"
        write_vtp(path, x, {"id": np.asarray(idx, np.int32), "radius": np.full(n, 1e-3)}, time=t)
        out.append((float(t), path))
    return out


def test_dispersion_of_a_random_walk_and_of_ballistic_motion(tmp_path):
    from tidem.results.dispersion import run_dispersion

    times = np.arange(21) * 0.01  # snapshots every 0.01 s to 0.2 s: the second half spans every lag
    rng = np.random.default_rng(3)
    D = 2e-4  # m^2/s: steps of variance 2 D dt, so <dz^2> = 2 D tau at every lag
    walk = np.cumsum(rng.normal(0.0, np.sqrt(2 * D * 0.01), (len(times), 40000)), axis=0)
    found = run_dispersion(write_heights(tmp_path, times, walk), 0.2)
    assert found["dispersion_m2_s"] == pytest.approx(D, rel=0.03)
    # ballistic z = v t: <dz^2> = <v^2> tau^2, whose least-squares slope over 0.02-0.1 s is 0.12 <v^2>; the
    # particles in reverse order, and one more at the rms speed in every other snapshot only, change nothing
    v = np.append(np.linspace(-0.1, 0.1, 50), np.sqrt(np.mean(np.linspace(-0.1, 0.1, 50) ** 2)))
    ids = [np.arange(51 - i % 2)[::-1] for i in range(len(times))]
    heights = [(0.1 + v * t)[idx] for t, idx in zip(times, ids)]
    (tmp_path / "b").mkdir()
    found = run_dispersion(write_heights(tmp_path / "b", times, heights, ids), 0.2)
    assert found["dispersion_m2_s"] == pytest.approx(0.06 * np.mean(v**2), rel=1e-9)
    # snapshots every 0.004 s: only the pairs exactly one lag apart count, not those one snapshot either side
    dense = np.arange(51) * 0.004
    (tmp_path / "c").mkdir()
    found = run_dispersion(write_heights(tmp_path / "c", dense, [0.1 + v * t for t in dense]), 0.2)
    assert found["dispersion_m2_s"] == pytest.approx(0.06 * np.mean(v**2), rel=1e-9)


def test_dispersion_needs_snapshots_one_lag_apart(tmp_path):
    from tidem.results.dispersion import run_dispersion

    times = np.arange(11) * 0.03  # 0.03 s apart: only 0.06 s of the lags is spanned
    found = run_dispersion(write_heights(tmp_path, times, [np.zeros(3)] * len(times)), 0.3)
    assert found["dispersion_m2_s"] is None
    assert "output.interval = 0.02 s or a divisor of it" in found["dispersion_note"]


def test_dispersion_of_a_run_from_its_snapshots(tmp_path):
    # the impact scene's spheres sent along z at constant speeds (softened, so that the step is long; they do
    # not touch): ballistic, D = 0.06 <v^2> (above); the snapshots fall on whole steps near every 0.01 s
    out = tmp_path / "vertical"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render",
                                 "--set", "numerics.t_end=0.2", "--set", "output.interval=0.01",
                                 "--set", "materials.sus304.youngs_modulus=1e7",
                                 "--set", "particles[0].velocities=[[0, 0, 0.1], [0, 0, 0.05], [0, 0, -0.05]]",
                                 "--set", "particles[1].velocities=[[0, 0, -0.1], [0, 0, 0.02], [0, 0, 0]]",
                                 "--set", 'observables=["dispersion"]'])
    assert result.exit_code == 0, result.output
    found = json.loads((out / "run.json").read_text())["observables"]["dispersion"]
    speeds = np.array([0.1, 0.05, 0.05, 0.1, 0.02, 0.0])
    assert found["dispersion_m2_s"] == pytest.approx(0.06 * np.mean(speeds**2), rel=0.01)
