"""Time per Taichi kernel of a scene's steps from a checkpoint (Taichi's kernel profiler), one
level below `tidem bench --profile`'s phases.

    python benchmarks/kernel_profile.py SCENE RUN_DIR [STEPS [THREADS]] [KEY=VALUE ...]
    python benchmarks/kernel_profile.py peer:N - [STEPS [THREADS]]

RUN_DIR holds a checkpoint.npz of SCENE (e.g. `tidem scene fluidized_tube --t-end 0.3 --out RUN_DIR
--no-render`); `peer:N` is instead the N-particle peer benchmark bed of `tidem bench` (float64,
from rest). Runs 50 warm-up steps (300 for the peer bed), then STEPS (default 1000) with THREADS
(default 2) CPU threads, and prints the kernels by total time (the counts include the warm-up;
the profiler adds a little time to each launch), then the median and 10th percentile of a launch of
the costliest ones.
"""

import sys
from pathlib import Path

import numpy as np
import taichi as ti
from taichi.lang import impl

from tidem.cli.common import build_or_exit, load_scene, script_main
from tidem.runner.launch import InputError, load_checkpoint
from tidem.runtime import startup
from tidem.scene.load import validate
from tidem.sim.model import build_model
from tidem.studies.bench import bench_scene, profile_scene, tiled_bed


def main(scene: str, run_dir: str, steps: int = 1000, threads: int = 2, sets: list[str] = ()) -> None:
    peer = int(scene.removeprefix("peer:")) if scene.startswith("peer:") else 0
    loaded = None if peer else load_scene(scene, list(sets))
    precision = "float64" if peer else loaded.scene.numerics.precision
    ti.init(arch=ti.cpu, default_fp=ti.f64 if precision == "float64" else ti.f32, default_ip=ti.i32,
            cpu_max_num_threads=threads, offline_cache=True, kernel_profiler=True, log_level=ti.ERROR)
    startup._current = ("cpu", precision, threads)  # tidem's own init would reset the profiler
    if peer:
        x, extent = tiled_bed(peer)
        model = build_model(validate(bench_scene(x, extent, precision), "<bench>"))
        result = profile_scene(None, steps, 300, model)
    else:
        model = build_or_exit(loaded)
        try:
            start = load_checkpoint(Path(run_dir), loaded, model)
        except InputError as exc:
            sys.exit(f"tidem: {exc}")
        result = profile_scene(loaded, steps, 50, model, start)
    print(f"{result['scene']}: {result['particles']} particles, {steps} steps, {threads} threads, "
          f"{result['particle_steps_per_s']:.3g} particle-steps/s")
    ti.profiler.print_kernel_profiler_info("count")
    print_quantiles()


def print_quantiles(top: int = 8) -> None:
    """Median and 10th percentile of each launch's time for the kernels of most total time: on a noisy VM
    a moment's slowing shifts the mean, much less these."""
    times: dict[str, list[float]] = {}
    for record in impl.get_runtime().prog.get_kernel_profiler_records():
        times.setdefault(record.name, []).append(record.kernel_time)
    print("kernel (launches): median, 10th percentile of a launch [ms]")
    for name, t in sorted(times.items(), key=lambda item: -sum(item[1]))[:top]:
        print(f"  {name} ({len(t)}): {np.median(t):.3f}, {np.percentile(t, 10):.3f}")


if __name__ == "__main__":
    script_main(main)
