#!/usr/bin/env python3
"""Mesh walls against analytic walls, side by side in one process (calls alternating, so that this
machine's drift between processes cancels out), on the settled peer bed of `tidem bench`:

- `floor`: the periodic bed on its analytic floor (z- wall) against the same bed on a floor made of
  a mesh of about TRIANGLES irregular triangles (a jittered grid, Delaunay) at z = 0;
- `box`: the bed in a box of five analytic walls (x-, x+, y-, y+, z-; not periodic) against the
  same bed in a box of five mesh faces (10 triangles), walls 0.5 d outside the bed's extent.

Each variant is timed in rounds of STEPS steps after a warm-up; the table gives the median and the
best round's ms/step and their ratio (mesh / analytic).

Usage (from the repository root):
    python benchmarks/mesh_walls.py [N=200000] [rounds=6] [steps=200] [threads=2] [triangles=100000]
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def floor_mesh(path: Path, extent, triangles: int) -> int:
    """A floor z = 0 over [0, extent] of about `triangles` irregular triangles; returns their number."""
    import pyvista as pv

    n = int(np.sqrt(triangles / 2 * extent[0] / extent[1])) + 1
    m = int(np.sqrt(triangles / 2 * extent[1] / extent[0])) + 1
    gx, gy = np.linspace(0, extent[0], n + 1), np.linspace(0, extent[1], m + 1)
    xx, yy = np.meshgrid(gx, gy)
    pts = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)
    inner = (pts[:, 0] > 0) & (pts[:, 0] < extent[0]) & (pts[:, 1] > 0) & (pts[:, 1] < extent[1])
    pts[inner, :2] += np.random.default_rng(1).uniform(-0.3, 0.3, (inner.sum(), 2)) * [extent[0] / n, extent[1] / m]
    mesh = pv.PolyData(pts).delaunay_2d()
    mesh.points[:, 2] = 0.0
    mesh.save(str(path))
    return mesh.n_cells


def box_mesh(path: Path, lo, hi) -> None:
    """Five faces (open top) of the box [lo, hi], two triangles each."""
    import pyvista as pv

    x0, y0, z0 = lo
    x1, y1, z1 = hi
    c = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    quads = [(0, 1, 2, 3), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    tris = [t for a, b, cc, d in quads for t in ((a, b, cc), (a, cc, d))]
    pv.PolyData(np.array(c, float), np.hstack([[3, *t] for t in tris])).save(str(path))


def scenes(n: int, folder: Path, triangles: int) -> dict:
    from tidem.studies.bench import bench_scene, tiled_bed

    x, extent = tiled_bed(n)
    d = 0.001
    out = {}
    floor = bench_scene(x, extent, "float64")
    out["floor: analytic"] = floor
    count = floor_mesh(folder / "floor.stl", extent, triangles)
    mesh_floor = json.loads(json.dumps(floor))
    mesh_floor["domain"]["walls"] = "none"
    mesh_floor["domain"]["min"][2] = -0.001
    mesh_floor["meshes"] = [{"file": str(folder / "floor.stl")}]
    out[f"floor: mesh of {count} triangles"] = mesh_floor
    boxed = json.loads(json.dumps(floor))
    lo, hi = [-0.5 * d, -0.5 * d, 0.0], [extent[0] + 0.5 * d, extent[1] + 0.5 * d, 0.03]
    boxed["domain"].update({"min": lo, "max": hi, "periodic": [], "walls": ["x-", "x+", "y-", "y+", "z-"]})
    out["box: analytic walls"] = boxed
    box_mesh(folder / "box.stl", lo, hi)
    mesh_box = json.loads(json.dumps(boxed))
    mesh_box["domain"]["walls"] = "none"
    mesh_box["domain"]["min"] = [lo[0] - d, lo[1] - d, -d]
    mesh_box["domain"]["max"] = [hi[0] + d, hi[1] + d, 0.03]
    mesh_box["meshes"] = [{"file": str(folder / "box.stl")}]
    out["box: mesh walls"] = mesh_box
    return out


def main() -> None:
    args = [int(a) for a in sys.argv[1:]]
    n, rounds, steps, threads, triangles = (args + [200000, 6, 200, 2, 100000][len(args):])[:5]
    os.environ.setdefault("TI_CPU_MAX_NUM_THREADS", str(threads))
    from tidem.runtime.startup import ensure_taichi

    ensure_taichi("cpu", "float64", threads)
    import taichi as ti

    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver
    from tidem.studies.bench import advance

    folder = Path(tempfile.mkdtemp())
    variants = scenes(n, folder, triangles)
    solvers = {}
    for name, raw in variants.items():
        solvers[name] = Solver(build_model(validate(raw, "<bench>")))
        advance(solvers[name], 300)
    times = {name: [] for name in solvers}
    for _ in range(rounds):
        for name, s in solvers.items():
            ti.sync()
            t0 = time.perf_counter()
            advance(s, steps)
            ti.sync()
            times[name].append((time.perf_counter() - t0) / steps * 1e3)
    print(f"peer bed of {n} particles, {threads} threads, {rounds} rounds of {steps} steps (ms/step: median, best)")
    names = list(times)
    for k, name in enumerate(names):
        med, best = float(np.median(times[name])), min(times[name])
        ratio = ""
        if k % 2 == 1:
            ref = names[k - 1]
            ratio = (f"   mesh / analytic: {med / np.median(times[ref]):.3f} (median), "
                     f"{best / min(times[ref]):.3f} (best)")
        print(f"  {name:<34} {med:8.3f} {best:8.3f}{ratio}")


if __name__ == "__main__":
    main()
