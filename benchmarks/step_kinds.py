"""Wall time of each step of a scene from a checkpoint, grouped by what the step does: a plain step,
one with a neighbour build, a gas step, a conduction evaluation, a health check (and their
combinations). Shows where a run's time goes beyond its contact passes, each kind's extra cost over
a plain step, and the variance that a phase profile averages away.

    python -P benchmarks/step_kinds.py SCENE RUN_DIR [STEPS [THREADS]]

RUN_DIR holds a checkpoint.npz of SCENE (e.g. `tidem scene fluidized_tube --t-end 0.3 --out RUN_DIR
--no-render`). Takes 200 steps to warm up, then STEPS (default 3000) one at a time, as the run loop
does between outputs (each step's kick goes on into the next kick-drift only within `advance`; here
every step is its own call, so the figures include that launch's round trip).
"""

import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from tidem.cli.common import build_or_exit, load_scene
from tidem.runner import checkpoint
from tidem.runner.launch import load_checkpoint
from tidem.runtime import startup
from tidem.sim.solver import Solver


def main(scene: str, run_dir: str, steps: int = 3000, threads: int = 2) -> None:
    startup.ensure_taichi("cpu", "float64", threads)
    loaded = load_scene(scene, [])
    model = build_or_exit(loaded)
    solver = Solver(model)
    checkpoint.restore(solver, *load_checkpoint(Path(run_dir), loaded, model))
    solver.advance(200)
    built = [False]
    rebuild = solver.rebuild

    def noted_rebuild(*args):
        built[0] = True
        return rebuild(*args)

    solver.rebuild = noted_rebuild
    gas_every = solver.gas.interval if solver.gas is not None else 0
    conduct_every = solver._conduct_every if model.features.heat else 0
    kinds = defaultdict(list)
    for _ in range(steps):
        built[0] = False
        step = solver.steps + 1
        start = time.perf_counter()
        solver.advance(1)
        wall = time.perf_counter() - start
        kind = [name for name, on in (("gas", gas_every and step % gas_every == 0), ("build", built[0]),
                                      ("conduct", conduct_every > 1 and (step - 1) % conduct_every == 0),
                                      ("check", step % solver._check_every == 0)) if on]
        kinds[" + ".join(kind) or "plain"].append(wall * 1e3)
    total = sum(sum(v) for v in kinds.values())
    plain = np.median(kinds["plain"]) if kinds["plain"] else 0.0
    print(f"{scene}: {solver.n} particles, {steps} steps, {threads} threads, {total / steps:.3f} ms a step")
    for kind, walls in sorted(kinds.items(), key=lambda kv: -sum(kv[1])):
        w = np.array(walls)
        print(f"  {kind:28s} {len(w):5d} steps  median {np.median(w):7.3f}  mean {w.mean():7.3f}  min {w.min():7.3f} ms"
              f"  (+{np.median(w) - plain:6.3f} over plain)  {w.sum() / total:6.1%} of the time")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *(int(a) for a in sys.argv[3:5]))
