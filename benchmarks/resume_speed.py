"""Whole steps of a scene from a run's checkpoint, in the windows a run takes (no outputs, no
per-phase split): the figure to compare two trees side by side.

    python benchmarks/resume_speed.py SCENE RUN_DIR [STEPS [THREADS]]

RUN_DIR holds a checkpoint.npz of SCENE (e.g. `tidem scene fluidized_tube --t-end 0.3 --out RUN_DIR
--no-render`). Runs 100 untimed steps (compiling every kernel), then STEPS (default 2000), and
prints ms per step and particle-steps/s. For a tree other than the installed one, run it with
`env PYTHONPATH=TREE python -P benchmarks/resume_speed.py ...` from a folder without a tidem tree.
"""

import sys
import time
from pathlib import Path

from tidem import checkpoint
from tidem.bench import advance
from tidem.cli import _checkpoint
from tidem.cli_common import build_or_exit, load_scene
from tidem.runtime import ensure_taichi
from tidem.solver import Solver


def main(scene: str, run_dir: str, steps: int = 2000, threads: int = 2) -> None:
    loaded = load_scene(scene, [])
    ensure_taichi("cpu", loaded.scene.numerics.precision, threads)
    model = build_or_exit(loaded)
    solver = Solver(model)
    checkpoint.restore(solver, *_checkpoint(Path(run_dir), loaded, model))
    advance(solver, 100)
    t0 = time.perf_counter()
    advance(solver, steps)
    wall = time.perf_counter() - t0
    n = int(solver.state.active.to_numpy().sum())
    print(f"{scene}: {n} particles, {steps} steps, {threads} threads: {1e3 * wall / steps:.3f} ms per step, "
          f"{n * steps / wall:.3g} particle-steps/s")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *map(int, sys.argv[3:5]))
