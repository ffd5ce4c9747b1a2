"""End-to-end runs through the CLI: output layout, ParaView-readable snapshots, progress of a
failed or interrupted run, shipped-scene lookup."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.io.vtp import read_vti, read_vtp
from tidem.render.plots import read_series

runner = CliRunner()


def test_impact_scene_output_and_hertz(tmp_path):
    out = tmp_path / "impact"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render"])
    assert result.exit_code == 0, result.output
    run = json.loads((out / "run.json").read_text())
    for key in ("scene_echo", "tidem_version", "active_models", "particles", "steps", "dt_s", "wall_s",
                "particle_steps_per_s"):
        assert key in run
    assert run["status"] == "finished" and run["particles"] == 6
    rows = run["contact_times"]
    for row in rows:
        # Hertz contact time within 2 % (the small damping of e = 0.95 lengthens it slightly)
        assert row["contact_time_s"] == pytest.approx(row["hertz_contact_time_s"], rel=0.02)
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["time_s", "step", "kinetic_energy_J"]
    pvd = (out / "snapshots.pvd").read_text()
    files = sorted((out / "snapshots").glob("*.vtp"))
    assert len(files) == pvd.count("<DataSet") >= 20
    points, data = read_vtp(files[-1])
    assert points.shape == (6, 3)
    assert set(data) >= {"radius", "velocity", "omega", "id"}
    assert np.allclose(data["radius"], 0.00955)


def test_snapshots_open_in_vtk(tmp_path):
    import pyvista as pv

    from tidem.io.vtp import write_vtp

    x = np.random.default_rng(0).random((50, 3))
    write_vtp(tmp_path / "a.vtp", x, {"radius": np.full(50, 0.1), "velocity": x * 2, "id": np.arange(50, dtype=np.int32)},
              time=0.5)
    mesh = pv.read(tmp_path / "a.vtp")
    assert mesh.n_points == 50 and mesh.n_cells == 50
    assert np.allclose(mesh.points, x)
    assert np.allclose(mesh.point_data["velocity"], 2 * x)
    assert list(mesh.point_data["id"]) == list(range(50))


def test_runaway_overlap_stops_with_particle_named(tmp_path):
    """Soft spheres hit hard: the run stops with a message naming the particle, exit 3, and
    the snapshots written before remain readable."""
    out = tmp_path / "soft"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render",
                                 "--set", "materials.sus304.youngs_modulus=1e5",
                                 "--set", "numerics.check_interval=5"])
    assert result.exit_code == 3, result.output
    assert "particle" in result.output and "% of its radius" in result.output
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed"
    for f in (out / "snapshots").glob("*.vtp"):
        read_vtp(f)


def test_ctrl_c_keeps_finished_output(tmp_path, monkeypatch):
    from tidem.sim.solver import Solver

    real_step = Solver._step

    def step(self, drift_next, diag):
        if self.steps == 300:
            raise KeyboardInterrupt
        real_step(self, drift_next, diag)

    monkeypatch.setattr(Solver, "_step", step)
    out = tmp_path / "stop"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render"])
    assert result.exit_code == 130
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "interrupted" and run["steps"] == 300
    listed = (out / "snapshots.pvd").read_text().count("<DataSet")
    assert listed == len(list((out / "snapshots").glob("*.vtp"))) > 0
    assert not list(out.rglob("*.tmp"))


def test_output_folder_removed_during_a_run_is_one_line_not_a_crash(tmp_path, monkeypatch):
    """The output folder deleted while the run goes on, then SIGTERM (the stop flag): the final
    checkpoint and run.json cannot be written; one line names the folder, exit 74, no crash log."""
    import shutil

    from tidem.sim.solver import Solver

    real_step = Solver._step

    def step(self, drift_next, diag):
        if self.steps == 300:
            while out.exists():  # the snapshot writer thread may rename a file under rmtree's feet
                shutil.rmtree(out, ignore_errors=True)
            raise KeyboardInterrupt
        real_step(self, drift_next, diag)

    monkeypatch.setattr(Solver, "_step", step)
    monkeypatch.setenv("TIDEM_LOG_DIR", str(tmp_path / "logs"))
    out = tmp_path / "gone"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render"])
    assert result.exit_code == 74, result.output
    assert "could not write its output" in result.output and str(out) in result.output
    assert not (tmp_path / "logs").exists()


def test_a_stop_asked_while_the_solver_is_built_ends_the_run_before_its_first_step(tmp_path, monkeypatch):
    """SIGTERM (the stop flag) during the set-up: no step taken, status interrupted, exit 130, a
    checkpoint at step 0 (before, the default handler killed the process with nothing said)."""
    from tidem.runner import loop as run_loop

    real_enter = run_loop.StopRequest.__enter__

    def enter(self):
        handled = real_enter(self)
        if self.signal is None:
            self.signal = "SIGTERM"
        return handled

    monkeypatch.setattr(run_loop.StopRequest, "__enter__", enter)
    out = tmp_path / "early"
    result = runner.invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet", "--no-render"])
    assert result.exit_code == 130, result.output
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "interrupted" and run["steps"] == 0
    assert (out / "checkpoint.npz").is_file()


def test_scenes_lists_shipped_with_runtime():
    result = runner.invoke(app, ["scenes"])
    assert result.exit_code == 0
    assert "sphere_impact.toml" in result.output and "moving_bed_tubes.toml" in result.output
    assert "run time:" in result.output


@pytest.mark.parametrize("name, solve", [
    ("fluidized_tube", "pressure solved directly on the CPU (banded Cholesky, half-bandwidth 20 cells), by Jacobi-preconditioned CG"),
    ("lab_fluidized_bundle", "pressure solved by Jacobi-preconditioned CG (tolerance 1e-08, at most")])
def test_check_names_the_pressure_solve(name, solve):
    """`tidem check` says whether a gas scene's pressure is solved directly (a thin grid on the CPU,
    `kernels/gas_band.py`) or by CG."""
    result = runner.invoke(app, ["check", name])
    assert result.exit_code == 0, result.output
    assert solve in result.output, result.output


def test_check_prints_derived_numbers():
    result = runner.invoke(app, ["check", "moving_bed_tubes"])
    assert result.exit_code == 0, result.output
    for word in ("Rayleigh time", "time step", "kernels:", "rolling resistance (model C)", "B/particle",
                 "conduction: every 10 step(s); explicit limit", "(heat.conduction_interval up to 10000)"):
        assert word in result.output


@pytest.mark.parametrize("name", ["sphere_impact.toml", "moving_bed_tubes.toml", "moving_bed_ta1.toml",
                                  "moving_bed_ta2.toml", "fluidized_tube.toml", "char_combustion.toml",
                                  "olefin_polymerization.toml", "plasma_sublimation.toml", "packed_bed_preheat.toml",
                                  "moving_bed_foil.toml", "lab_fluidized_bundle.toml", "hopper_discharge.toml",
                                  "rotary_kiln.toml", "moving_bed_hopper.toml", "pseudo2d_bubbling_bed.toml",
                                  "tube_bank.toml"])
def test_shipped_scene_smoke(tmp_path, name):
    """`tidem scene NAME --smoke` runs output.smoke_steps steps and finishes cleanly."""
    out = tmp_path / name
    result = runner.invoke(app, ["scene", name, "--smoke", "--out", str(out), "--quiet", "--no-render"])
    assert result.exit_code == 0, result.output
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "finished" and 0 < run["steps"] <= 300
    assert (out / "snapshots.pvd").exists()
    if any(m.startswith("gas") for m in run["active_models"]):  # the gas fields go with every snapshot
        vti = sorted((out / "gas").glob("gas_*.vti"))
        assert (out / "gas.pvd").exists() and len(vti) == len(list((out / "snapshots").glob("*.vtp")))
        grid, fields = read_vti(vti[-1])
        eps = fields["voidage"][fields["solid"] == 0]
        assert grid["time"] > 0 and ((eps > 0) & (eps <= 1)).all()
    if name == "lab_fluidized_bundle.toml":  # 700 000 grains as parcels of 27
        assert run["particles"] == 25926 and run["grains_at_start"] == 700002 and run["coarse_grain"] == [3.0]
        _, arrays = read_vtp(sorted((out / "snapshots").glob("*.vtp"))[-1])
        assert (arrays["grains"] == 27.0).all() and len(arrays["grains"]) == 25926
    if name == "rotary_kiln.toml":  # the turning drum's mesh, written at every snapshot, and its heat
        assert len(list((out / "meshes").glob("mesh0_*.vtp"))) == len(list((out / "snapshots").glob("*.vtp")))
        assert read_series(out / "timeseries.csv")["meshes0_heat_W"][-1] > 0.0
    if name == "moving_bed_hopper.toml":  # the hopper mesh written; the sink counts (nothing reaches it so soon)
        assert (out / "meshes.pvd").exists()
        assert read_series(out / "timeseries.csv")["discharged_particles"][-1] == 0.0
    if name == "pseudo2d_bubbling_bed.toml":  # the probes 45 mm up, before the air is on: the gas column above them
        series = read_series(out / "timeseries.csv")
        for probe in ("gas_pressure_z45mm_Pa", "gas_pressure_x45_y4_z45mm_Pa"):
            assert series[probe][0] == pytest.approx(1.28 * 9.81 * (0.5 - 0.045), rel=1e-3)
    if name == "moving_bed_foil.toml":  # the heated foil warms from the bed's temperature
        foil = read_series(out / "timeseries.csv")["tubes1_foil_T_K"]
        assert foil[0] == pytest.approx(293.15) and foil[-1] > foil[0] + 0.01


def test_every_shipped_scene_has_a_smoke_test():
    from tidem.scene.load import shipped_scenes

    params = test_shipped_scene_smoke.pytestmark[0].args[1]
    assert sorted(shipped_scenes()) == sorted(params)


def test_every_shipped_scene_has_a_gallery_frame_in_the_readme():
    from pathlib import Path

    from tidem.scene.load import shipped_scenes

    root = Path(__file__).resolve().parents[2]
    readme = (root / "README.md").read_text()
    for name in shipped_scenes():
        frame = f"renders/gallery/{name.removesuffix('.toml')}.png"
        assert (root / frame).is_file() and frame in readme, frame


def test_a_run_that_cannot_fit_on_disk_is_refused_before_it_starts(tmp_path, monkeypatch):
    """`tidem scene` estimates its output (tidem.runner.output_size) against the folder's free space."""
    import shutil
    from types import SimpleNamespace

    monkeypatch.setattr(shutil, "disk_usage", lambda path: SimpleNamespace(free=10**6))
    out = tmp_path / "full"
    result = runner.invoke(app, ["scene", "sphere_impact.toml", "--out", str(out), "--quiet", "--no-render",
                                 "--set", "output.snapshots=20000"])
    assert result.exit_code == 2, result.output
    assert "output.snapshots: the run would write about" in result.output and "has 977 KiB free" in result.output
    assert not (out / "run.json").exists()
    result = runner.invoke(app, ["check", "sphere_impact.toml", "--set", "output.snapshots=20000"])
    assert result.exit_code == 0 and "output: 1122 snapshots, about" in result.output  # one per step at most
