"""The time-series figures of a run (`plots/*.png`), grouped by what an engineer asks of them:

- `hydrodynamics.png` (runs with a gas): the pressure drop with its mean over the second half
  and the bed's weight per area (run.json `bed_weight_per_area_Pa`, the drop a fully fluidized
  bed carries), its spectrum over the second half with the dominant frequency marked when the
  window holds five of its periods (`tidem.results.hydrodynamics`, as the `pressure_fluctuation`
  observable), and the bed height with its mean over the second half;
- `heat.png` (runs with heated surfaces): heat flow of each heated surface and each heated
  tube's alpha with a running mean, particle and gas temperatures;
- `energy.png`: kinetic, rotational and potential energy, contacts per particle;
- `solver.png`: whether the run can be trusted, not what it found: the gas pressure solver's
  iterations, residual and velocity divergence, the largest overlap against the scene's limit;
- `timeseries.png`: every column of timeseries.csv, one panel each (the raw columns).

Every time axis marks each change of the run's conditions (a point of a scene schedule, a live
change: `change_marks`) with a dotted line, labelled on the figure's top panel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tidem.results.hydrodynamics import MIN_PERIODS, dominant_frequency, second_half, spectrum

LABELS = {
    "kinetic_energy_J": "Kinetic energy [J]",
    "rotational_energy_J": "Rotational energy [J]",
    "potential_energy_J": "Potential energy [J]",
    "coordination": "Contacts per particle [-]",
    "particles": "Particles [-]",
    "max_overlap_ratio": "Largest overlap / radius [-]",
    "bed_height_m": "Bed height [m]",
    "plate_z_m": "Outlet plate height [m]",
    "gas_pressure_drop_Pa": "Pressure drop [Pa]",
    "gas_cg_iterations": "Pressure solver iterations [-]",
    "gas_residual": "Pressure solver\nrelative residual [-]",
    "gas_divergence_per_s": "Gas velocity divergence [1/s]",
    "T_mean_K": "Mean particle temperature [K]",
    "gas_T_mean_K": "Mean gas temperature [K]",
}
DPI = 110
SPECTRUM_MAX_HZ = 50.0
"""The spectrum is shown up to this frequency (bubbling beds fluctuate at a few Hz)."""


def _label(key: str) -> str:
    """A column's axis label with its unit, from LABELS or the column's unit suffix."""
    if key in LABELS:
        return LABELS[key]
    for suffix, unit in (("_W_m2K", "W/(m$^2$ K)"), ("_W", "W"), ("_J", "J"), ("_K", "K"), ("_Pa", "Pa"),
                         ("_kg_s", "kg/s"), ("_kg", "kg"), ("_m", "m"), ("_s", "s")):
        if key.endswith(suffix):
            return f"{key[:-len(suffix)].replace('_', ' ')} [{unit}]"
    return f"{key.replace('_', ' ')} [-]"


def running_mean(t: np.ndarray, y: np.ndarray, window: float) -> np.ndarray:
    """Centred running mean of y over `window` seconds of t (fewer samples at the ends; NaNs skipped)."""
    ok = np.isfinite(y)
    cum = np.r_[0.0, np.cumsum(np.where(ok, y, 0.0))]
    count = np.r_[0, np.cumsum(ok)]
    lo = np.searchsorted(t, t - 0.5 * window, side="left")
    hi = np.searchsorted(t, t + 0.5 * window, side="right")
    n = count[hi] - count[lo]
    return np.where(n > 0, (cum[hi] - cum[lo]) / np.maximum(n, 1), np.nan)


def change_marks(run: dict) -> list[tuple[float, str]]:
    """(time, label) of each change of the run's conditions: the points of the scene's schedules
    (after t = 0) and each live change (run.json's `steering`)."""
    marks = []

    def walk(node, key):
        if isinstance(node, dict) and {"times", "values"} <= node.keys():
            marks.extend((float(t), key) for t in node["times"] if t > 0)
        elif isinstance(node, dict):
            for k, v in node.items():
                walk(v, f"{key}.{k}" if key else k)
        elif isinstance(node, list):
            for i, v in enumerate(node):
                walk(v, f"{key}[{i}]")

    walk(run.get("scene_echo", {}), "")
    marks += [(c["time_s"], f"{c['key']} = {c['value']:g}") for c in run.get("steering", [])]
    return sorted(marks)


def _mark_changes(fig, marks: list[tuple[float, str]]) -> None:
    """A dashed line at each change on every time axis, labelled on the top one."""
    timed = [ax for ax in fig.axes if ax.get_xlabel() == "Time [s]"]
    axes = [ax for ax in fig.axes if any(ax is t or ax.get_shared_x_axes().joined(ax, t) for t in timed)]
    top = min(axes, key=lambda ax: -ax.get_position().y1, default=None)
    for t, label in marks:
        for ax in axes:
            ax.axvline(t, color="0.4", ls=":", lw=1)
        top.annotate(label, (t, 1.0), xycoords=("data", "axes fraction"), rotation=90, fontsize=7, va="top",
                     ha="right", color="0.3")


def _finish(fig, path: Path, marks: list[tuple[float, str]] = ()) -> Path:
    import matplotlib.pyplot as plt

    if marks:
        _mark_changes(fig, marks)
    for ax in fig.axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def plot_energy(data: dict, path: Path, marks=()) -> Path:
    """Kinetic and rotational energy (log scale), the change of potential energy since the start,
    and contacts per particle."""
    import matplotlib.pyplot as plt

    t = data["time_s"]
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for key in ("kinetic_energy_J", "rotational_energy_J"):
        axes[0].plot(t, data[key], lw=1.0, label=LABELS[key].split(" [")[0])
    if np.nanmax(data["kinetic_energy_J"]) > 0:
        axes[0].set_yscale("symlog", linthresh=max(1e-12, 1e-6 * np.nanmax(data["kinetic_energy_J"])))
    axes[0].set_ylabel("Energy [J]")
    axes[0].legend(fontsize=8)
    axes[1].plot(t, data["potential_energy_J"] - data["potential_energy_J"][0], lw=1.0)
    axes[1].set_ylabel("Potential energy\nless its start value [J]")
    axes[2].plot(t, data["coordination"], lw=1.0)
    axes[2].set_ylabel(LABELS["coordination"])
    axes[2].set_xlabel("Time [s]")
    return _finish(fig, path, marks)


def plot_hydrodynamics(data: dict, run: dict, path: Path, marks=()) -> Path:
    """Pressure drop with its second-half mean and the bed weight per area, its spectrum over
    the second half with the dominant frequency (module docstring), and the bed height."""
    import matplotlib.pyplot as plt

    t, p = data["time_s"], data["gas_pressure_drop_Pa"]
    th, ph = second_half(t, p)
    panels = 3 if "bed_height_m" in data else 2
    fig, axes = plt.subplots(panels, 1, figsize=(8, 3.0 * panels))
    ax = axes[0]
    ax.plot(t, p, lw=0.8, color="C0", label="pressure drop")
    if len(ph):
        ax.hlines(ph.mean(), th[0], th[-1], color="C3", lw=2,
                  label=f"mean over the second half: {ph.mean():.4g} Pa (std {ph.std():.3g} Pa)")
    weight = run.get("bed_weight_per_area_Pa")
    if weight is not None:
        ax.axhline(weight, color="k", ls="--", lw=1, label=f"bed weight / area: {weight:.4g} Pa")
    ax.set_xlabel("Time [s]")
    ax.set_ylabel(LABELS["gas_pressure_drop_Pa"])
    ax.legend(fontsize=8, loc="lower right")
    ax = axes[1]
    f, a = spectrum(th, ph)
    shown = f <= min(SPECTRUM_MAX_HZ, f[-1]) if len(f) else f > 0
    ax.plot(f[shown], a[shown], "o-", ms=2.5, lw=1.0, color="C0")
    peak = dominant_frequency(th, ph)
    if peak is not None and peak.resolved:
        ax.axvline(peak.frequency_Hz, color="C3", ls="--", lw=1)
        note = f"dominant frequency {peak.frequency_Hz:.3g} Hz ({peak.periods:.0f} periods in the window)"
    elif peak is not None:
        note = (f"no dominant frequency: the highest peak, {peak.frequency_Hz:.3g} Hz, has {peak.periods:.1f} periods "
                f"in the window (< {MIN_PERIODS}); run longer")
    else:
        note = "too few samples for a spectrum"
    ax.text(0.98, 0.95, note, transform=ax.transAxes, ha="right", va="top", fontsize=8,
            bbox=dict(facecolor="white", alpha=0.8, edgecolor="none"))
    if len(th):
        ax.set_title(f"Spectrum of the pressure drop, {th[0]:.3g}-{th[-1]:.3g} s, detrended, Hann window", fontsize=9)
    ax.set_xlabel("Frequency [Hz]")
    ax.set_ylabel("Amplitude [Pa]")
    if panels == 3:
        ax = axes[2]
        h = data["bed_height_m"]
        ax.plot(t, 1e3 * h, lw=0.8, color="C2", label="bed height (99th percentile of the centres' z)")
        th, hh = second_half(t, h)
        if len(hh):
            ax.hlines(1e3 * hh.mean(), th[0], th[-1], color="C3", lw=2,
                      label=f"mean over the second half: {1e3 * hh.mean():.4g} mm")
        ax.set_xlabel("Time [s]")
        ax.set_ylabel("Bed height [mm]")
        ax.legend(fontsize=8, loc="lower right")
    return _finish(fig, path, marks)


def _heat_label(key: str) -> str:
    """`tubes0_gas_heat_W` -> 'tubes0 to the gas', `tubes0_heat_W` -> 'tubes0 to the particles',
    `tubes0_alpha_W_m2K` -> 'tubes0'."""
    for suffix, text in (("_gas_heat_W", " to the gas"), ("_heat_W", " to the particles"), ("_alpha_W_m2K", "")):
        if key.endswith(suffix):
            return key[:-len(suffix)] + text
    return key


def plot_heat(data: dict, path: Path, marks=()) -> Path:
    """Heat flow of each heated surface and each heated tube's alpha (thin) with their running
    mean over a twentieth of the run (thick); the particles' and the gas's mean temperature and
    the hottest particle's."""
    import matplotlib.pyplot as plt

    t = data["time_s"]
    window = (t[-1] - t[0]) / 20
    groups = [[k for k in data if k.endswith("_heat_W")], [k for k in data if k.endswith("_alpha_W_m2K")]]
    groups = [g for g in groups if g]
    fig, axes = plt.subplots(len(groups) + 1, 1, figsize=(8, 3.0 * (len(groups) + 1)), sharex=True, squeeze=False)
    axes = axes[:, 0]
    for ax, keys in zip(axes, groups):
        for i, key in enumerate(keys):
            ax.plot(t, data[key], lw=0.6, alpha=0.45, color=f"C{i}")
            ax.plot(t, running_mean(t, data[key], window), lw=1.8, color=f"C{i}", label=_heat_label(key))
        ax.set_ylabel("Heat flow into the bed [W]" if keys[0].endswith("_heat_W") else "alpha [W/(m$^2$ K)]")
        ax.legend(fontsize=8, title=f"thick: running mean over {window:.3g} s", title_fontsize=8)
    ax = axes[-1]
    if "T_mean_K" in data:
        ax.plot(t, data["T_mean_K"], color="C1", label="particles, mean")
    if "gas_T_mean_K" in data:
        ax.plot(t, data["gas_T_mean_K"], color="C0", label="gas, mean over the cells")
    ax.set_ylabel("Mean temperature [K]")
    ax.legend(fontsize=8)
    ax.yaxis.get_major_formatter().set_useOffset(False)
    if "T_max_K" in data:
        twin = ax.twinx()
        twin.plot(t, data["T_max_K"], color="C3", lw=0.8, ls=":")
        twin.set_ylabel("Hottest particle [K] (dotted)", color="C3")
        twin.yaxis.get_major_formatter().set_useOffset(False)
    ax.set_xlabel("Time [s]")
    return _finish(fig, path, marks)


def plot_solver(data: dict, run: dict, path: Path, marks=()) -> Path:
    """The diagnostics: the gas pressure solver's iterations, residual and divergence (with a
    gas), and the largest overlap against numerics.max_overlap, where the run stops."""
    import matplotlib.pyplot as plt

    from tidem.scene.schema import Gas, Numerics

    t = data["time_s"]
    keys = [k for k in ("gas_cg_iterations", "gas_residual", "gas_divergence_per_s") if k in data]
    keys.append("max_overlap_ratio")
    fig, axes = plt.subplots(len(keys), 1, figsize=(8, 2.4 * len(keys) + 0.6), sharex=True, squeeze=False)
    for ax, key in zip(axes[:, 0], keys):
        ax.plot(t, data[key], lw=0.8)
        ax.set_ylabel(LABELS[key], fontsize=9)
        if key != "max_overlap_ratio" and np.nanmin(data[key]) > 0:
            ax.set_yscale("log")
    echo = run.get("scene_echo", {})
    lines = {"max_overlap_ratio": ("numerics.max_overlap", "the run stops above it",
                                   echo.get("numerics", {}).get("max_overlap", Numerics.model_fields["max_overlap"].default))}
    if "gas" in echo:
        tolerance = echo["gas"].get("tolerance", Gas.model_fields["tolerance"].default)
        lines["gas_cg_iterations"] = ("gas.max_iterations", "the solve stops there",
                                      echo["gas"].get("max_iterations", Gas.model_fields["max_iterations"].default))
        lines["gas_residual"] = ("gas.tolerance", "converged below it",
                                 max(tolerance, 1e-5) if run.get("precision") == "float32" else tolerance)
    for ax, key in zip(axes[:, 0], keys):
        if key in lines:
            name, meaning, value = lines[key]
            ax.axhline(value, color="C3", ls="--", lw=1, label=f"{name} = {value:g}: {meaning}")
            ax.legend(fontsize=8, loc="best")
    axes[-1, 0].set_xlabel("Time [s]")
    fig.suptitle("Solver diagnostics: can the run be trusted?", fontsize=10)
    return _finish(fig, path, marks)


def plot_raw(data: dict, path: Path, marks=()) -> Path:
    """Every column of timeseries.csv but time and step, one panel each."""
    import matplotlib.pyplot as plt

    t = data["time_s"]
    columns = [k for k in data if k not in ("time_s", "step")]
    rows = (len(columns) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(10, 2.6 * rows), sharex=True, squeeze=False)
    for ax, key in zip(axes.ravel(), columns):
        ax.plot(t, data[key], lw=1.2)
        ax.set_ylabel(_label(key), fontsize=8)
        ax.set_title(key, fontsize=8)
    for ax in axes.ravel()[len(columns):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("Time [s]")
    fig.suptitle("Raw columns of timeseries.csv", fontsize=10)
    return _finish(fig, path, marks)


def plot_series(data: dict, run: dict, out_dir: Path) -> list[Path]:
    """The figures of the module docstring that the run's columns allow; returns their files."""
    marks = change_marks(run)
    written = [plot_energy(data, out_dir / "energy.png", marks)]
    if "gas_pressure_drop_Pa" in data:
        written.append(plot_hydrodynamics(data, run, out_dir / "hydrodynamics.png", marks))
    if any(k.endswith("_heat_W") or k.endswith("_alpha_W_m2K") for k in data) or "T_mean_K" in data:
        written.append(plot_heat(data, out_dir / "heat.png", marks))
    written.append(plot_solver(data, run, out_dir / "solver.png", marks))
    written.append(plot_raw(data, out_dir / "timeseries.png", marks))
    return written
