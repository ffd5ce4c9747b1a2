"""The contact passes (in a scene with heat also without the conduction, as between two
evaluations of it), the passes with the kick and the next step's kick-drift in one launch (as a
run's step takes them, where the scene has no reactions) and the neighbour build, each called
again and again on one fixed state (a scene's checkpoint): the cleanest figure for a change to one
of these kernels, since neither the state nor the work changes between calls.

    python benchmarks/kernel_repeat.py SCENE RUN_DIR [CALLS [THREADS]]
    python benchmarks/kernel_repeat.py peer:N - [CALLS [THREADS]]

RUN_DIR holds a checkpoint.npz of SCENE (e.g. `tidem scene fluidized_tube --t-end 0.3 --out RUN_DIR
--no-render`); `peer:N` is instead the N-particle peer benchmark bed of `tidem bench` (float64, after
its 300 warm-up steps). Takes 20 steps, then times CALLS (default 100) calls of each kernel after one
untimed call and prints the minimum, 20th percentile and median in ms. The passes take a time step of
zero: the same work as a step, but the springs do not grow and the particles do not move from call
to call (with the step's dt, some hundreds of calls on one state stretch them until the contacts
slide, which costs more square roots and divisions than a step does). For a tree other than the
installed one, run it with `env PYTHONPATH=TREE python -P benchmarks/kernel_repeat.py ...` from a folder
without a tidem tree.
"""

import sys
import time
from pathlib import Path

import numpy as np
import taichi as ti
import typer

from tidem.cli.common import build_or_exit, load_scene
from tidem.runner import checkpoint
from tidem.runner.launch import InputError, load_checkpoint
from tidem.runtime.startup import ensure_taichi
from tidem.scene.load import validate
from tidem.sim.model import build_model
from tidem.sim.solver import Solver
from tidem.studies.bench import advance, bench_scene, tiled_bed


def main(scene: str, run_dir: str, calls: int = 100, threads: int = 2) -> None:
    if scene.startswith("peer:"):
        ensure_taichi("cpu", "float64", threads)
        x, extent = tiled_bed(int(scene.removeprefix("peer:")))
        solver = Solver(build_model(validate(bench_scene(x, extent, "float64"), "<bench>")))
        advance(solver, 300)
    else:
        loaded = load_scene(scene, [])
        ensure_taichi("cpu", loaded.scene.numerics.precision, threads)
        model = build_or_exit(loaded)
        solver = Solver(model)
        checkpoint.restore(solver, *load_checkpoint(Path(run_dir), loaded, model))
    model = solver.model
    advance(solver, 20)
    n, t, dt = solver.n, solver.t, 0.0  # module docstring: the history stays as it is
    # as most steps run it: no contact counts and overlaps for the host (kernels/contact.py)
    kernels = {"contact passes": lambda: solver._forces(n, t, dt, 1, 0)}
    if solver._forces_and_kick is not None:  # as a run's step takes them: with the kick and the next kick-drift
        kernels["passes, kick and kick-drift"] = lambda: solver._forces_and_kick(n, t, dt, 1, 0, 1, 1)
    if model.features.heat:  # a step between two evaluations of the conduction (heat.conduction_interval)
        kernels["contact passes without conduction"] = lambda: solver._forces(n, t, dt, 0, 0)
    if solver._rebuild is not None:
        kernels["neighbour build"] = lambda: solver._rebuild(n)
    for name, call in kernels.items():
        call()
        ti.sync()
        ms = []
        for _ in range(calls):
            t0 = time.perf_counter()
            call()
            ti.sync()
            ms.append(1e3 * (time.perf_counter() - t0))
        print(f"{scene} {name}: min {min(ms):.3f}, p20 {np.percentile(ms, 20):.3f}, median {np.median(ms):.3f} ms "
              f"({calls} calls, {threads} threads)")


if __name__ == "__main__":
    try:
        main(sys.argv[1], sys.argv[2], *map(int, sys.argv[3:5]))
    except typer.Exit as stop:  # the scene was refused; the reason is printed
        sys.exit(stop.exit_code)
    except InputError as exc:  # the checkpoint was refused
        sys.exit(f"tidem: {exc}")
