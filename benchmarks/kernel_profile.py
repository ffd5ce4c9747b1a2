"""Time per Taichi kernel of a scene's steps from a checkpoint (Taichi's kernel profiler), one
level below `tidem bench --profile`'s phases.

    python benchmarks/kernel_profile.py SCENE RUN_DIR [STEPS [THREADS]] [KEY=VALUE ...]

RUN_DIR holds a checkpoint.npz of SCENE (e.g. `tidem scene fluidized_tube --t-end 0.3 --out RUN_DIR
--no-render`). Runs 50 warm-up steps, then STEPS (default 1000) with THREADS (default 2) CPU
threads, and prints the kernels by total time (the counts include the warm-up; the profiler adds a
little time to each launch).
"""

import sys
from pathlib import Path

import taichi as ti

from tidem import runtime
from tidem.bench import profile_scene
from tidem.cli import _checkpoint
from tidem.cli_common import build_or_exit, load_scene


def main(scene: str, run_dir: str, steps: int = 1000, threads: int = 2, sets: list[str] = ()) -> None:
    loaded = load_scene(scene, list(sets))
    fp = ti.f64 if loaded.scene.numerics.precision == "float64" else ti.f32
    ti.init(arch=ti.cpu, default_fp=fp, default_ip=ti.i32, cpu_max_num_threads=threads, offline_cache=True,
            kernel_profiler=True, log_level=ti.ERROR)
    runtime._current = ("cpu", loaded.scene.numerics.precision, threads)  # tidem's own init would reset the profiler
    model = build_or_exit(loaded)
    start = _checkpoint(Path(run_dir), loaded, model)
    result = profile_scene(loaded, steps, 50, model, start)
    print(f"{result['scene']}: {result['particles']} particles, {steps} steps, {threads} threads, "
          f"{result['particle_steps_per_s']:.3g} particle-steps/s")
    ti.profiler.print_kernel_profiler_info("count")


if __name__ == "__main__":
    args = sys.argv[1:]
    numbers = [a for a in args[2:4] if a.isdigit()]
    main(args[0], args[1], *map(int, numbers), sets=args[2 + len(numbers):])
