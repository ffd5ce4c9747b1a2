"""Seed-spread table and Pareto plot of a coarse-graining tradeoff (docs/coarse_graining.md).

    python benchmarks/coarse_grain/summarize.py RUN_DIR/tradeoff.csv [OUT_STEM [BED_MASS_KG]]

Reads the tradeoff.csv of `tidem tradeoff ... --vary 'particles[0].coarse_grain=...' --vary
'particles[0].seed=...'`, groups the variants by k, and writes OUT_STEM.md (per k and
observable: mean over the seeds, the seeds' range, the mean's deviation from k = 1 and the
verdict) and OUT_STEM.png (deviation from k = 1 against the mean wall time per k, with the
seeds' range as bars). Two time means over the second half of each variant's timeseries.csv
are added to the registry's observables (see `late_means`). An observable tolerates a k when the
k seeds' range overlaps the k = 1 seeds' range ("within the spread"), or when its mean lies
within 5 % of k = 1's ("within 5 %"); otherwise it is "off" by the deviation shown.
"""

from __future__ import annotations

import csv
import re
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

SHOWN = {"pressure_drop_Pa": "pressure drop [Pa]", "bed_height_m": "bed height (end) [m]",
         "kinetic_energy_J": "kinetic energy (end) [J]", "mean_temperature_K": "mean T (end) [K]",
         "mean_kinetic_energy_J": "kinetic energy (mean) [J]", "mean_centre_of_mass_m": "centre of mass (mean) [m]"}
BED_MASS = 0.03665  # [kg], bubbling_tube_slab.toml (28 000 grains; `tidem check` prints it)


def label(key: str) -> str:
    if key in SHOWN:
        return SHOWN[key]
    m = re.match(r"(tubes?)(\d+)_(.*)", key)
    return f"tube {m.group(2)} {m.group(3).replace('_', ' ')}" if m else key


def late_means(run_dir: Path, bed_mass: float) -> dict[str, str]:
    """Time means over the second half of a variant's timeseries.csv: the kinetic energy and
    the bed's centre-of-mass height (potential energy / (M g); unbiased by the parcel size,
    unlike a percentile of the centres)."""
    rows = list(csv.DictReader(open(run_dir / "timeseries.csv")))
    t_end = float(rows[-1]["time_s"])
    late = [r for r in rows if float(r["time_s"]) >= 0.5 * t_end]
    ke = np.mean([float(r["kinetic_energy_J"]) for r in late])
    pe = np.mean([float(r["potential_energy_J"]) for r in late])
    return {"mean_kinetic_energy_J": str(ke), "mean_centre_of_mass_m": str(pe / (bed_mass * 9.81))}


def load(path: Path, bed_mass: float):
    rows = list(csv.DictReader(open(path)))
    keys = [k for k in rows[0] if not k.startswith("error_") and k not in
            ("variant", "overrides", "status", "wall_s", "particle_steps_per_s", "dt_s")]
    keys += ["mean_kinetic_energy_J", "mean_centre_of_mass_m"]
    by_k = defaultdict(list)
    for r in rows:
        if r["status"] != "finished":
            continue
        r.update(late_means(path.parent / f"variant_{int(r['variant']):02d}", bed_mass))
        k = float(re.search(r"coarse_grain=([0-9.]+)", r["overrides"]).group(1))
        by_k[k].append(r)
    return keys, dict(sorted(by_k.items()))


def summarize(csv_path: Path, stem: Path, bed_mass: float = BED_MASS) -> None:
    keys, by_k = load(csv_path, bed_mass)
    base = {key: np.array([float(r[key]) for r in by_k[1.0]]) for key in keys}
    wall = {k: np.mean([float(r["wall_s"]) for r in rs]) for k, rs in by_k.items()}
    rate = {k: np.mean([float(r["particle_steps_per_s"]) for r in rs]) for k, rs in by_k.items()}
    lines = ["| k | seeds | mean wall [s] | speed-up vs k = 1 | " + " | ".join(label(k) for k in keys) + " |",
             "|" + "---|" * (4 + len(keys))]
    verdicts = {key: [] for key in keys}
    for k, rs in by_k.items():
        cells = []
        for key in keys:
            v = np.array([float(r[key]) for r in rs])
            ref = base[key]
            dev = (v.mean() - ref.mean()) / abs(ref.mean())
            overlap = v.min() <= ref.max() and v.max() >= ref.min()
            cells.append(f"{v.mean():.4g} [{v.min():.4g}, {v.max():.4g}] ({100 * dev:+.1f} %)")
            if k != 1.0:
                verdicts[key].append((k, "within the spread" if overlap else
                                      "within 5 %" if abs(dev) <= 0.05 else f"off {100 * dev:+.0f} %"))
        lines.append(f"| {k:g} | {len(rs)} | {wall[k]:.0f} | {wall[1.0] / wall[k]:.1f}x | " + " | ".join(cells) + " |")
    lines += ["", "Cells: mean over the seeds [min, max] (deviation of the mean from k = 1's mean). "
              "Particle-steps/s per variant: " + ", ".join(f"k = {k:g}: {rate[k]:.3g}" for k in by_k) + ".", "",
              "| observable | " + " | ".join(f"k = {k:g}" for k in by_k if k != 1.0) + " |",
              "|---|" + "---|" * (len(by_k) - 1)]
    lines += [f"| {label(key)} | " + " | ".join(v for _, v in verdicts[key]) + " |" for key in keys]
    stem.with_suffix(".md").write_text("\n".join(lines) + "\n")
    plot(keys, by_k, base, wall, stem.with_suffix(".png"))
    print("\n".join(lines))


def plot(keys, by_k, base, wall, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=120)
    ks = list(by_k)
    t = np.array([wall[k] for k in ks])
    for i, key in enumerate(keys):
        ref = base[key].mean()
        dev = [np.array([float(r[key]) for r in by_k[k]]) / ref - 1 for k in ks]
        y = np.array([100 * d.mean() for d in dev])
        lo = y - np.array([100 * d.min() for d in dev])
        hi = np.array([100 * d.max() for d in dev]) - y
        ax.errorbar(t * (1 + 0.03 * (i - len(keys) / 2)), y, yerr=[lo, hi], marker="o", capsize=3, label=label(key))
    for k, x in zip(ks, t):
        ax.annotate(f"k = {k:g}", (x, 0), textcoords="offset points", xytext=(0, -14), ha="center", fontsize=8)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("mean wall time per run [s] (2 runs side by side on 2 cores)")
    ax.set_ylabel("deviation from the k = 1 mean [%]")
    ax.set_title("Coarse graining: what each k costs in accuracy (bars: range over 3 seeds)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


if __name__ == "__main__":
    src = Path(sys.argv[1])
    summarize(src, Path(sys.argv[2]) if len(sys.argv) > 2 else src.with_name("coarse_grain_summary"),
              float(sys.argv[3]) if len(sys.argv) > 3 else BED_MASS)
