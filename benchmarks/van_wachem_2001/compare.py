"""tidem's pseudo2d_bubbling_bed runs against the digitised records of van Wachem et al. (2001).

    python benchmarks/van_wachem_2001/compare.py FIGURE RUN_DIR[=LABEL] ...

For each run (a `tidem scene pseudo2d_bubbling_bed` folder) and for the records, over the run's
bubbling window (from T_START on; the records over their whole length): the time-mean bed height
and its 5-95 % range, the mean time between bed-height peaks and between pressure peaks (the
records' own peak finder, `analyze.py`: 1 ms resampling, 20 ms Gaussian smoothing, prominence
15 % of the peak-to-peak range, peaks at least 0.2 s apart), the standard deviation and
peak-to-peak range of the relative pressure (the probe's pressure 45 mm above the distributor
less its time mean), and the voidage of the probe's cell layer (from the gas snapshots; reported,
not judged: the records' voidage comes from light intensity). Prints a Markdown table and draws
FIGURE: bed height and relative pressure over windows as long as the records, and the pressure
spectra. T_STOP=SECONDS (environment) ends every run's window there. PROBE=COLUMN (environment)
reads another probe's column, e.g. PROBE=gas_pressure_x45_y4_z45mm_Pa for the point at the column's
centre (the shipped scene records both; the default is the cross-section's mean, gas_pressure_z45mm_Pa).
"""

import os
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from analyze import DT, find_peaks, gauss_smooth, load, resample  # noqa: E402

T_START = 1.0  # s: the air is fully on at 0.3 s; the first slug and the bed's expansion are over by 1 s
T_STOP = float(os.environ.get("T_STOP", "inf"))  # s: T_STOP=3.5 compares runs over one window
PROBE_Z = 0.045
PROBE = os.environ.get("PROBE", "gas_pressure_z45mm_Pa")  # the time-series column of the pressure probe
SIGMA_S, PROMINENCE, MIN_SEP = 0.02, 0.15, 0.2


def peaks_period(t, y):
    """Mean time between peaks [s] (the records' peak finder) and the peak count."""
    tg, yg = resample(t, y)
    ys = gauss_smooth(yg, SIGMA_S / DT)
    pk = find_peaks(tg, ys, PROMINENCE * (y.max() - y.min()), MIN_SEP)
    per = np.diff(tg[pk])
    return (float(per.mean()) if per.size else float("nan")), len(pk)


def spectrum(t, y):
    """(frequency [Hz], power) of the de-meaned curve resampled at 1 ms, Hann window."""
    tg, yg = resample(t, y)
    yd = yg - yg.mean()
    n = 1 << 16
    return np.fft.rfftfreq(n, DT), np.abs(np.fft.rfft(yd * np.hanning(len(yd)), n)) ** 2


def stats(t, height, pressure):
    rel = pressure - np.mean(pressure)
    return {
        "height_mean_m": float(np.mean(height)),
        "height_p5_m": float(np.percentile(height, 5)), "height_p95_m": float(np.percentile(height, 95)),
        "height_period_s": peaks_period(t, height)[0],
        "pressure_period_s": peaks_period(t, rel)[0],
        "pressure_std_Pa": float(np.std(rel)), "pressure_ptp_Pa": float(np.ptp(rel)),
    }


def probe_voidage(run: Path) -> float:
    """Time mean voidage of the gas-cell layer at PROBE_Z, snapshots from T_START on."""
    from tidem.io.vtp import read_vti

    values = []
    for path in sorted((run / "gas").glob("gas_*.vti")):
        grid, fields = read_vti(path)
        if not T_START <= grid["time"] <= T_STOP:
            continue
        k = int((PROBE_Z - grid["origin"][2]) / grid["spacing"][2])
        eps, solid = fields["voidage"], fields["solid"]
        values.append(float(eps[:, :, k][solid[:, :, k] == 0].mean()))
    return float(np.mean(values)) if values else float("nan")


def read_run(run: Path):
    from tidem.render.plots import read_series

    s = read_series(run / "timeseries.csv")
    keep = (s["time_s"] >= T_START) & (s["time_s"] <= T_STOP)
    return s["time_s"][keep], s["bed_height_m"][keep], s[PROBE][keep]


def main(figure: str, runs: list[str]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    th, h = load(HERE / "height.csv")
    tp, p = load(HERE / "relative_pressure.csv")
    # the records' points cluster at the extrema: their statistics along the curve through them (1 ms)
    hg, pg = resample(th, h)[1], resample(tp, p)[1]
    rel = p - pg.mean()
    ref = {"height_mean_m": float(hg.mean()), "height_p5_m": float(np.percentile(hg, 5)),
           "height_p95_m": float(np.percentile(hg, 95)), "height_period_s": peaks_period(th, h)[0],
           "pressure_period_s": peaks_period(tp, rel)[0], "pressure_std_Pa": float(np.std(pg)),
           "pressure_ptp_Pa": float(np.ptp(rel))}
    tv, v = load(HERE / "voidage.csv")
    rows = [("van Wachem et al. (2001), records", ref, float(resample(tv, v)[1].mean()))]
    series = []
    for arg in runs:
        path, _, label = arg.partition("=")
        t, height, pressure = read_run(Path(path))
        rows.append((label or path, stats(t, height, pressure), probe_voidage(Path(path))))
        series.append((label or path, t, height, pressure))
    print(f"window: records as digitised; runs from t = {T_START} s to {T_STOP} s or their end")
    print("| | bed height mean [5-95 %], mm | bed-height period, s | pressure period, s | pressure std, Pa | "
          "pressure peak-to-peak, Pa | voidage at 45 mm |")
    print("|---|---|---|---|---|---|---|")
    for label, r, eps in rows:
        print(f"| {label} | {1e3 * r['height_mean_m']:.1f} [{1e3 * r['height_p5_m']:.1f}, {1e3 * r['height_p95_m']:.1f}] | "
              f"{r['height_period_s']:.3f} | {r['pressure_period_s']:.3f} | {r['pressure_std_Pa']:.1f} | "
              f"{r['pressure_ptp_Pa']:.0f} | {eps:.3f} |")

    fig, ax = plt.subplots(3, 1, figsize=(9, 10), constrained_layout=True)
    ax[0].plot(th - th[0], 1e3 * h, "k.-", label="records (from 2.0 s)")
    ax[1].plot(tp - tp[0], rel, "k.-", label="records (from 3.0 s)")
    f, pw = spectrum(tp, rel)
    ax[2].semilogy(f, pw / pw.max(), "k", label="records")
    for label, t, height, pressure in series:
        span = (t >= t[-1] - (th[-1] - th[0]))
        ax[0].plot(t[span] - t[span][0], 1e3 * height[span], label=f"{label} (last {th[-1] - th[0]:.1f} s)")
        span = (t >= t[-1] - (tp[-1] - tp[0]))
        ax[1].plot(t[span] - t[span][0], pressure[span] - pressure.mean(), label=f"{label} (last {tp[-1] - tp[0]:.1f} s)")
        f, pw = spectrum(t, pressure - pressure.mean())
        ax[2].semilogy(f, pw / pw.max(), label=f"{label} (t > {T_START} s)")
    ax[0].set(xlabel="time in window [s]", ylabel="bed height [mm]", title="Bed height (tidem: 99th percentile of particle centres)")
    ax[1].set(xlabel="time in window [s]", ylabel="relative pressure [Pa]", title="Pressure 45 mm above the distributor, less its mean")
    ax[2].set(xlabel="frequency [Hz]", ylabel="power (normalised)", xlim=(0, 10), ylim=(1e-4, 1.5), title="Spectrum of the relative pressure")
    for a in ax:
        a.legend(fontsize=8)
        a.grid(alpha=0.3)
    fig.savefig(figure, dpi=110)
    print(f"figure: {figure}")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
