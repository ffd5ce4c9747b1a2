"""Summarise `gpu_lab_bed.sh`'s runs: each run's run.json (status, steps, rate, profile), the stepping
rate over stretches of bed time from the snapshots' write times (the snapshot files are written as
the run passes their times, so two files' times bracket the steps between them), the synchronised
profile, and the full run's observables.
Usage: python3 benchmarks/gpu_lab_bed_summary.py RUNS OUT"""

import json
import re
import sys
from pathlib import Path

STRETCHES = [(0.1, 0.3), (0.3, 0.5), (0.5, 1.0), (0.1, 1.0)]


def snapshot_times(run: Path) -> list[tuple[float, float]]:
    """(bed time, write time) of every snapshot the run folder's collection file lists that exists."""
    pvd = run / "snapshots.pvd"
    if not pvd.is_file():
        return []
    found = re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', pvd.read_text())
    return [(float(t), (run / f).stat().st_mtime) for t, f in found if (run / f).is_file()]


def stretch_rates(run: Path, dt: float, particles: int) -> list[str]:
    """ms a step and particle-steps/s between the snapshots nearest each stretch's ends."""
    times = snapshot_times(run)
    lines = []
    for a, b in STRETCHES:
        inside = [(t, w) for t, w in times if a - 1e-3 <= t <= b + 1e-3]
        if len(inside) < 2 or inside[-1][0] - inside[0][0] < 0.5 * (b - a):
            continue
        (t0, w0), (t1, w1) = inside[0], inside[-1]
        steps = (t1 - t0) / dt
        lines.append(f"  {t0:.3f}-{t1:.3f} s: {steps:.0f} steps in {w1 - w0:.1f} s, {1e3 * (w1 - w0) / steps:.3f} "
                     f"ms/step, {particles * steps / (w1 - w0):.3g} particle-steps/s")
    return lines


def profile_line(profile: dict) -> str:
    return ", ".join(f"{k} {v['ms_per_step']:.3f}" for k, v in profile.items())


def main(runs: Path, out: Path) -> None:
    for name in ("full", "resume", "base"):
        path = runs / name / "run.json"
        if not path.is_file():
            continue
        d = json.loads(path.read_text())
        print(f"{name}: {d['status']}, t {d.get('time_s')}, {d.get('steps')} steps, wall {d.get('wall_s', 0):.1f} s, "
              f"setup {d.get('setup_s', 0):.1f} s, {d.get('particle_steps_per_s', 0):.3g} particle-steps/s")
        print(f"  run profile, ms/step: {profile_line(d.get('profile', {}))}")
        for line in stretch_rates(runs / name, d["dt_s"], d["particles"]):
            print(line)
        if name == "full":
            print("  observables: " + json.dumps(d.get("observables", {})))
    path = out / "profile.json"
    if path.is_file():
        d = json.loads(path.read_text())
        print(f"profile: {d['particle_steps_per_s']:.3g} particle-steps/s; ms/step: {profile_line(d['profile'])}")


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
