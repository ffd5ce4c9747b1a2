"""The observables of a developed bubbling bed, per run, over a window (issue's coarse-graining list).

    python benchmarks/coarse_grain/bubbling_observables.py T_START RUN_DIR[=LABEL] ... [--csv OUT.csv] [--plot OUT.png]
        [--cell H]
    python benchmarks/coarse_grain/bubbling_observables.py - RUNS.csv ... [--groups G1,G2,...] [--plot OUT.png]

For each `tidem scene` run folder of `bubbling_tube_slab.toml` (snapshots every 0.02 s or so:
`--set output.interval=0.02`), over the window from T_START to the run's end:
- `height_mm`: time mean of the height under which 99 % of the solids' volume lies, each particle a
  sphere whose volume is spread over its own height (unbiased by the parcel size), from the snapshots;
- `com_mm`: time mean of the bed's centre of mass, potential energy / (M g), from timeseries.csv (M from
  run.json's bed weight per floor area);
- `dp_std_Pa`, `dp_freq_Hz`: standard deviation of the gas pressure drop and the frequency of its
  spectrum's peak above 0.5 Hz (de-meaned, Hann window), from timeseries.csv;
- `theta_mm2_s2`: granular temperature per grain, theta = sum m |v - u_cell|^2 / (3 sum m), u_cell the
  mass-weighted mean velocity of the cell (cubes of H, 6 mm unless `--cell` is given), each cell's sum
  scaled by n / (n - 1) for its n particles (an unbiased variance); a parcel's grains move with it, so
  the parcel's fluctuation is its grains';
- `dispersion_mm2_s`: vertical dispersion coefficient D_z = slope of <(z(t + tau) - z(t))^2> / 2 over lags
  tau of 0.02-0.1 s, particles followed by id (a mixing rate; `tidem.results.dispersion`, the observable's);
- `alpha_W_m2K`, `tube_heat_W`: time means of the tube's alpha and heat flow, from timeseries.csv (nan for a
  bed without a tube).
Prints one Markdown row per run; `--csv` also writes them. Then, grouping runs whose labels differ only in
a trailing `_sN` (seeds), one row per group: the mean over its seeds, their range, and the mean's deviation
from the first group's mean; `--plot` draws those deviations as bars with the seeds' range (5 % shaded).
The second form takes the rows of earlier `--csv` files instead of run folders; `--groups` keeps those groups,
in that order (the first is the reference), G1+G2 pooling two groups' runs as one.
"""

from __future__ import annotations

import csv
import json
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp
from tidem.results.dispersion import dispersion_coefficient, indexed_heights

GRAVITY = 9.81
CELL = 0.006  # m: the slab's gas cell, the cubes of the granular temperature unless --cell is given
COLUMNS = ("height_mm", "com_mm", "dp_std_Pa", "dp_freq_Hz", "theta_mm2_s2", "dispersion_mm2_s",
           "alpha_W_m2K", "tube_heat_W")
SHOWN = ("bed height", "centre of mass", "Δp std", "Δp peak", "granular T", "dispersion", "tube alpha",
         "tube heat")  # the plot's names of COLUMNS


def solids_top(z: np.ndarray, r: np.ndarray, share: float = 0.99) -> float:
    """The height under which `share` of the spheres' volume lies (exact sphere caps, bisection)."""
    total = (4.0 / 3.0 * np.pi * r**3).sum()
    lo, hi = float((z - r).min()), float((z + r).max())
    for _ in range(50):
        level = 0.5 * (lo + hi)
        h = np.clip(level - (z - r), 0.0, 2 * r)
        if (np.pi * h * h * (3 * r - h) / 3).sum() < share * total:
            lo = level
        else:
            hi = level
    return 0.5 * (lo + hi)


def granular_temperature(x: np.ndarray, v: np.ndarray, m: np.ndarray, size: float = CELL) -> float:
    """theta [m^2/s^2] about the mass-weighted mean velocity of each cube of `size` (n / (n - 1) per cube)."""
    cell = np.floor(x / size).astype(np.int64)
    _, key = np.unique(cell, axis=0, return_inverse=True)
    key = key.ravel()
    n = np.bincount(key)
    msum = np.bincount(key, m)
    mean = np.stack([np.bincount(key, m * v[:, c]) for c in range(3)], axis=1) / msum[:, None]
    dev = (m * ((v - mean[key]) ** 2).sum(axis=1))
    per_cell = np.bincount(key, dev)
    keep = n >= 2
    scaled = per_cell[keep] * n[keep] / (n[keep] - 1)
    return float(scaled.sum() / (3 * msum[keep].sum()))


def snapshots(run: Path, t_start: float) -> list[tuple[float, Path]]:
    root = ET.parse(run / "snapshots.pvd").getroot()
    found = [(float(d.get("timestep")), run / d.get("file")) for d in root.iter("DataSet")]
    return [(t, p) for t, p in found if t >= t_start - 1e-9]


def run_folder(spec: str, needs: tuple[str, ...] = ("run.json", "timeseries.csv", "snapshots.pvd")) -> Path:
    """The run folder of a RUN_DIR argument; exits with one line naming what is missing."""
    run = Path(spec)
    missing = [name for name in needs if not (run / name).is_file()]
    if missing:
        sys.exit(f"{spec}: not a finished tidem run folder (no {', '.join(missing)}); give the --out folder of "
                 "`tidem scene`")
    return run


def bed_mass(run: Path) -> float:
    """The bed's mass [kg]: run.json's weight per floor area times the floor's area, over g."""
    info = json.loads((run / "run.json").read_text())
    lo, hi = info["scene_echo"]["domain"]["min"], info["scene_echo"]["domain"]["max"]
    return info["bed_weight_per_area_Pa"] * (hi[0] - lo[0]) * (hi[1] - lo[1]) / GRAVITY


def observe(run: Path, t_start: float, cell: float = CELL) -> dict[str, float]:
    with open(run / "timeseries.csv") as f:
        rows = list(csv.DictReader(f))
    col = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    t = col["time_s"]
    win = t >= t_start
    dp = col["gas_pressure_drop_Pa"][win]
    dt = float(np.median(np.diff(t[win])))
    freq = np.fft.rfftfreq(1 << 15, dt)
    power = np.abs(np.fft.rfft((dp - dp.mean()) * np.hanning(len(dp)), 1 << 15)) ** 2
    band = freq > 0.5
    tube = "tubes0_alpha_W_m2K" in col
    heights, thetas, z_by_id = [], [], []
    for ts, path in snapshots(run, t_start):
        x, data = read_vtp(path)
        r = data["radius"]
        heights.append(solids_top(x[:, 2], r))
        thetas.append(granular_temperature(x, data["velocity"], r**3, cell))
        z_by_id.append((ts, indexed_heights(x, data["id"])))
    dz = dispersion_coefficient(z_by_id)  # None: a window shorter than its lags
    return {
        "height_mm": 1e3 * float(np.mean(heights)),
        "com_mm": 1e3 * float(np.mean(col["potential_energy_J"][win]) / (bed_mass(run) * GRAVITY)),
        "dp_std_Pa": float(dp.std()),
        "dp_freq_Hz": float(freq[band][np.argmax(power[band])]),
        "theta_mm2_s2": 1e6 * float(np.mean(thetas)),
        "dispersion_mm2_s": float("nan") if dz is None else 1e6 * dz,
        "alpha_W_m2K": float(np.mean(col["tubes0_alpha_W_m2K"][win])) if tube else float("nan"),
        "tube_heat_W": float(np.mean(col["tubes0_heat_W"][win])) if tube else float("nan"),
    }


def seed_groups(rows: list[dict]) -> dict[str, list[dict]]:
    """Runs grouped by their label without a trailing `_sN`, in order."""
    groups: dict[str, list[dict]] = {}
    for row in rows:
        groups.setdefault(re.sub(r"_s\d+$", "", row["run"]), []).append(row)
    return groups


def plot_groups(rows: list[dict], path: Path) -> None:
    """Each group's deviation from the first group's mean per observable, bars with the seeds' range."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = seed_groups(rows)
    names = list(groups)
    base = {c: np.mean([r[c] for r in groups[names[0]]]) for c in COLUMNS}
    width = 0.8 / max(len(names) - 1, 1)
    fig, ax = plt.subplots(figsize=(11, 4.5))
    for g, name in enumerate(names[1:]):
        dev = np.array([[100 * (r[c] / base[c] - 1) for c in COLUMNS] for r in groups[name]])
        mean = dev.mean(axis=0)
        x = np.arange(len(COLUMNS)) + (g - (len(names) - 2) / 2) * width
        ax.bar(x, mean, width, yerr=[mean - dev.min(axis=0), dev.max(axis=0) - mean], capsize=2,
               label=f"{name} ({len(dev)} seed{'s' if len(dev) > 1 else ''})")
    ax.axhline(0.0, color="black", lw=0.8)
    ax.axhspan(-5, 5, color="0.9", zorder=0)
    ax.set_xticks(np.arange(len(COLUMNS)), SHOWN)
    ax.set_ylabel(f"deviation from {names[0]} [%]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def print_groups(rows: list[dict]) -> None:
    """Mean [range] (deviation from the first group) per group of seeds."""
    groups = seed_groups(rows)
    base = {c: np.mean([r[c] for r in next(iter(groups.values()))]) for c in COLUMNS}
    print("\n| runs | seeds | " + " | ".join(COLUMNS) + " |\n|" + "---|" * (len(COLUMNS) + 2))
    for name, members in groups.items():
        cells = []
        for c in COLUMNS:
            v = np.array([r[c] for r in members])
            spread = f" [{v.min():.4g}, {v.max():.4g}]" if len(v) > 1 else ""
            cells.append(f"{v.mean():.4g}{spread} ({100 * (v.mean() / base[c] - 1):+.1f} %)")
        print(f"| {name} | {len(members)} | " + " | ".join(cells) + " |")


def take_option(argv: list[str], flag: str) -> tuple[list[str], str | None]:
    """argv without `flag` and its value, and that value (None where the flag is absent)."""
    if flag not in argv:
        return argv, None
    i = argv.index(flag)
    return argv[:i] + argv[i + 2:], argv[i + 1]


def main(argv: list[str]) -> None:
    argv, out = take_option(argv, "--csv")
    argv, figure = take_option(argv, "--plot")
    argv, cell = take_option(argv, "--cell")
    argv, keep = take_option(argv, "--groups")
    cell = CELL if cell is None else float(cell)
    keep = None if keep is None else keep.split(",")
    print("| run | " + " | ".join(COLUMNS) + " |\n|" + "---|" * (len(COLUMNS) + 1))
    rows = []
    for spec in argv[1:]:
        if argv[0] == "-":
            with open(spec, newline="") as f:
                rows += [{"run": r["run"], **{c: float(r[c]) for c in COLUMNS}} for r in csv.DictReader(f)]
            continue
        path, _, label = spec.partition("=")
        obs = observe(run_folder(path), float(argv[0]), cell)
        rows.append({"run": label or path, **obs})
        print(f"| {label or path} | " + " | ".join(f"{obs[c]:.4g}" for c in COLUMNS) + " |", flush=True)
    if keep is not None:  # each kept group, "A+B" pooling groups A and B under that name
        groups = seed_groups(rows)
        rows = [{**r, "run": f"{name}_s{i + 1}"} for name in keep
                for i, r in enumerate(r for g in name.split("+") for r in groups[g])]
    print_groups(rows)
    if figure is not None:
        plot_groups(rows, Path(figure))
    if out is not None:
        with open(out, "w", newline="") as f:
            w = csv.DictWriter(f, ["run", *COLUMNS])
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main(sys.argv[1:])
