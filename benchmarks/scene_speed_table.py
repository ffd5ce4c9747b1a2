"""Tabulate `scene_speed.sh`'s runs: per scene, particle-steps/s before and after for each
seed with the ratio, and each observable's mean and range over the seeds for both versions, how many
of the seeds after lie inside the range of the first three seeds before (the three-seed check) and of
all of them, and the difference of the means over its standard error.
Usage: python3 benchmarks/scene_speed_table.py OUT (prints Markdown)."""

import json
import sys
from pathlib import Path


def load(folder: Path) -> dict[str, dict]:
    """run.json of every seed folder under `folder`, keyed by the folder name, in the seeds' order."""
    runs = sorted(folder.glob("seed*/run.json"), key=lambda p: int(p.parent.name.removeprefix("seed")))
    return {p.parent.name: json.loads(p.read_text()) for p in runs}


def scalars(observables: dict, prefix: str = "") -> dict[str, float]:
    """The numeric observables, nested tables flattened to dotted names."""
    out = {}
    for key, value in observables.items():
        if isinstance(value, dict):
            out.update(scalars(value, f"{prefix}{key}."))
        elif isinstance(value, (int, float)):
            out[prefix + key] = float(value)
    return out


def values(runs: dict[str, dict], name: str) -> list[float]:
    found = [scalars(r.get("observables", {})).get(name) for r in runs.values()]
    return [v for v in found if v is not None]


def spread(runs: dict[str, dict], name: str) -> str:
    v = values(runs, name)
    if not v:
        return "-"
    return f"{sum(v) / len(v):.4g} [{min(v):.4g}, {max(v):.4g}]"


def compared(before: list[float], after: list[float]) -> str:
    """How many of `after` lie inside the min-max of the first three of `before` (the three-seed check) and of
    all of `before`, and the difference of the means over its standard error (Welch)."""
    if len(before) < 2 or len(after) < 2:
        return "- | -"
    first = before[:3]
    inside = [sum(min(b) <= v <= max(b) for v in after) for b in (first, before)]
    var = [sum((v - sum(x) / len(x)) ** 2 for v in x) / (len(x) - 1) / len(x) for x in (before, after)]
    se = (var[0] + var[1]) ** 0.5
    t = (sum(after) / len(after) - sum(before) / len(before)) / se if se > 0 else 0.0
    return f"{inside[0]}/{len(after)}, {inside[1]}/{len(after)} | {t:+.1f}"


def main(out: Path) -> None:
    for scene_dir in sorted(p for p in out.iterdir() if p.is_dir()):
        before, after = load(scene_dir / "before"), load(scene_dir / "after")
        print(f"\n### {scene_dir.name}\n")
        print("| seed | before particle-steps/s | after particle-steps/s | after / before |")
        print("|---|---|---|---|")
        for seed in sorted(set(before) | set(after), key=lambda name: int(name.removeprefix("seed"))):
            b = before.get(seed, {}).get("particle_steps_per_s")
            a = after.get(seed, {}).get("particle_steps_per_s")
            ratio = f"{a / b:.2f}" if a and b else "-"
            print(f"| {seed} | {b or 0:.3g} | {a or 0:.3g} | {ratio} |")
        names = sorted({k for r in list(before.values()) + list(after.values())
                        for k in scalars(r.get("observables", {}))})
        print("\n| observable | before: mean [min, max] over seeds | after: mean [min, max] | after inside before's "
              "first three seeds, all seeds | difference of the means / its standard error |")
        print("|---|---|---|---|---|")
        for name in names:
            b, a = values(before, name), values(after, name)
            print(f"| {name} | {spread(before, name)} | {spread(after, name)} | {compared(b, a)} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
