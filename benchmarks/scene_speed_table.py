"""Tabulate `scene_speed.sh`'s runs: per scene, particle-steps/s before and after for each
seed with the ratio, and each observable's mean and range over the seeds for both versions.
Usage: python3 benchmarks/scene_speed_table.py OUT (prints Markdown)."""

import json
import sys
from pathlib import Path


def load(folder: Path) -> dict[str, dict]:
    """run.json of every seed folder under `folder`, keyed by the folder name."""
    return {p.parent.name: json.loads(p.read_text()) for p in sorted(folder.glob("seed*/run.json"))}


def scalars(observables: dict, prefix: str = "") -> dict[str, float]:
    """The numeric observables, nested tables flattened to dotted names."""
    out = {}
    for key, value in observables.items():
        if isinstance(value, dict):
            out.update(scalars(value, f"{prefix}{key}."))
        elif isinstance(value, (int, float)):
            out[prefix + key] = float(value)
    return out


def spread(runs: dict[str, dict], name: str) -> str:
    values = [scalars(r.get("observables", {})).get(name) for r in runs.values()]
    values = [v for v in values if v is not None]
    if not values:
        return "-"
    return f"{sum(values) / len(values):.4g} [{min(values):.4g}, {max(values):.4g}]"


def main(out: Path) -> None:
    for scene_dir in sorted(p for p in out.iterdir() if p.is_dir()):
        before, after = load(scene_dir / "before"), load(scene_dir / "after")
        print(f"\n### {scene_dir.name}\n")
        print("| seed | before particle-steps/s | after particle-steps/s | after / before |")
        print("|---|---|---|---|")
        for seed in sorted(set(before) | set(after)):
            b = before.get(seed, {}).get("particle_steps_per_s")
            a = after.get(seed, {}).get("particle_steps_per_s")
            ratio = f"{a / b:.2f}" if a and b else "-"
            print(f"| {seed} | {b or 0:.3g} | {a or 0:.3g} | {ratio} |")
        names = sorted({k for r in list(before.values()) + list(after.values())
                        for k in scalars(r.get("observables", {}))})
        print("\n| observable | before: mean [min, max] over seeds | after: mean [min, max] |")
        print("|---|---|---|")
        for name in names:
            print(f"| {name} | {spread(before, name)} | {spread(after, name)} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
