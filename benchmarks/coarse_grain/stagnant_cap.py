"""Stagnant cap on the tube of the moving-bed verification (benchmarks/coarse_grain/moving_bed.sh).

    python benchmarks/coarse_grain/stagnant_cap.py RUN_DIR

For each variant's last snapshot: the share of the grains (parcels weighted by k^3) in the
10 mm layer on top of the tube (|x - x_t| < R, R < z - z_t < R + 10 mm) that move slower than
0.2 times the plate speed, and the mean sinking speed beside the tube at its height (the flank:
R < |x - x_t| < R + 5 mm, |z - z_t| < 5 mm, grain-weighted). Prints one Markdown row per variant.
"""

import csv
import re
import sys
from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp

X_T, Z_T, R_T, PLATE, GRAIN_D = 0.0185, 0.045, 0.0135, 0.02, 0.001


def cap_and_flank(snapshot: Path) -> tuple[float, float]:
    x, data = read_vtp(snapshot)
    grains = (2 * data["radius"] / GRAIN_D) ** 3
    speed = np.linalg.norm(data["velocity"], axis=1)
    dx, dz = np.abs(x[:, 0] - X_T), x[:, 2] - Z_T
    cap = (dx < R_T) & (dz > R_T) & (dz < R_T + 0.01)
    slow = cap & (speed < 0.2 * PLATE)
    flank = (dx > R_T) & (dx < R_T + 0.005) & (np.abs(dz) < 0.005)
    sink = -np.sum(grains[flank] * data["velocity"][flank, 2]) / grains[flank].sum()
    return grains[slow].sum() / grains[cap].sum(), sink


if __name__ == "__main__":
    run = Path(sys.argv[1])
    labels = {int(r["variant"]): re.sub(r"particles\[0\]\.", "", r["overrides"])
              for r in csv.DictReader(open(run / "tradeoff.csv"))}
    print("| variant | overrides | stagnant share of the cap | flank sinking speed, mm/s |\n|---|---|---|---|")
    for d in sorted(run.glob("variant_*")):
        last = sorted((d / "snapshots").glob("*.vtp"))[-1]
        share, sink = cap_and_flank(last)
        print(f"| {d.name} | {labels[int(d.name.split('_')[1])]} | {share:.2f} | {1000 * sink:.1f} |")
