#!/usr/bin/env python3
"""hopper_discharge at several slot widths, and the fit of Beverloo's slot form
    W = C rho_b sqrt(g) L (b - k d)^n
to the discharge rates: for each k on a grid, n and C by least squares in logs; the k of the
smallest residual wins (n = 3/2 in Beverloo's law). Also the early/late halves of each run's
window (the rate must not depend on the fill height).

Usage (from the repository root):
    python benchmarks/mesh_scenes/beverloo.py OUT_DIR [FILL_m [b_mm ...]]
FILL_m: the height the bin is filled to (default 0.25 m, the scene's; the domain reaches 0.05 m
above it); b_mm: the slot widths (default 24 32 48 64 80 mm: 6-20 d).
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

from tidem.render.plots import read_series
from tidem.results.observables import RunRecord, discharge_rate

D = 0.004  # mean bead diameter [m]
L = 0.02  # slot length (the slab's period) [m]
HALF = 0.1  # half the plate width: a plate at +-(HALF + b/2) leaves a slot b


def run(out: Path, b: float, fill: float) -> dict:
    folder = out / f"b{b * 1e3:.0f}"
    if not (folder / "run.json").exists():
        off = HALF + b / 2
        subprocess.run([sys.executable, "-m", "tidem", "scene", "hopper_discharge", "--no-render", "--out", str(folder),
                        "--set", f"meshes[0].offset=[{-off},0.0,0.0]", "--set", f"meshes[1].offset=[{off},0.0,0.0]",
                        "--set", f"particles[0].region.max=[0.1,0.02,{fill}]",
                        "--set", f"domain.max=[0.1,0.02,{fill + 0.05}]"], check=True)
    series = read_series(folder / "timeseries.csv")  # the observable computed anew: `tidem.results.observables`
    zero = np.zeros((0, 3))
    obs = discharge_rate(RunRecord(time_s=float(series["time_s"][-1]), x=zero, v=zero, mass=np.zeros(0),
                                   radius=np.zeros(0), v0=zero, floor_z=0.0, series=series))
    return dict(b=b, rate=obs["discharge_rate_kg_s"], early=obs["discharge_rate_early_kg_s"],
                late=obs["discharge_rate_late_kg_s"])


def fit_k(b: np.ndarray, w: np.ndarray, n: float = 1.5) -> dict:
    """Best (k, C') of W = C' (b - k d)^n with n fixed (Beverloo's 3/2), k over a grid in [0, 3], and the
    largest relative deviation of the rates from it."""
    best = None
    for k in np.linspace(0.0, 3.0, 301):
        x = b - k * D
        if (x <= 0).any():
            break
        logc = float(np.mean(np.log(w) - n * np.log(x)))
        dev = float(np.max(np.abs(w / (math.exp(logc) * x**n) - 1.0)))
        if best is None or dev < best["largest_deviation"]:
            best = dict(k=float(k), n=n, c=math.exp(logc), largest_deviation=dev)
    return best


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
    fill = float(sys.argv[2]) if len(sys.argv) > 2 else 0.25
    widths = [float(a) * 1e-3 for a in sys.argv[3:]] or [0.024, 0.032, 0.048, 0.064, 0.080]
    out.mkdir(parents=True, exist_ok=True)
    rows = [run(out, b, fill) for b in widths]
    b = np.array([r["b"] for r in rows])
    w = np.array([r["rate"] for r in rows])
    best = fit(b, w)
    n_fixed, logc_fixed = np.polyfit(np.log(b - 1.5 * D), np.log(w), 1)
    with open(out / "beverloo.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["b_m", "b_over_d", "rate_kg_s", "early_kg_s", "late_kg_s", "late_over_early"])
        for r in rows:
            wr.writerow([r["b"], r["b"] / D, r["rate"], r["early"], r["late"], r["late"] / r["early"]])
    beverloo = fit_k(b, w)
    summary = dict(fill_m=fill, best_fit=best, n_at_k_1_5=float(n_fixed), n_3_2=beverloo, widths_m=list(b),
                   rates_kg_s=list(w),
                   late_over_early=[r["late"] / r["early"] for r in rows])
    (out / "beverloo.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.loglog(b - best["k"] * D, w, "o", label="tidem, hopper_discharge")
    x = np.linspace((b - best["k"] * D).min(), (b - best["k"] * D).max(), 50)
    ax.loglog(x, best["c"] * x ** best["n"], "-", label=f"fit: n = {best['n']:.2f}, k = {best['k']:.2f}")
    ax.set_xlabel(f"b - k d [m] (k = {best['k']:.2f})")
    ax2 = ax.twiny()  # the same rates against b - k d with Beverloo's n = 3/2 and its own k
    xb = b - beverloo["k"] * D
    ax.loglog([], [], "s", mfc="none", color="C2", label=f"against b - {beverloo['k']:.2f} d (top axis)")
    ax2.loglog(xb, w, "s", mfc="none", color="C2")
    xx = np.linspace(xb.min(), xb.max(), 50)
    ax2.loglog(xx, beverloo["c"] * xx**1.5, ":", color="C2")
    ax.loglog([], [], ":", color="C2", label=f"n = 3/2, k = {beverloo['k']:.2f} (largest deviation "
              f"{100 * beverloo['largest_deviation']:.0f} %)")
    ax2.set_xlabel("b - k d [m] with n = 3/2")
    ax.set_ylabel("discharge rate W [kg/s]")
    ax.set_title(f"Slot of length L = {L * 1e3:.0f} mm, beads d = {D * 1e3:.0f} mm")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "beverloo.png", dpi=110)


if __name__ == "__main__":
    main()
