"""The Python API (`tidem.load_scene`, `tidem.run`, `tidem.read_run`) through its public names
only: overrides as the CLI's --set, errors as exceptions with the CLI's messages, two runs in one
process, the renderer's process, a failed run, Ctrl-C and resuming after it."""

import os
import signal
import sys
import threading
import time

import numpy as np
import pytest
from typer.testing import CliRunner

import tidem
from tidem.cli.commands import app

QUICK = {"output.snapshots": 4}


def test_overrides_as_set_gives_them():
    by_kwargs = tidem.load_scene("sphere_impact", materials__sus304__restitution=0.5, numerics__t_end=0.002)
    by_dict = tidem.load_scene("sphere_impact.toml", {"materials.sus304.restitution": 0.5, "numerics.t_end": 0.002})
    by_text = tidem.load_scene("sphere_impact", ["materials.sus304.restitution=0.5", "numerics.t_end=2e-3"])
    for loaded in (by_kwargs, by_dict, by_text):
        assert loaded.scene.materials["sus304"].restitution == 0.5 and loaded.scene.numerics.t_end == 0.002
    assert tidem.load_scene("sphere_impact", {"particles[0].positions": [[-0.01, 0.0, 0.0]] * 3}).scene.particles[0] \
        .positions[0] == (-0.01, 0.0, 0.0)
    assert tidem.load_scene().name == "fluidized_tube", "no name: the default scene, as `tidem scene`"
    swept = tidem.load_scene("sphere_impact", particles__0__seed=np.arange(3)[2], numerics__force_dt=np.bool_(False),
                             particles__0__velocity=np.array([0.5, 0.0, 0.0]))  # values as a numpy sweep gives them
    assert swept.scene.particles[0].seed == 2 and swept.scene.numerics.force_dt is False
    assert swept.scene.particles[0].velocity == (0.5, 0.0, 0.0)


def test_errors_carry_the_messages_the_cli_prints(tmp_path):
    with pytest.raises(tidem.SceneError) as caught:
        tidem.load_scene("sphere_impact", numerics__t_endd=1.0, materials__sus304__density=-1.0)
    cli = CliRunner().invoke(app, ["check", "sphere_impact", "--set", "numerics.t_endd=1.0",
                                   "--set", "materials.sus304.density=-1.0"])
    assert cli.exit_code == 2 and str(caught.value) in cli.output
    assert "did you mean 't_end'" in str(caught.value)
    with pytest.raises(tidem.SceneError, match="no shipped scene of that name"):
        tidem.load_scene("no_such_scene")
    (tmp_path / "a_file").write_text("")
    with pytest.raises(tidem.InputError, match="a file of that name exists; give a folder"):
        tidem.run("sphere_impact", out=tmp_path / "a_file", progress=False)
    with pytest.raises(tidem.InputError, match="--arch gpu: choose cpu, cuda, vulkan or auto"):
        tidem.run("sphere_impact", out=tmp_path / "x", arch="gpu")
    with pytest.raises(tidem.InputError, match="not a run folder"):
        tidem.read_run(tmp_path)


def test_two_runs_in_one_process_and_reading_them_back(tmp_path, monkeypatch):
    """Two restitutions, each run's observables from its own run.json; the second renders its
    frames and movie in the renderer's process and writes the plots."""
    runs = {}
    for e, render in ((0.5, False), (0.9, True)):
        scene = tidem.load_scene("sphere_impact", {**QUICK, "materials.sus304.restitution": e})
        runs[e] = tidem.run(scene, out=tmp_path / f"e{e}", render=render, plots=render, progress=False)
    for e, run in runs.items():
        assert run.status == "finished"
        assert run.observables["restitution"]["restitution"] == pytest.approx(e, rel=0.02)
        assert run.values["restitution"] == run.observables["restitution"]["restitution"]
    assert not (tmp_path / "e0.5" / "plots").exists() and not (tmp_path / "e0.5" / "frames").exists()
    done = tmp_path / "e0.9"
    assert (done / "sphere_impact.mp4").stat().st_size > 1000
    assert len(list((done / "frames").glob("frame_*.png"))) == len(runs[0.9].snapshots) == 5
    assert {p.name for p in (done / "plots").glob("*.png")} >= {"energy.png", "heat.png", "solver.png", "timeseries.png"}
    back = tidem.read_run(done)
    assert back.summary == runs[0.9].summary and "RunFolder(" in repr(back)
    series = back.series
    assert series["time_s"][0] == 0.0 and series["kinetic_energy_J"].shape == series["time_s"].shape
    times = [t for t, _ in back.snapshots]
    assert times == sorted(times) and times[0] == 0.0
    points, arrays = back.snapshot(-1)
    assert points.shape == (6, 3) and np.allclose(arrays["radius"], 0.00955)
    with pytest.raises(IndexError, match="out of range"):
        back.snapshot(5)
    with pytest.raises(IndexError, match="wrote no gas files"):
        back.gas()
    monkeypatch.setitem(sys.modules, "pandas", None)  # as where pandas is not installed
    with pytest.raises(ImportError, match="needs pandas"):
        back.dataframe()


def test_dataframe_with_pandas(tmp_path):
    pandas = pytest.importorskip("pandas")
    run = tidem.run(tidem.load_scene("sphere_impact", QUICK), out=tmp_path / "r", plots=False, progress=False)
    frame = run.dataframe()
    assert isinstance(frame, pandas.DataFrame) and list(frame.columns) == list(run.series)


def test_a_failed_run_raises_with_its_folder(tmp_path):
    scene = tidem.load_scene("sphere_impact", {"materials.sus304.youngs_modulus": 1e5, "numerics.check_interval": 5})
    with pytest.raises(tidem.RunFailed, match="% of its radius") as caught:
        tidem.run(scene, out=tmp_path / "soft", plots=False, progress=False)
    assert str(caught.value).startswith("run stopped: ") and caught.value.run.status == "failed"


def test_ctrl_c_stops_the_run_keeps_its_output_and_it_resumes(tmp_path):
    """Spheres bouncing between walls for a long while; SIGINT once the first snapshot is on disk
    (as Ctrl-C in a notebook): the run stops between steps with a checkpoint and raises a
    KeyboardInterrupt carrying its folder; resuming runs on to a new end time."""
    out = tmp_path / "long"
    scene = tidem.load_scene("sphere_impact", {"domain.walls": "auto", "numerics.t_end": 2.0})

    def interrupt():
        for _ in range(1200):
            if (out / "snapshots.pvd").exists():
                time.sleep(0.2)
                os.kill(os.getpid(), signal.SIGINT)
                return
            time.sleep(0.05)

    threading.Thread(target=interrupt, daemon=True).start()
    with pytest.raises(KeyboardInterrupt) as caught:
        tidem.run(scene, out=out, plots=False, progress=False)
    assert isinstance(caught.value, tidem.RunInterrupted)
    stopped = caught.value.run
    assert stopped.status == "interrupted" and "checkpoint written" in str(caught.value)
    t_stop = stopped.summary["time_s"]
    assert 0.0 < t_stop < 2.0 and (out / "checkpoint.npz").exists()
    resumed = tidem.run(scene, resume=out, t_end=t_stop + 1e-4, plots=False, progress=False)
    assert resumed.status == "finished" and resumed.summary["resumed_from"]
    assert 0 <= resumed.summary["time_s"] - (t_stop + 1e-4) <= resumed.summary["dt_s"]  # whole steps
