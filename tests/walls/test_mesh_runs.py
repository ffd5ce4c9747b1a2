"""Whole runs with mesh walls: a turning, heated drum resumed from its checkpoint is the uninterrupted
run bit for bit (the triangles' motion, their bins and the contact slots carry over), and a box of
mesh walls settles the same bed as the box's analytic walls (packing and height within the spread
of three seeds)."""

import numpy as np
import pyvista as pv

from tests.conftest import make_scene
from tests.runner.test_checkpoint import snapshots
from tidem.runner import checkpoint
from tidem.runner.loop import run
from tidem.runtime.startup import restart
from tidem.scene.load import validate
from tidem.sim.model import build_model

SAND = {"density": 2600.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.3, "friction": 0.5,
        "rolling_friction": 0.1, "conductivity": 3.0, "heat_capacity": 800.0}


def drum(tmp_path, t_end):
    path = tmp_path / "drum.stl"
    if not path.exists():
        pv.Cylinder(center=(0.0, 0.003, 0.0), direction=(0, 1, 0), radius=0.025, height=0.006, resolution=36,
                    capping=False).triangulate().save(str(path))
    return make_scene(
        domain={"min": [-0.03, 0.0, -0.03], "max": [0.03, 0.006, 0.03], "periodic": ["y"], "walls": "none",
                "gravity": [0, 0, -9.81]},
        materials={"sand": dict(SAND)},
        particles=[{"name": "bed", "material": "sand", "diameter": {"distribution": "uniform", "min": 0.0018,
                                                                     "max": 0.0022}, "seed": 2, "temperature": 300.0,
                    "region": {"min": [-0.03, 0.0, -0.03], "max": [0.03, 0.006, -0.01]}, "inside_mesh": 0}],
        meshes=[{"file": str(path), "temperature": 400.0,
                 "rotation": {"center": [0.0, 0.0, 0.0], "axis": [0.0, 1.0, 0.0], "speed": 4.0}}],
        heat={"initial_temperature": 300.0},
        numerics={"t_end": t_end, "dt_fraction": 0.3},
        output={"interval": 0.01, "timeseries_interval": 0.002},
    )


def test_turning_heated_drum_resumes_bit_identical(tmp_path):
    whole, half = tmp_path / "whole", tmp_path / "half"
    assert run(build_model(validate(drum(tmp_path, 0.04))), whole, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    assert run(build_model(validate(drum(tmp_path, 0.02))), half, progress=False).status == "finished"
    restart()  # the same scene again, first after a start: its kernels come from the cache
    loaded = validate(drum(tmp_path, 0.04))
    meta, arrays = checkpoint.load(half)
    assert run(build_model(loaded), half, progress=False, resume=(meta, arrays)).status == "finished"
    sa, sb = snapshots(whole), snapshots(half)
    assert len(sa) == len(sb) == 5
    for (pa, da), (pb, db) in zip(sa, sb):
        assert np.array_equal(pa, pb) and all(np.array_equal(da[k], db[k]) for k in da)
    assert (whole / "timeseries.csv").read_text() == (half / "timeseries.csv").read_text()
    heat = np.genfromtxt(whole / "timeseries.csv", delimiter=",", names=True)["meshes0_heat_W"]
    assert heat[-1] > 0.0  # the wall heats the bed


def settled_box(tmp_path, seed, mesh):
    """300 grains poured into a 24 x 24 mm box (analytic walls, or the same five faces as a mesh)."""
    raw = make_scene(
        domain={"min": [0.0, 0.0, 0.0], "max": [0.024, 0.024, 0.04], "walls": ["x-", "x+", "y-", "y+", "z-"],
                "gravity": [0, 0, -9.81]},
        materials={"sand": {**SAND, "rolling_friction": 0.0}},
        particles=[{"name": "bed", "material": "sand", "seed": seed,
                    "diameter": {"distribution": "uniform", "min": 0.0018, "max": 0.0022},
                    "region": {"min": [0.0, 0.0, 0.004], "max": [0.024, 0.024, 0.04]}, "count": 300}],
        numerics={"t_end": 0.35, "dt_fraction": 0.3},
    )
    if mesh:
        path = tmp_path / "box.stl"
        lo, hi = np.zeros(3), np.array([0.024, 0.024, 0.04])
        box = pv.Box(bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])).triangulate()
        box = box.extract_cells(np.flatnonzero(box.cell_centers().points[:, 2] < hi[2] - 1e-9)).extract_surface(
            algorithm="dataset_surface")
        box.save(str(path))
        raw["domain"].update({"walls": "none", "min": [-0.002, -0.002, -0.002], "max": [0.026, 0.026, 0.042]})
        raw["meshes"] = [{"file": str(path)}]
    return raw


def test_box_of_mesh_walls_settles_the_bed_of_the_box_walls(tmp_path, solver_for):
    out = {}
    for mesh in (False, True):
        heights, packings = [], []
        for seed in (1, 2, 3):
            s = solver_for(settled_box(tmp_path, seed, mesh))
            s.advance(int(0.35 / s.dt))
            x, r = s.state.x.to_numpy(), s.state.radius.to_numpy()
            top = np.percentile(x[:, 2] + r, 95)
            heights.append(top)
            packings.append((4 / 3 * np.pi * r**3).sum() / (0.024 * 0.024 * top))
            speed = np.linalg.norm(s.state.v.to_numpy(), axis=1)
            assert np.percentile(speed, 99) < 0.01 and speed.max() < 0.05  # settled: a grain may still roll on top
        out[mesh] = (heights, packings)
    for k in (0, 1):
        lo = min(out[False][k] + out[True][k])
        spread = max(max(out[False][k]) - min(out[False][k]), max(out[True][k]) - min(out[True][k]))
        assert abs(np.mean(out[True][k]) - np.mean(out[False][k])) <= spread + 1e-9, (k, out)
        assert lo > 0
