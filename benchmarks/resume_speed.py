"""Whole steps of a scene from a run's checkpoint, in the windows a run takes (the contacts' own
pass and the kick in one launch, unlike `tidem bench --profile`): the figure to compare two trees
side by side.

    python benchmarks/resume_speed.py SCENE RUN_DIR [STEPS [THREADS]]

RUN_DIR holds a checkpoint.npz of SCENE (e.g. `tidem scene fluidized_tube --t-end 0.3 --out RUN_DIR
--no-render`). Runs 100 untimed steps (compiling every kernel), then STEPS (default 2000), and
prints ms per step and particle-steps/s. For a tree other than the installed one, run it with
`env PYTHONPATH=TREE python -P benchmarks/resume_speed.py ...` from a folder without a tidem tree.
"""

import sys
from pathlib import Path

import typer

from tidem.cli.common import build_or_exit, load_scene
from tidem.runner.launch import InputError, load_checkpoint
from tidem.runtime.startup import ensure_taichi
from tidem.studies.bench import profile_scene


def main(scene: str, run_dir: str, steps: int = 2000, threads: int = 2) -> None:
    loaded = load_scene(scene, [])
    ensure_taichi("cpu", loaded.scene.numerics.precision, threads)
    model = build_or_exit(loaded)
    r = profile_scene(loaded, steps, 100, model, load_checkpoint(Path(run_dir), loaded, model), split=False)
    print(f"{scene}: {r['particles']} particles, {steps} steps, {threads} threads: "
          f"{1e3 * r['wall_s'] / steps:.3f} ms per step, {r['particle_steps_per_s']:.3g} particle-steps/s")


if __name__ == "__main__":
    try:
        main(sys.argv[1], sys.argv[2], *map(int, sys.argv[3:5]))
    except typer.Exit as stop:  # the scene was refused; the reason is printed
        sys.exit(stop.exit_code)
    except InputError as exc:  # the checkpoint was refused
        sys.exit(f"tidem: {exc}")
