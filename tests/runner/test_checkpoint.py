"""Checkpoint and resume: a resumed float64 run is bit-identical to an uninterrupted
one (snapshots and time series), SIGTERM stops at a step boundary with a checkpoint, a kill
during the write leaves the previous checkpoint loadable, and an edited scene is refused."""

import os
import signal

import numpy as np
import pytest
from typer.testing import CliRunner

from tests.conftest import make_scene
from tidem.cli.commands import app
from tidem.io.vtp import read_vtp
from tidem.render.plots import read_series
from tidem.runner import checkpoint
from tidem.runner.loop import run
from tidem.runtime.startup import restart
from tidem.scene.load import validate
from tidem.sim.model import build_model
from tidem.sim.solver import Solver

SAND = {"density": 2600.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.3, "friction": 0.5,
        "rolling_friction": 0.1, "conductivity": 3.0, "heat_capacity": 800.0}
T_END = 0.06


def hot_pour(t_end=T_END, conduction_interval=1, **numerics):
    """Particles poured (random places, seeded) onto a heated floor with a tube: pour RNG,
    tangential and rolling springs, wall and tube slots, temperatures and the time-averaged
    cells and ring sectors all carry state."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.016, 0.008, 0.03], "periodic": ["x"], "walls": "auto",
                "gravity": [0, 0, -9.81]},
        materials={"sand": dict(SAND)},
        particles=[{"name": "bed", "material": "sand", "diameter": {"distribution": "uniform", "min": 0.0016,
                                                                     "max": 0.002}, "seed": 5,
                    "region": {"min": [0, 0, 0.0], "max": [0.016, 0.008, 0.006]}, "temperature": 300.0},
                   {"name": "poured", "material": "sand", "count": 40, "seed": 9,
                    "diameter": {"distribution": "mono", "value": 0.002}, "temperature": 400.0,
                    "pour": {"region": {"min": [0, 0, 0.02], "max": [0.016, 0.008, 0.03]}, "rate": 2000.0}}],
        tubes=[{"center": [0.008, 0.0, 0.012], "axis": "y", "diameter": 0.004, "temperature": 350.0}],
        heat={"initial_temperature": 300.0, "conduction_interval": conduction_interval},
        averaging={"start": 0.01, "interval": 0.002, "cell_size": [0.004, 0.005], "rings": 2},
        numerics={"t_end": t_end, "dt_fraction": 0.3, **numerics},
        output={"interval": 0.01, "timeseries_interval": 0.002},
    )


def snapshots(run_dir):
    return [read_vtp(p) for p in sorted((run_dir / "snapshots").glob("*.vtp"))]


def assert_same_run(a, b):
    sa, sb = snapshots(a), snapshots(b)
    assert len(sa) == len(sb) == round(T_END / 0.01) + 1
    for (pa, da), (pb, db) in zip(sa, sb):
        assert np.array_equal(pa, pb)
        assert da.keys() == db.keys()
        for k in da:
            assert np.array_equal(da[k], db[k]), k
    assert (a / "timeseries.csv").read_text() == (b / "timeseries.csv").read_text()
    assert (a / "snapshots.pvd").read_text() == (b / "snapshots.pvd").read_text()
    for name in ("averages_cells.csv", "averages_rings.csv"):
        assert (a / name).read_text() == (b / name).read_text(), name
    assert read_series(a / "averages_cells.csv")["samples"][0] == 26  # t = 0.01, 0.012, ..., 0.06


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole")
    assert run(build_model(validate(hot_pour())), out, progress=False).status == "finished"
    return out


def resume(out, t_end=T_END, conduction_interval=1, **numerics):
    restart()  # the same scene again, first after a start: its kernels come from the cache
    loaded = validate(hot_pour(t_end, conduction_interval, **numerics))
    meta, arrays = checkpoint.load(out)
    checkpoint.check_scene(meta, loaded.raw, numerics.get("precision", "float64"))
    return run(build_model(loaded), out, progress=False, resume=(meta, arrays))


def test_run_to_half_then_resume_is_bit_identical(uninterrupted, tmp_path):
    restart()  # the same scene again, first after a start: its kernels come from the cache
    first = run(build_model(validate(hot_pour(T_END / 2))), tmp_path, progress=False)
    assert first.status == "finished" and (tmp_path / "checkpoint.npz").is_file()
    second = resume(tmp_path)
    assert second.status == "finished" and second.summary["resumed_from"].startswith("t = 0.03")
    assert_same_run(uninterrupted, tmp_path)


def test_mixed_precision_resume_is_bit_identical(tmp_path):
    """numerics.precision = 'mixed' keeps the rows' history in float32: the checkpoint stores them
    as they are, and the resumed run is the uninterrupted one bit for bit."""
    whole, half = tmp_path / "whole", tmp_path / "half"
    assert run(build_model(validate(hot_pour(precision="mixed"))), whole, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    assert run(build_model(validate(hot_pour(T_END / 2, precision="mixed"))), half, progress=False).status == "finished"
    assert resume(half, precision="mixed").status == "finished"
    assert_same_run(whole, half)


def test_conduction_every_few_steps_resumes_bit_identical(tmp_path):
    """With heat.conduction_interval = 5 the surfaces' heat flows hold between evaluations: the
    checkpoint (here between two evaluations) carries them, and the resumed run is the
    uninterrupted one bit for bit."""
    whole, half = tmp_path / "whole", tmp_path / "half"
    assert run(build_model(validate(hot_pour(conduction_interval=5))), whole, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    first = run(build_model(validate(hot_pour(T_END / 2, conduction_interval=5))), half, progress=False)
    assert first.status == "finished" and first.steps % 5 != 0, "the checkpoint falls between two evaluations"
    assert resume(half, conduction_interval=5).status == "finished"
    assert_same_run(whole, half)


def test_sigterm_checkpoints_at_a_step_boundary_and_resume_is_bit_identical(uninterrupted, tmp_path, monkeypatch):
    real_step = Solver._step

    def step(self, drift_next, diag):
        real_step(self, drift_next, diag)
        if self.steps == 777:
            os.kill(os.getpid(), signal.SIGTERM)

    monkeypatch.setattr(Solver, "_step", step)
    restart()  # the same scene again, first after a start: its kernels come from the cache
    stopped = run(build_model(validate(hot_pour())), tmp_path, progress=False)
    # the run loop stops at the end of the steps it hands the solver at once (50 at most, tidem.runner.loop)
    assert stopped.status == "interrupted" and "SIGTERM" in stopped.message and 777 <= stopped.steps <= 800
    monkeypatch.setattr(Solver, "_step", real_step)
    assert checkpoint.load(tmp_path)[0]["solver"]["steps"] == stopped.steps
    assert resume(tmp_path).status == "finished"
    assert_same_run(uninterrupted, tmp_path)


def test_kill_during_checkpoint_write_keeps_the_previous_one(tmp_path, monkeypatch):
    s = Solver(build_model(validate(hot_pour())))
    try:
        loop = {"entries": [], "series_rows": 0}
        checkpoint.save(tmp_path, s, loop, {"a": 1})
        before = (tmp_path / "checkpoint.npz").read_bytes()
        for _ in range(20):
            s.step()

        def killed(fh, **arrays):
            fh.write(b"PK\x03\x04 half a zip")
            raise KeyboardInterrupt

        monkeypatch.setattr(np, "savez", killed)
        with pytest.raises(KeyboardInterrupt):
            checkpoint.save(tmp_path, s, loop, {"a": 1})
    finally:
        s.release()
    assert (tmp_path / "checkpoint.npz").read_bytes() == before
    meta, _ = checkpoint.load(tmp_path)
    assert meta["solver"]["steps"] == 0


def test_restore_refuses_a_missing_or_misshapen_array_before_writing_any_field(tmp_path):
    s = Solver(build_model(validate(hot_pour())))
    try:
        checkpoint.save(tmp_path, s, {}, {})
        meta, arrays = checkpoint.load(tmp_path)
        with pytest.raises(checkpoint.CheckpointError, match="lacks state/T"):
            checkpoint.restore(s, meta, {k: v for k, v in arrays.items() if k != "state/T"})
        T0 = s.state.T.to_numpy()
        bad = {**arrays, "state/T": np.zeros_like(arrays["state/T"]), "state/x": arrays["state/x"][:-1]}
        with pytest.raises(checkpoint.CheckpointError, match=r"state/x: checkpoint shape \(\d+, 3\) does not match"):
            checkpoint.restore(s, meta, bad)
        assert np.array_equal(s.state.T.to_numpy(), T0)  # every shape is checked before any field is written
    finally:
        s.release()


def test_resume_refuses_an_edited_scene_naming_the_key():
    raw = hot_pour()
    edited = hot_pour(0.2)  # a later end time and new output cadence may change
    edited["output"]["interval"] = 0.02
    edited["render"] = {"range": [300.0, 310.0]}  # a [render] table added
    edited["numerics"]["max_overlap"] = 0.15  # the health check's limit: it stops a run, never moves one
    meta = {"scene": raw, "precision": "float64"}
    checkpoint.check_scene(meta, edited, "float64")
    edited["materials"]["sand"]["friction"] = 0.3
    edited["tubes"][0]["temperature"] = 360.0
    with pytest.raises(checkpoint.CheckpointError) as err:
        checkpoint.check_scene(meta, edited, "float64")
    assert "materials.sand.friction" in str(err.value) and "tubes[0].temperature" in str(err.value)
    with pytest.raises(checkpoint.CheckpointError, match="float32"):
        checkpoint.check_scene(meta, raw, "float32")


def test_cli_resume_refuses_edit_and_continues_a_run(tmp_path):
    runner = CliRunner()
    out = tmp_path / "impact"
    args = ["scene", "sphere_impact", "--quiet", "--no-render"]
    assert runner.invoke(app, [*args, "--out", str(out), "--t-end", "6e-4"]).exit_code == 0
    bad = runner.invoke(app, [*args, "--resume", str(out), "--set", "materials.sus304.restitution=0.5"])
    assert bad.exit_code == 2 and "materials.sus304.restitution" in bad.output
    done = runner.invoke(app, [*args, "--resume", str(out), "--t-end", "6e-4"])
    assert done.exit_code == 2 and "already at or past the end time" in done.output
    ok = runner.invoke(app, [*args, "--resume", str(out)])
    assert ok.exit_code == 0, ok.output
    assert "resuming from t = 0.0006" in ok.output
    missing = runner.invoke(app, [*args, "--resume", str(tmp_path / "nothing")])
    assert missing.exit_code == 2 and "no checkpoint.npz" in missing.output


def test_resumed_reacting_run_keeps_the_reaction_log(tmp_path_factory):
    """reactions.csv of a run resumed at t/2 equals the uninterrupted run's (the rows sampled
    before the checkpoint travel in it)."""
    def reacting(t_end):
        raw = hot_pour(t_end)
        raw["reactions"] = [{"type": "polymerization", "group": "bed", "rate_constant": 1e-9, "monomer_pressure": 1e6,
                             "activation_energy": 1e5, "reference_temperature": 353.15, "enthalpy": 3.34e6}]
        return validate(raw)

    whole, split = tmp_path_factory.mktemp("whole_rx"), tmp_path_factory.mktemp("split_rx")
    assert run(build_model(reacting(T_END)), whole, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    assert run(build_model(reacting(T_END / 2)), split, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    loaded = reacting(T_END)
    meta, arrays = checkpoint.load(split)
    assert run(build_model(loaded), split, progress=False, resume=(meta, arrays)).status == "finished"
    rows = (whole / "reactions.csv").read_text().splitlines()
    assert len(rows) > 100 and float(rows[1].split(",")[0]) == 0.0
    assert (split / "reactions.csv").read_text() == (whole / "reactions.csv").read_text()


KILLED = """name = "killed"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.02, 0.02, 0.04]
[materials.sand]
density = 2600.0
youngs_modulus = 1e7
[[particles]]
name = "bed"
material = "sand"
diameter = { value = 0.004 }
region = { min = [0.0, 0.0, 0.0], max = [0.02, 0.02, 0.04] }
[numerics]
t_end = 100.0
[output]
interval = 0.002
checkpoint_interval = 0.01
"""


def complete_vtp(path) -> bool:
    """A snapshot that parses in full: its closing tag is there and every array has one row per point."""
    import re

    if not path.read_bytes().endswith(b"</VTKFile>\n"):
        return False
    points, data = read_vtp(path)
    n = int(re.search(rb'NumberOfPoints="(\d+)"', path.read_bytes()).group(1))
    return len(points) == n and all(len(v) == n for v in data.values())


def test_kill_9_leaves_complete_snapshots_and_a_checkpoint_that_resumes(tmp_path):
    import subprocess
    import sys
    import time

    scene = tmp_path / "killed.toml"
    scene.write_text(KILLED)
    out = tmp_path / "run"
    env = {**os.environ, "TIDEM_COMPILE": "fast"}
    cmd = [sys.executable, "-m", "tidem", "scene", str(scene), "--no-render", "--quiet"]
    proc = subprocess.Popen(cmd + ["--out", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not (out / checkpoint.FILE).exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)  # into the snapshots and checkpoints that follow
    proc.kill()
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, proc.stderr.read().decode()
    snaps = sorted((out / "snapshots").glob("*.vtp"))
    assert len(snaps) >= 2
    assert all(complete_vtp(p) for p in snaps)
    meta, _ = checkpoint.load(out)
    t_end = meta["solver"]["t"] + 0.005
    (out / "snapshots" / "snap_99999.vtp.tmp").write_bytes(b"<?xml")  # as a kill during a write leaves it
    done = subprocess.run(cmd + ["--resume", str(out), "--t-end", repr(t_end)], env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "finished" in done.stderr
    assert all(complete_vtp(p) for p in (out / "snapshots").glob("*.vtp"))
    assert not list(out.rglob("*.tmp"))
