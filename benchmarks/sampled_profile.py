"""How truly a GPU run's sampled profile books each phase, tried on the CPU, where every lap is exact.

A run on a GPU waits at the phase edges of one step in SAMPLE_EVERY only and shares the steps' time
out as those steps share theirs (`tidem.runtime.phases`). Here a scene's steps from a checkpoint run as a run
takes them (the fused force pass), every lap of every step is recorded, and the exact time per phase
is compared with what each way of choosing the sampled steps would book: every 16th step (before
2026-11-28) and `tidem.runtime.phases.sampled_step` (evenly over the multiples of every interval).

    python benchmarks/sampled_profile.py SCENE RUN_DIR [STEPS [THREADS]] [KEY=VALUE ...]

RUN_DIR holds a checkpoint.npz of SCENE; KEY=VALUE are `--set`s (numerics.t_end beyond the
checkpoint's time, say). Prints ms a step per phase: exact, and booked by each rule with its ratio.
"""

import sys
from pathlib import Path

import numpy as np
import taichi as ti

from tidem.cli.common import build_or_exit, load_scene, script_main
from tidem.runner import checkpoint
from tidem.runner.launch import InputError, load_checkpoint
from tidem.runtime import startup
from tidem.runtime.phases import SAMPLE_EVERY, STEP_PHASES, PhaseTimer, clock, sampled_step
from tidem.sim.solver import Solver
from tidem.studies.bench import advance

RULES = {"every 16th step": lambda step: step % SAMPLE_EVERY == 0,
         "sampled_step": lambda step: sampled_step(step, SAMPLE_EVERY)}


class LapRecorder(PhaseTimer):
    """A PhaseTimer that keeps every step's laps (seconds per phase) by step number."""

    def __init__(self):
        super().__init__()
        self.laps: dict[int, np.ndarray] = {}
        self._row = None

    def begin_step(self, step: int) -> float:
        self._row = self.laps.setdefault(step, np.zeros(len(STEP_PHASES)))
        return clock()

    def lap(self, phase: str, start: float) -> float:
        now = clock()
        if phase in STEP_PHASES and self._row is not None:
            self._row[STEP_PHASES.index(phase)] += now - start
        return now


def main(scene: str, run_dir: str, steps: int = 4000, threads: int = 2, sets: list[str] = ()) -> None:
    loaded = load_scene(scene, list(sets))
    precision = loaded.scene.numerics.precision
    ti.init(arch=ti.cpu, default_fp=ti.f64 if precision == "float64" else ti.f32, default_ip=ti.i32,
            cpu_max_num_threads=threads, offline_cache=True, log_level=ti.ERROR)
    startup._current = ("cpu", precision, threads)
    model = build_or_exit(loaded)
    try:
        start = load_checkpoint(Path(run_dir), loaded, model)
    except InputError as exc:
        sys.exit(f"tidem: {exc}")
    solver = Solver(model)
    checkpoint.restore(solver, *start)
    advance(solver, 50)
    solver.timer = LapRecorder()
    if solver.gas is not None:
        solver.gas.timer = solver.timer  # the gas phase books its laps in the solver's timer
    advance(solver, steps)
    numbers = np.array(sorted(solver.timer.laps))
    laps = np.array([solver.timer.laps[s] for s in numbers])
    exact = laps.sum(axis=0)
    print(f"{model.name}: {steps} steps from t = {start[0]['solver']['t']:.4g} s, {threads} threads; ms a step")
    header = f"{'phase':<20} {'exact':>8}" + "".join(f" {name:>16} {'ratio':>6}" for name in RULES)
    print(header)
    booked = {}
    for name, rule in RULES.items():
        chosen = np.array([rule(int(s)) for s in numbers])
        share = laps[chosen].sum(axis=0)
        booked[name] = exact.sum() * share / share.sum()
        print(f"# {name}: {chosen.sum()} sampled steps")
    for i, phase in enumerate(STEP_PHASES):
        if exact[i] <= 1e-4 * exact.sum():
            continue
        row = f"{phase:<20} {1e3 * exact[i] / steps:8.3f}"
        for name in RULES:
            row += f" {1e3 * booked[name][i] / steps:16.3f} {booked[name][i] / exact[i]:6.2f}"
        print(row)


if __name__ == "__main__":
    script_main(main)
