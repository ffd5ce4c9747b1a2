"""Summarise `gpu_mesh_check.sh`'s runs: for each scene, its GPU and CPU runs' status, steps, rate and
every observable of run.json side by side with their relative difference.
Usage: python3 benchmarks/gpu_mesh_summary.py RUNS"""

import json
import sys
from pathlib import Path

from tidem.results.observables import flatten


def read(run: Path) -> dict | None:
    path = run / "run.json"
    return json.loads(path.read_text()) if path.is_file() else None


def compare(scene: str, gpu: dict | None, cpu: dict | None) -> list[str]:
    lines = [f"## {scene}"]
    for kind, run in (("gpu", gpu), ("cpu", cpu)):
        if run is None:
            lines.append(f"  {kind}: no run.json (see gpu_mesh_check.log)")
        else:
            lines.append(f"  {kind}: {run['status']}, {run['steps']} steps of {run['particles']} particles, "
                         f"{run['particle_steps_per_s']:.3g} particle-steps/s, wall {run['wall_s']:.1f} s")
    if gpu is None or cpu is None:
        return lines
    if gpu["particle_steps_per_s"] and cpu["particle_steps_per_s"]:
        lines.append(f"  gpu / cpu rate: {gpu['particle_steps_per_s'] / cpu['particle_steps_per_s']:.2f}")
    a, b = flatten(gpu.get("observables", {})), flatten(cpu.get("observables", {}))
    for name in sorted(a.keys() & b.keys()):
        scale = max(abs(a[name]), abs(b[name]))
        rel = abs(a[name] - b[name]) / scale if scale else 0.0
        lines.append(f"  {name:40s} gpu {a[name]:<14.6g} cpu {b[name]:<14.6g} rel. diff {rel:.2e}")
    return lines


def main(runs: Path) -> None:
    scenes = sorted({p.name[: -len("_gpu")] for p in runs.glob("*_gpu") if p.is_dir()})
    for scene in scenes:
        print("\n".join(compare(scene, read(runs / f"{scene}_gpu"), read(runs / f"{scene}_cpu"))))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
