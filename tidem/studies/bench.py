"""`tidem bench`: particle-steps per second on the dense settled bed of the peer benchmark.

The bed is the 10 000-sphere column of `benchmarks/settle_bed.toml`, settled by tidem and
stored in `benchmarks/bed10k.npz`, tiled laterally like `shared/bench/peers/tile_bed.py`
(10k: 1x1, 50k: 5x1, 200k: 5x4, 1M: 10x10 copies of the 20 d x 20 d column). The run uses the peer
code's settings: Hertz-Mindlin with tangential history, d = 1 mm, rho = 2600 kg/m3,
E = 1e7 Pa, nu = 0.3, e = 0.5, mu = 0.5, dt = 1e-6 s, skin 0.1 d, periodic in x and y.
Particles are stored in cell order (as LAMMPS' atom sorting does). Each case runs in its own process (own Taichi precision and thread count): 300 warm-up
steps, then the timed steps; peak resident memory of that process is reported too.

`profile_scene` (`tidem bench --profile SCENE`) times the steps of any scene by phase
(`tidem.runtime.phases`), after warm-up steps that compile every kernel, with no output written.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from tidem.particles.placement import spatial_key
from tidem.sim.memory import peak_resident_bytes

BED = Path(__file__).resolve().parent.parent / "benchmarks" / "bed10k.npz"
TILES = {10000: (1, 1), 50000: (5, 1), 200000: (5, 4), 1000000: (10, 10)}
COLUMN = 0.02  # m, lateral size of the settled column


def read_lammps_bed(path: Path) -> tuple[np.ndarray, tuple[float, float]]:
    """Positions and x/y extent from a LAMMPS/LIGGGHTS granular data file
    (`id type diameter density x y z` atoms, as written by shared/bench/peers/tile_bed.py)."""
    lines = Path(path).read_text().splitlines()
    extent = [0.0, 0.0]
    for line in lines[:20]:
        parts = line.split()
        if len(parts) == 4 and parts[2] in ("xlo", "ylo"):
            extent["xy".index(parts[2][0])] = float(parts[1]) - float(parts[0])
    start = next(k for k, line in enumerate(lines) if line.strip() == "Atoms") + 1
    atoms = np.loadtxt(lines[start:], ndmin=2)
    atoms = atoms[np.argsort(atoms[:, 0])]
    return atoms[:, 4:7], (extent[0], extent[1])


def tiled_bed(n: int, bed: Path | None = None) -> tuple[np.ndarray, tuple[float, float]]:
    """Positions of an n-particle bed tiled from the settled 10k column, and its x/y extent;
    or the bed of a LAMMPS data file when `bed` is given."""
    if bed is not None and Path(bed).suffix == ".data":
        x, extent = read_lammps_bed(bed)
        return x[np.argsort(spatial_key(x, (0.0, 0.0, 0.0), 0.0011), kind="stable")], extent
    base = np.load(bed or BED)["x"]
    tx, ty = TILES.get(n, (max(1, round(n / len(base))), 1))
    tiles = [base + [i * COLUMN, j * COLUMN, 0.0] for j in range(ty) for i in range(tx)]
    x = np.concatenate(tiles)
    return x[np.argsort(spatial_key(x, (0.0, 0.0, 0.0), 0.0011), kind="stable")], (tx * COLUMN, ty * COLUMN)


def bench_scene(x: np.ndarray, extent, precision: str) -> dict:
    return {
        "name": f"bench_{len(x)}",
        "domain": {"min": [0.0, 0.0, 0.0], "max": [extent[0], extent[1], 0.03], "periodic": ["x", "y"], "walls": ["z-"]},
        "contact": {"model": "hertz_mindlin"},
        "materials": {"glass": {"density": 2600.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3,
                                "restitution": 0.5, "friction": 0.5}},
        "particles": [{"name": "bed", "material": "glass", "diameter": {"distribution": "mono", "value": 0.001},
                       "positions": x.tolist()}],
        "numerics": {"dt": 1e-6, "precision": precision, "skin": 0.1},
    }


def advance(solver, steps: int) -> None:
    """Take `steps` steps in the windows the run loop uses between progress updates (no outputs)."""
    last = solver.steps + steps
    while solver.steps < last:
        solver.advance(solver.steps_until(lambda t: False, 50, last))


def run_case(n: int, precision: str, steps: int, threads: int, bed: str | None = None, arch: str = "cpu") -> dict:
    """Time one case in this process (called in a child process by `run_matrix`) on Taichi's `arch`."""
    from tidem.runtime.startup import ensure_taichi

    ensure_taichi(arch, precision, threads)
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    x, extent = tiled_bed(n, Path(bed) if bed else None)
    model = build_model(validate(bench_scene(x, extent, precision), "<bench>"))
    solver = Solver(model)
    advance(solver, 300)
    import taichi as ti

    ti.sync()
    t0 = time.perf_counter()
    advance(solver, steps)
    ti.sync()
    wall = time.perf_counter() - t0
    rss = peak_resident_bytes()
    e = solver.energies()
    return {"particles": len(x), "precision": precision, "arch": arch, "threads": threads, "steps": steps, "loop_s": wall,
            "particle_steps_per_s": len(x) * steps / wall, "rebuilds": solver.rebuilds,
            "contacts_per_particle": float(e["coordination"]), "field_bytes_per_particle": model.memory_bytes() / len(x),
            "peak_rss_MiB": rss / 2**20}


def run_matrix(sizes: list[int], precisions: list[str], steps: int, threads: int, out: Path | None,
               bed: Path | None = None, arch: str = "cpu") -> list[dict]:
    """Run every (size, precision) case in a fresh process on Taichi's `arch` and print a table."""
    if bed is not None:
        sizes = [len(tiled_bed(0, bed)[0])]
    rows = []
    print(f"{'N':>8} {'precision':>9} {'threads':>7} {'steps':>6} {'loop s':>8} {'particle-steps/s':>17} "
          f"{'B/particle (fields)':>20} {'peak RSS MiB':>12}")
    # each case's child imports the tidem this process runs (not one in its working folder)
    root = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ, TI_CPU_MAX_NUM_THREADS=str(threads),
               PYTHONPATH=os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    for n in sizes:
        for prec in precisions:
            k = max(200, steps * 10000 // max(n, 10000) if n > 50000 else steps)
            proc = subprocess.run([sys.executable, "-P", "-c", f"import json, tidem.studies.bench as b; "
                                   f"print(json.dumps(b.run_case({n}, '{prec}', {k}, {threads}, {str(bed) if bed else None!r}, '{arch}')))"],
                                  capture_output=True, text=True, env=env)
            if proc.returncode != 0:
                last = proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else ""
                kind, _, message = last.partition(": ")  # the exception's class, then its message
                print(f"{n:>8} {prec:>9} failed: {message if message and ' ' not in kind else last}")
                continue
            row = json.loads(proc.stdout.strip().splitlines()[-1])
            rows.append(row)
            print(f"{n:>8} {prec:>9} {threads if arch == 'cpu' else arch:>7} {k:>6} {row['loop_s']:>8.2f} {row['particle_steps_per_s']:>17.3g} "
                  f"{row['field_bytes_per_particle']:>20.0f} {row['peak_rss_MiB']:>12.0f}", flush=True)
    if out is not None:
        Path(out).write_text(json.dumps(rows, indent=2))
    return rows


def profile_scene(loaded, steps: int, warmup: int, model=None, resume: tuple[dict, dict] | None = None,
                  split: bool = True, prepare=None) -> dict:
    """Run `warmup` steps of a loaded scene (from a checkpoint `resume`, `tidem.runner.checkpoint.load`,
    if given), then `steps` timed steps by phase; returns {scene, particles, steps, wall_s,
    particle_steps_per_s, profile}. With `split` the contact passes and the kick run as kernels
    of their own, so that the profile tells them apart (a run takes them in one launch).
    `prepare`: a function of the new solver called before the steps (a benchmark's own restore).
    Taichi must be initialised."""
    import taichi as ti

    from tidem.runner import checkpoint
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    model = model or build_model(loaded)
    solver = Solver(model)
    if resume is not None:
        checkpoint.restore(solver, *resume)
    if prepare is not None:
        prepare(solver)
    solver.timer.sync = ti.lang.impl.current_cfg().arch != ti.cpu
    solver.split_passes = split
    advance(solver, warmup)
    ti.sync()
    solver.timer.reset()
    t0 = time.perf_counter()
    advance(solver, steps)
    ti.sync()
    wall = time.perf_counter() - t0
    n = int(solver.state.active.to_numpy().sum())
    solver.release()
    return {"scene": model.name, "particles": n, "steps": steps, "wall_s": wall,
            "particle_steps_per_s": n * steps / wall, "profile": solver.timer.table(steps)}
