"""The tube's alpha by route, per run and per group of seeds: how the heat a tube gives the bed divides.

    python benchmarks/coarse_grain/tube_routes.py RUN_DIR[=LABEL] ...

Reads run.json's `tube_mean_alpha` observable (over heat.profile_start to the run's end; from the start where
the scene sets none): the tube's mean alpha and its parts through the particles' contact spots, the gas gap of
touching particles (Schlünder), the gas lens of particles near the tube, and the gas's convection, in
W/(m² K). Runs whose labels differ only in a trailing `_sN` are grouped (the mean over their seeds).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from bubbling_observables import run_folder, seed_groups

ROUTES = ("mean", "contact_spot", "gas_gap", "gas_lens", "gas")


def routes(run: Path) -> dict[str, float]:
    """The tube's alpha and its parts [W/(m² K)] from `run`'s run.json (the first tube)."""
    seen = json.loads((run / "run.json").read_text())["observables"]["tube_mean_alpha"]
    return {r: seen[f"tube0_{r}_alpha_W_m2K"] for r in ROUTES}


def main(argv: list[str]) -> None:
    runs = [{"run": label or path, **routes(run_folder(path, ("run.json",)))}
            for path, _, label in (spec.partition("=") for spec in argv)]
    groups = seed_groups(runs)
    print("| runs | seeds | " + " | ".join(ROUTES) + " |\n|" + "---|" * (len(ROUTES) + 2))
    for name, rows in groups.items():
        mean = {r: sum(row[r] for row in rows) / len(rows) for r in ROUTES}
        print(f"| {name} | {len(rows)} | " + " | ".join(f"{mean[r]:.1f}" for r in ROUTES) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
