#!/usr/bin/env python3
"""Where a fine mesh floor's cost lies (follow-up of `mesh_walls.py`): the periodic peer bed of N
particles on the analytic floor, on a floor of two triangles, and on the ~100 000-triangle floor of
`mesh_walls.py` with the candidate room as sized (`mesh_bins.candidate_slots`) and forced to 24, and
the same floor with every triangle a flat patch of its own (the general narrow phase of
`kernels/mesh_contact.py` for every particle that lists two triangles or more). Timed alternating in
one process (4 rounds of 200 steps); prints how many triangles the particles list.

Usage (from the repository root): python benchmarks/mesh_floor_cost.py [N=100000]
"""
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("TI_CPU_MAX_NUM_THREADS", "2")
from tidem.runtime.startup import ensure_taichi

ensure_taichi("cpu", "float64", 2)
import mesh_walls as mw
import taichi as ti

import tidem.walls.mesh_bins as mb
from tidem.scene.load import validate
from tidem.sim.model import build_model
from tidem.sim.solver import Solver
from tidem.studies.bench import advance, bench_scene, tiled_bed

n = int(sys.argv[1]) if len(sys.argv) > 1 else 100000
folder = Path(tempfile.mkdtemp())
x, extent = tiled_bed(n)
floor = bench_scene(x, extent, "float64")
count = mw.floor_mesh(folder / "floor.stl", extent, 100000)
mesh_floor = json.loads(json.dumps(floor))
mesh_floor["domain"]["walls"] = "none"; mesh_floor["domain"]["min"][2] = -0.001
mesh_floor["meshes"] = [{"file": str(folder / "floor.stl")}]
solvers = {"analytic": Solver(build_model(validate(floor, "<b>")))}
m = build_model(validate(mesh_floor, "<b>")); print("M default", m.mesh_table.candidates)
solvers["mesh M=%d" % m.mesh_table.candidates] = Solver(m)
orig = mb.candidate_slots
mb.candidate_slots = lambda tri, reach: 24
m2 = build_model(validate(mesh_floor, "<b>")); print("M forced", m2.mesh_table.candidates)
solvers["mesh M=24"] = Solver(m2)
mb.candidate_slots = orig
patches = mb.flat_patches
mb.flat_patches = lambda v, t: np.arange(len(t))
solvers["mesh, no flat patch"] = Solver(build_model(validate(mesh_floor, "<b>")))
mb.flat_patches = patches
import pyvista as pv

ex = extent
big = pv.PolyData(np.array([[0,0,0],[ex[0],0,0],[ex[0],ex[1],0],[0,ex[1],0]],float), np.array([3,0,1,2,3,0,2,3]))
big.save(str(folder / "big.stl"))
two = json.loads(json.dumps(mesh_floor)); two["meshes"] = [{"file": str(folder / "big.stl")}]
solvers["mesh 2 triangles"] = Solver(build_model(validate(two, "<b>")))
for s in solvers.values():
    advance(s, 300)
for name, s in solvers.items():
    if "mesh" in name:
        mc, flat = s.state.mc_n.to_numpy(), s.state.mc_flat.to_numpy()
        print(name, "max listed", mc.max(), "particles listing", (mc > 0).sum(), "of them in one flat patch",
              ((mc > 0) & (flat >= 0)).sum())
times = {k: [] for k in solvers}
for _ in range(4):
    for name, s in solvers.items():
        ti.sync(); t0 = time.perf_counter(); advance(s, 200); ti.sync(); times[name].append((time.perf_counter() - t0) / 200 * 1e3)
for k, v in times.items():
    print(f"{k:20s} median {np.median(v):.3f} best {min(v):.3f} ms/step")
