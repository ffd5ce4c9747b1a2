"""How a bubbling bed's answer moves with the gas cell, per averaging scheme (docs/validation.md, grid independence).

    python benchmarks/grid_independence/summarize.py OUT.md LABEL=RUN_DIR [LABEL=RUN_DIR ...]

Each RUN_DIR is a `tidem tradeoff ... --vary gas.cell_size=... --vary 'particles[0].seed=...'` folder. Per variant,
over the second half of its timeseries.csv (samples every `output.timeseries_interval`): the time-mean bed height
(99th percentile of the centres) and centre of mass (potential energy / (M g)), the pressure drop's mean, standard
deviation and dominant frequency (`tidem.results.hydrodynamics.dominant_frequency`), the mean kinetic energy per
grain, the tube's heat flow; and the tube's mean alpha since heat.profile_start from run.json. Per scheme and cell:
the mean over the seeds and their range; then the spread between cells, (largest - smallest mean) / the mean over
the cells, next to the seeds' own spread at each cell.
"""

from __future__ import annotations

import csv
import json
import re
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from tidem.results.hydrodynamics import dominant_frequency, second_half

QUANTITIES = {
    "bed_height_mm": "bed height, time mean [mm]",
    "centre_of_mass_mm": "centre of mass, time mean [mm]",
    "pressure_drop_Pa": "pressure drop, mean [Pa]",
    "pressure_std_Pa": "pressure drop, std [Pa]",
    "pressure_frequency_Hz": "pressure drop, dominant frequency [Hz]",
    "kinetic_energy_uJ": "kinetic energy per grain, mean [uJ]",
    "tube_alpha_W_m2K": "tube alpha since profile_start [W/(m2 K)]",
    "tube_heat_W": "tube heat flow, mean [W]",
}


def variant_values(run: Path) -> dict[str, float]:
    with open(run / "timeseries.csv") as f:
        rows = list(csv.DictReader(f))
    col = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    t = col["time_s"]
    late = t >= 0.5 * t[-1]
    info = json.loads((run / "run.json").read_text())
    n = int(col["particles"][-1])
    ts, p = second_half(t, col["gas_pressure_drop_Pa"])
    peak = dominant_frequency(ts, p)
    mass = float(info["scene_echo"]["materials"]["sand"]["density"]) * np.pi / 6 * \
        float(info["scene_echo"]["particles"][0]["diameter"]["value"]) ** 3 * n
    out = {
        "bed_height_mm": 1e3 * col["bed_height_m"][late].mean(),
        "centre_of_mass_mm": 1e3 * (col["potential_energy_J"][late] / (mass * 9.81)).mean(),
        "pressure_drop_Pa": p.mean(),
        "pressure_std_Pa": p.std(),
        "pressure_frequency_Hz": peak.frequency_Hz if peak is not None else float("nan"),
        "kinetic_energy_uJ": 1e6 * col["kinetic_energy_J"][late].mean() / n,
        "tube_heat_W": col["tubes0_heat_W"][late].mean(),
    }
    obs = info.get("observables") or {}
    alpha = obs.get("tube_mean_alpha", {}).get("tube0_mean_alpha_W_m2K") if isinstance(obs, dict) else None
    out["tube_alpha_W_m2K"] = float(alpha) if alpha is not None else float("nan")
    return out


def overrides(text: str) -> dict[str, str]:
    return dict(part.strip().split("=", 1) for part in text.split(";") if "=" in part)


def study(folder: Path) -> dict[float, list[dict[str, float]]]:
    """{cell size [m]: [values of each seed]} of one tradeoff folder."""
    by_cell: dict[float, list[dict[str, float]]] = defaultdict(list)
    with open(folder / "tradeoff.csv") as f:
        for row in csv.DictReader(f):
            if row["status"] != "finished":
                continue
            cell = float(overrides(row["overrides"])["gas.cell_size"])
            by_cell[cell].append(variant_values(folder / f"variant_{int(row['variant']):02d}"))
    return dict(sorted(by_cell.items()))


def table(label: str, by_cell: dict[float, list[dict[str, float]]]) -> list[str]:
    cells = list(by_cell)
    head = " | ".join(f"{1e3 * c:g} mm cells" for c in cells)
    lines = [f"### {label}", "", f"| quantity | {head} | spread between cells | seeds' spread (largest) |",
             "|---|" + "---|" * (len(cells) + 2)]
    for key, name in QUANTITIES.items():
        means, parts, spreads = [], [], []
        for c in cells:
            v = np.array([s[key] for s in by_cell[c]])
            means.append(v.mean())
            parts.append(f"{v.mean():.4g} ({v.min():.4g}-{v.max():.4g})")
            spreads.append((v.max() - v.min()) / abs(v.mean()) if v.mean() else float("nan"))
        m = np.array(means)
        between = (m.max() - m.min()) / abs(m.mean())
        lines.append(f"| {name} | " + " | ".join(parts) + f" | {100 * between:.1f} % | {100 * max(spreads):.1f} % |")
    return lines + [""]


def main(argv: list[str]) -> None:
    out = Path(argv[0])
    lines = ["Second half of each run; per cell the mean over the seeds and (their range).", ""]
    for arg in argv[1:]:
        label, folder = arg.rsplit("=", 1)
        lines += table(label, study(Path(folder)))
    out.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) < 3 or not re.match(r".+=.+", sys.argv[2]):
        sys.exit(__doc__)
    main(sys.argv[1:])
