"""Realisations of a tradeoff's variants: the runs that differ only in a seed, taken together.

A bubbling bed is chaotic: two seeds of its initial lattice give observables several per cent apart, so one
run per variant cannot tell a model's effect from chance. When a `--vary` key is a seed (its last part is
`seed`, e.g. `particles[0].seed`), `tidem tradeoff` groups the variants whose other overrides are the same
and reports per group, beside the per-run table:
- each observable's mean over the group's finished runs, their range [min, max], and the signed deviation
  of the mean from the reference group's mean, (mean − mean_ref) / |mean_ref|;
- the mean wall time and the speed-up, the reference group's mean wall time over the group's.
The reference group holds the reference variant. Files: tradeoff_groups.csv, tradeoff_groups.md, and
tradeoff_groups.png (each observable's deviation per group, bars with the seeds' range, ±5 % shaded).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

BAND = 0.05  # the plot's shaded band: the coarse-graining goal of 5 % (docs/coarse_graining.md)


def is_seed(override: str) -> bool:
    """`particles[0].seed=2` -> True: an override of a seed."""
    return override.partition("=")[0].strip().rsplit(".", 1)[-1] == "seed"


@dataclass
class Group:
    overrides: list[str]  # the variants' overrides but the seed
    runs: list[dict] = field(default_factory=list)  # finished results

    @property
    def label(self) -> str:
        return ", ".join(self.overrides) or "(scene as is)"

    def values(self, key: str) -> np.ndarray:
        return np.array([r["observables"][key] for r in self.runs if r["observables"].get(key) is not None], float)

    def wall_s(self) -> float:
        return float(np.mean([r["wall_s"] for r in self.runs])) if self.runs else float("nan")


def seed_groups(results: list[dict], reference: int) -> tuple[list[Group], int] | None:
    """The finished results grouped by their overrides without the seed, in the order of first appearance,
    and the index of the reference variant's group; None when no override is a seed or no group holds two
    runs (nothing to group)."""
    if not any(is_seed(o) for r in results for o in r["overrides"]):
        return None
    groups: dict[tuple[str, ...], Group] = {}
    ref_key = None
    for r in results:
        key = tuple(o for o in r["overrides"] if not is_seed(o))
        group = groups.setdefault(key, Group(list(key)))
        if r["status"] == "finished":
            group.runs.append(r)
        if r["index"] == reference:
            ref_key = key
    if ref_key is None or max(len(g.runs) for g in groups.values()) < 2:
        return None
    ordered = list(groups.values())
    return ordered, list(groups).index(ref_key)


def group_rows(groups: list[Group], ref: int) -> tuple[list[str], list[dict]]:
    """The observables' names and one row per group: runs, wall_s, speed_up and per observable its mean,
    min, max and deviation (signed, relative to the reference group's mean)."""
    keys = sorted({k for g in groups for r in g.runs for k, v in r["observables"].items()
                   if isinstance(v, (int, float)) and not isinstance(v, bool)})
    base = groups[ref]
    rows = []
    for g in groups:
        row = {"group": g.label, "runs": len(g.runs), "wall_s": g.wall_s(), "speed_up": base.wall_s() / g.wall_s()}
        for key in keys:
            v, b = g.values(key), base.values(key)
            if not len(v):
                continue
            mean = float(v.mean())
            row[f"{key}_mean"], row[f"{key}_min"], row[f"{key}_max"] = mean, float(v.min()), float(v.max())
            if len(b) and b.mean() != 0:
                row[f"{key}_deviation"] = (mean - float(b.mean())) / abs(float(b.mean()))
        rows.append(row)
    return keys, rows


def write_groups(groups: list[Group], ref: int, out_dir: Path) -> None:
    """tradeoff_groups.csv, .md and .png (module docstring)."""
    keys, rows = group_rows(groups, ref)
    head = ["group", "runs", "wall_s", "speed_up"] + [f"{k}_{s}" for k in keys
                                                     for s in ("mean", "min", "max", "deviation")]
    with open(out_dir / "tradeoff_groups.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, head, restval="")
        w.writeheader()
        w.writerows(rows)
    lines = ["| group | runs | wall s (mean) | speed-up | " + " | ".join(keys) + " |", "|" + "---|" * (4 + len(keys))]
    for row in rows:
        cells = [row["group"], str(row["runs"]), f"{row['wall_s']:.4g}", f"{row['speed_up']:.3g}x"]
        for k in keys:
            if f"{k}_mean" not in row:
                cells.append("")
                continue
            dev = row.get(f"{k}_deviation")
            cells.append(f"{row[f'{k}_mean']:.4g} [{row[f'{k}_min']:.4g}, {row[f'{k}_max']:.4g}]"
                         + (f" ({100 * dev:+.1f} %)" if dev is not None else ""))
        lines.append("| " + " | ".join(cells) + " |")
    note = (f"\nMean over each group's seeds [their range] (the mean's deviation from the reference group, "
            f"{groups[ref].label}). Speed-up: the reference group's mean wall time over the group's.\n")
    (out_dir / "tradeoff_groups.md").write_text("\n".join(lines) + "\n" + note)
    plot_groups(groups, ref, keys, rows, out_dir / "tradeoff_groups.png")


def plot_groups(groups: list[Group], ref: int, keys: list[str], rows: list[dict], path: Path) -> None:
    """Each observable's deviation from the reference group, one bar per other group, with the seeds' range."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    others = [i for i in range(len(groups)) if i != ref]
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(keys) + 2), 4.5), dpi=120)
    width = 0.8 / max(len(others), 1)
    x = np.arange(len(keys))
    for j, i in enumerate(others):
        row, base = rows[i], rows[ref]
        dev, low, high = [], [], []
        for k in keys:
            b = base.get(f"{k}_mean")
            ok = f"{k}_deviation" in row and b
            dev.append(100 * row[f"{k}_deviation"] if ok else np.nan)
            low.append(100 * (row[f"{k}_mean"] - row[f"{k}_min"]) / abs(b) if ok else 0.0)
            high.append(100 * (row[f"{k}_max"] - row[f"{k}_mean"]) / abs(b) if ok else 0.0)
        ax.bar(x + (j - (len(others) - 1) / 2) * width, dev, width, yerr=[low, high], capsize=2,
               label=f"{groups[i].label} ({row['speed_up']:.3g}x)")
    ax.axhspan(-100 * BAND, 100 * BAND, color="0.85", zorder=0)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xticks(x, keys, rotation=30, ha="right", fontsize=7)
    ax.set_ylabel(f"deviation from {groups[ref].label} [%]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
