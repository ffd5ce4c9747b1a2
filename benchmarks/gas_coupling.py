"""Cost of the gas coupling on the fluidized-bed scene: DEM-only steps against coupled steps
at several coupling intervals, measured side by side, alternating.

    python benchmarks/gas_coupling.py [--steps 2000] [--intervals 1,5,10,20,40] [--rounds 2]

Every case runs in its own process (fresh Taichi, warm offline cache) on the shipped
`fluidized_tube` scene after 2000 warm-up steps (the air on and the bed moving); "dem only"
is the same scene without its [gas] table (and without gas-particle heat exchange). Prints
one Markdown row per case: particle-steps/s and the cost of a step relative to DEM only.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

CASE = r"""
import json, sys, time, tomllib
from tidem.runtime.startup import ensure_taichi
ensure_taichi("cpu", "float64")
from tidem.sim.model import build_model
from tidem.scene.load import resolve, validate
from tidem.sim.solver import Solver
interval, steps = int(sys.argv[1]), int(sys.argv[2])
raw = tomllib.loads(resolve("fluidized_tube").read_text())
raw["gas"]["inlet_ramp"] = 0.0
if interval == 0:
    del raw["gas"]
else:
    raw["gas"]["coupling_interval"] = interval
s = Solver(build_model(validate(raw)))
for _ in range(2000):
    s.step()
t0 = time.perf_counter()
for _ in range(steps):
    s.step()
wall = time.perf_counter() - t0
print(json.dumps({"interval": interval, "rate": s.n * steps / wall, "wall": wall}))
"""


def run_case(interval: int, steps: int) -> dict:
    out = subprocess.run([sys.executable, "-c", CASE, str(interval), str(steps)], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--intervals", default="1,5,10,20,40")
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    cases = [0] + [int(v) for v in args.intervals.split(",")]
    results: dict[int, list[float]] = {c: [] for c in cases}
    for _ in range(args.rounds):
        for c in cases:
            results[c].append(run_case(c, args.steps)["rate"])
    base = sum(results[0]) / len(results[0])
    print(f"# {time.strftime('%Y-%m-%d %H:%M')}, {args.steps} timed steps, {args.rounds} rounds alternating")
    print("| case | particle-steps/s (each round) | step cost / DEM only |")
    print("|---|---|---|")
    for c in cases:
        mean = sum(results[c]) / len(results[c])
        name = "DEM only (no [gas])" if c == 0 else f"gas every {c} steps"
        print(f"| {name} | {', '.join(f'{r:.3g}' for r in results[c])} | {base / mean:.2f} |")


if __name__ == "__main__":
    main()
