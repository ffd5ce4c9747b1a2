"""Plots of a run (`plots/*.png`): the time-series figures grouped by meaning
(`tidem.render.series_plots`), the tube alpha profile, the packed-bed profiles, maps of the
time-averaged bed ([averaging]) and of the gas at the last snapshot, drawn with matplotlib
(which pyvista brings)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np


def read_series(path: Path) -> dict[str, np.ndarray]:
    """A CSV file with a header row (timeseries.csv, alpha_profile.csv) as {column: float array};
    empty cells are NaN."""
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        return {}
    return {k: np.array([float(r[k]) if r[k] != "" else np.nan for r in rows]) for k in rows[0]}


def plot_timeseries(run_dir: Path) -> list[Path]:
    """Write the run's plots: the time-series figures (`tidem.render.series_plots`: energy,
    hydrodynamics, heat, solver and the raw columns), then where the run has them the alpha
    profile, the packed-bed profiles, the averages and the gas maps; returns the files."""
    import json

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tidem.render.series_plots import plot_series

    series = Path(run_dir) / "timeseries.csv"
    data = read_series(series) if series.exists() else {}  # a folder of snapshots alone: frames, no plots
    if len(data.get("time_s", [])) < 2:
        return []
    out_dir = Path(run_dir) / "plots"
    out_dir.mkdir(exist_ok=True)
    summary = Path(run_dir) / "run.json"
    written = plot_series(data, json.loads(summary.read_text()) if summary.exists() else {}, out_dir)

    profile = Path(run_dir) / "alpha_profile.csv"
    if profile.exists():
        prof = read_series(profile)
        fig, ax = plt.subplots(figsize=(7, 4))
        for k in np.unique(prof["tube"]):
            sel = prof["tube"] == k
            ax.plot(prof["angle_deg"][sel], prof["alpha_W_m2K"][sel], "o-", ms=3, label=f"tube {int(k)}")
        ax.set_xlabel("Angle from the top of the tube [deg]")
        ax.set_ylabel("alpha [W/(m$^2$ K)]")
        ax.set_xticks(range(0, 361, 45))
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        written.append(out_dir / "alpha_profile.png")
        fig.savefig(written[-1], dpi=110)
        plt.close(fig)
    profiles = Path(run_dir) / "preheat_profiles.csv"
    if profiles.exists():
        written.append(plot_bed_profiles(profiles, out_dir / "preheat_profiles.png"))
    averages = Path(run_dir) / "averages.vti"
    if averages.exists():
        written.append(plot_averages(averages, out_dir / "averages.png"))
    gas_files = sorted((Path(run_dir) / "gas").glob("gas_*.vti"))
    if gas_files:
        written.append(plot_gas_maps(gas_files[-1], out_dir / "gas_maps.png"))
    return written


GAS_MAPS = [("temperature", "Gas temperature [K]", "inferno"), ("o2_mole_fraction", "O$_2$ mole fraction [-]", "viridis"),
            ("voidage", "Voidage [-]", "cividis"), ("speed", "Gas speed [m/s]", "viridis")]


def depth_map(fig, ax, values, extent, cmap: str, label: str) -> None:
    """One x-z map (values indexed [x, z]) with its colour bar in plain units (1123.05 K, not
    0.05 + 1.123e3) and the x axis labelled."""
    image = ax.imshow(values.T, origin="lower", extent=extent, cmap=cmap, aspect="equal")
    bar = fig.colorbar(image, ax=ax, shrink=0.8)
    bar.set_label(label)
    bar.formatter.set_useOffset(False)
    bar.update_ticks()
    ax.set_xlabel("x [m]")


def plot_gas_maps(vti_path: Path, png_path: Path) -> Path:
    """Maps of the gas at one snapshot, averaged over the depth (y): temperature and O2 where
    the run has them, voidage and speed; tube cells blank."""
    import matplotlib.pyplot as plt

    from tidem.io.vtp import read_vti

    grid, fields = read_vti(vti_path)
    fields["speed"] = np.linalg.norm(fields["velocity"], axis=-1)
    fluid = fields["solid"] == 0
    shown = [m for m in GAS_MAPS if m[0] in fields]
    cells, origin, spacing = grid["cells"], grid["origin"], grid["spacing"]
    extent = [origin[0], origin[0] + cells[0] * spacing[0], origin[2], origin[2] + cells[2] * spacing[2]]
    fig, axes = plt.subplots(1, len(shown), figsize=(4.0 * len(shown), 5.5), squeeze=False)
    for ax, (key, label, cmap) in zip(axes[0], shown):
        total = np.where(fluid, fields[key], 0.0).sum(axis=1)
        count = fluid.sum(axis=1)
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        depth_map(fig, ax, mean, extent, cmap, label)
    axes[0][0].set_ylabel("z [m]")
    fig.suptitle(f"Gas, mean over the depth (y), at t = {grid['time']:.4g} s")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    plt.close(fig)
    return png_path


AVERAGE_MAPS = [("packing_fraction", "Packing fraction [-]", "cividis"), ("speed", "Speed [m/s]", "viridis"),
                ("temperature", "Temperature [K]", "inferno")]


def plot_averages(vti_path: Path, png_path: Path) -> Path:
    """Maps of the time-averaged cells of `averages.vti` over x-z: packing fraction, speed of
    the number-mean velocity and (with heat) temperature, with the tubes along y of run.json
    outlined (and their periodic images); cells no particle entered are blank."""
    import json

    import matplotlib.pyplot as plt

    from tidem.io.vtp import read_vti

    grid, fields = read_vti(vti_path)
    fields["speed"] = np.linalg.norm(fields["velocity"], axis=-1)
    cells, origin, spacing = grid["cells"], grid["origin"], grid["spacing"]
    extent = [origin[0], origin[0] + cells[0] * spacing[0], origin[2], origin[2] + cells[2] * spacing[2]]
    width = extent[1] - extent[0]
    summary = Path(vti_path).parent / "run.json"
    tubes = json.loads(summary.read_text())["render_geometry"]["tubes"] if summary.exists() else []
    shown = [m for m in AVERAGE_MAPS if m[0] in fields]
    fig, axes = plt.subplots(1, len(shown), figsize=(4.0 * len(shown), 5.5), squeeze=False)
    for ax, (key, label, cmap) in zip(axes[0], shown):
        depth_map(fig, ax, fields[key][:, 0, :], extent, cmap, label)
        for tube in (t for t in tubes if t["mask"][1] == 0.0):
            for shift in (-width, 0.0, width):
                ax.add_patch(plt.Circle((tube["c"][0] + shift, tube["c"][2]), tube["r"], fill=False, color="w", lw=1))
        ax.set_xlim(extent[:2])
        ax.set_ylim(extent[2:])
    axes[0][0].set_ylabel("z [m]")
    fig.suptitle(f"Time averages over the depth (y), up to t = {grid['time']:.4g} s")
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    plt.close(fig)
    return png_path


def plot_bed_profiles(csv_path: Path, png_path: Path) -> Path:
    """Solid temperature against height at each profile time: the run's bins (dots), Schumann
    (lines) and source 4's explicit scheme (dashed)."""
    import matplotlib.pyplot as plt

    prof = read_series(csv_path)
    fig, ax = plt.subplots(figsize=(7, 5))
    times = np.unique(prof["time_s"])
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, len(times)))
    for t, colour in zip(times, colours):
        sel = prof["time_s"] == t
        z = prof["height_m"][sel]
        ax.plot(z, prof["T_schumann_K"][sel], "-", color=colour, lw=1.5, label=f"{t:.0f} s")
        ax.plot(z, prof["T_explicit_K"][sel], "--", color=colour, lw=1.0)
        ax.plot(z, prof["T_solid_K"][sel], "o", color=colour, ms=3)
    ax.plot([], [], "k-", label="Schumann")
    ax.plot([], [], "k--", label="explicit scheme (source 4)")
    ax.plot([], [], "ko", ms=3, label="tidem (bin means)")
    ax.set_xlabel("Height above the gas inlet [m]")
    ax.set_ylabel("Solid temperature [K]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    plt.close(fig)
    return png_path
