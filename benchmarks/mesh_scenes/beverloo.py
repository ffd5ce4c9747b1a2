#!/usr/bin/env python3
"""hopper_discharge at several slot widths, and the fit of Beverloo's slot form
    W = C rho_b sqrt(g) L (b - k d)^n
to the discharge rates: for each k on a grid, n and C by least squares in logs; the k of the
smallest residual wins (n = 3/2 in Beverloo's law). Also the early/late halves of each run's
window (the rate must not depend on the fill height).

Usage (from the repository root):
    python benchmarks/mesh_scenes/beverloo.py OUT_DIR [b_mm ...]     (default 24 32 48 64 80 mm: 6-20 d)
Writes OUT_DIR/b<b>/ (the runs), OUT_DIR/beverloo.csv and OUT_DIR/beverloo.png.
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

D = 0.004  # mean bead diameter [m]
L = 0.02  # slot length (the slab's period) [m]
HALF = 0.1  # half the plate width: a plate at +-(HALF + b/2) leaves a slot b


def run(out: Path, b: float) -> dict:
    folder = out / f"b{b * 1e3:.0f}"
    if not (folder / "run.json").exists():
        off = HALF + b / 2
        subprocess.run([sys.executable, "-m", "tidem", "scene", "hopper_discharge", "--no-render", "--out", str(folder),
                        "--set", f"meshes[0].offset=[{-off},0.0,0.0]", "--set", f"meshes[1].offset=[{off},0.0,0.0]"],
                       check=True)
    obs = json.loads((folder / "run.json").read_text())["observables"]["discharge_rate"]
    return dict(b=b, rate=obs["discharge_rate_kg_s"], early=obs["discharge_rate_early_kg_s"],
                late=obs["discharge_rate_late_kg_s"])


def fit(b: np.ndarray, w: np.ndarray) -> dict:
    """Best (k, n, C') of W = C' (b - k d)^n over k in [0, 3] (C' = C rho_b sqrt(g) L)."""
    best = None
    for k in np.linspace(0.0, 3.0, 301):
        x = b - k * D
        if (x <= 0).any():
            break
        n, logc = np.polyfit(np.log(x), np.log(w), 1)
        res = float(np.sum((np.log(w) - (logc + n * np.log(x))) ** 2))
        if best is None or res < best["residual"]:
            best = dict(k=float(k), n=float(n), c=float(math.exp(logc)), residual=res)
    return best


def main() -> None:
    out = Path(sys.argv[1])
    widths = [float(a) * 1e-3 for a in sys.argv[2:]] or [0.024, 0.032, 0.048, 0.064, 0.080]
    out.mkdir(parents=True, exist_ok=True)
    rows = [run(out, b) for b in widths]
    b = np.array([r["b"] for r in rows])
    w = np.array([r["rate"] for r in rows])
    best = fit(b, w)
    n_fixed, logc_fixed = np.polyfit(np.log(b - 1.5 * D), np.log(w), 1)
    with open(out / "beverloo.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["b_m", "b_over_d", "rate_kg_s", "early_kg_s", "late_kg_s", "late_over_early"])
        for r in rows:
            wr.writerow([r["b"], r["b"] / D, r["rate"], r["early"], r["late"], r["late"] / r["early"]])
    summary = dict(best_fit=best, n_at_k_1_5=float(n_fixed), widths_m=list(b), rates_kg_s=list(w))
    (out / "beverloo.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.loglog(b - best["k"] * D, w, "o", label="tidem, hopper_discharge")
    x = np.linspace((b - best["k"] * D).min(), (b - best["k"] * D).max(), 50)
    ax.loglog(x, best["c"] * x ** best["n"], "-", label=f"fit: n = {best['n']:.2f}, k = {best['k']:.2f}")
    ax.loglog(x, best["c"] * x ** 1.5 * (w[-1] / (best["c"] * (b[-1] - best["k"] * D) ** 1.5)), ":",
              label="n = 3/2 (Beverloo), through the widest")
    ax.set_xlabel("b - k d [m]")
    ax.set_ylabel("discharge rate W [kg/s]")
    ax.set_title(f"Slot of length L = {L * 1e3:.0f} mm, beads d = {D * 1e3:.0f} mm")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "beverloo.png", dpi=110)


if __name__ == "__main__":
    main()
