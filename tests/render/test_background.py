"""Frames rendered in a background process while the run goes on: the same frames as
`tidem render`, only finished frames after a stop, a clear message on errors, and a worker
that never outlives its parent."""

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.io.vtp import write_pvd, write_vtp
from tidem.render.background import BackgroundRenderer
from tidem.render.gl import RenderUnavailable, prepare_offscreen

try:
    prepare_offscreen()
except RenderUnavailable:  # pragma: no cover
    pytest.skip("no off-screen OpenGL library", allow_module_level=True)


def run_folder(path, snaps=3, field="speed"):
    """A run folder with `snaps` snapshots of two particles and the run.json a run writes."""
    (path / "snapshots").mkdir(parents=True)
    info = {"scene": "t", "render": {"field": field, "range": [0.0, 1.0], "view": "front", "height": 240},
            "render_geometry": {"bounds": [0.0, 0.2, 0.0, 0.02, 0.0, 0.1], "periodic": [False] * 3, "tubes": []}}
    (path / "run.json").write_text(json.dumps(info))
    entries = []
    for k in range(snaps):
        name = f"snapshots/snap_{k:05d}.vtp"
        write_vtp(path / name, np.array([[0.05, 0.01, 0.05], [0.15, 0.01, 0.05]]),
                  {"radius": np.full(2, 0.02), "velocity": np.array([[0.0, 0, 0], [0.5 * k, 0, 0]])}, time=0.1 * k)
        entries.append((0.1 * k, name))
    write_pvd(path / "snapshots.pvd", entries)
    return path / name


def wait_for(condition, timeout=60.0):
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.05)


def test_frames_appear_while_the_run_goes_on_and_stop_keeps_only_finished_ones(tmp_path):
    snap = run_folder(tmp_path, snaps=40)
    with BackgroundRenderer(tmp_path) as bg:
        bg(snap)
        wait_for(lambda: bg.frames_done() >= 2)
        assert bg.proc.poll() is None, "the worker renders while the parent (the run) goes on"
        bg.stop()
        assert bg.proc.poll() is not None
    done = bg.frames_done()
    assert 2 <= done < 40
    assert not list((tmp_path / "frames").glob(".frame_*")), "no half-written frame"
    with BackgroundRenderer(tmp_path) as bg:
        bg(snap)
        assert bg.finish() is None
    assert bg.frames_done() == 40


def test_worker_error_is_one_line(tmp_path):
    snap = run_folder(tmp_path, snaps=1, field="temperature")
    with BackgroundRenderer(tmp_path) as bg:
        bg(snap)
        error = bg.finish()
    assert error.startswith("the snapshots have no 'temperature' array"), error


def test_worker_dies_with_its_parent(tmp_path):
    snap = run_folder(tmp_path, snaps=200)
    code = ("import os, signal, sys; from pathlib import Path; from tidem.render.background import BackgroundRenderer; "
            f"bg = BackgroundRenderer(Path({str(tmp_path)!r})); bg(Path({str(snap)!r})); "
            "print(bg.proc.pid, flush=True); sys.stdin.readline(); os.kill(os.getpid(), signal.SIGKILL)")
    parent = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    worker = int(parent.stdout.readline())
    wait_for(lambda: (tmp_path / "frames" / "frame_00000.png").exists())
    parent.stdin.write("\n")
    parent.stdin.flush()
    parent.wait(timeout=30)

    def gone():
        try:
            with open(f"/proc/{worker}/stat") as fh:
                return fh.read().split(")")[-1].split()[0] == "Z"  # a zombie has exited
        except FileNotFoundError:
            return True

    wait_for(gone, timeout=10)
    assert len(list((tmp_path / "frames").glob("frame_*.png"))) < 200


def test_ctrl_c_during_the_run_keeps_finished_frames_and_stops_the_worker(tmp_path, monkeypatch):
    from tidem.render import background
    from tidem.sim.solver import Solver

    started = []
    real_call = background.BackgroundRenderer.__call__

    def call(self, snapshot):
        real_call(self, snapshot)
        started.append(self.proc)

    real_step = Solver._step

    def step(self, drift_next, diag):
        if self.steps == 600:
            wait_for(lambda: (out / "frames" / "frame_00001.png").exists())
            raise KeyboardInterrupt
        real_step(self, drift_next, diag)

    monkeypatch.setattr(background.BackgroundRenderer, "__call__", call)
    monkeypatch.setattr(Solver, "_step", step)
    out = tmp_path / "stop"
    result = CliRunner().invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet"])
    assert result.exit_code == 130
    assert started[0].poll() is not None, "the worker is gone"
    frames = sorted((out / "frames").glob("*"))
    assert frames and all(f.name.startswith("frame_") for f in frames)
    assert len(frames) <= (out / "snapshots.pvd").read_text().count("<DataSet")
    assert not (out / "sphere_impact.mp4").exists()
    assert os.path.exists(out / "run.json")
