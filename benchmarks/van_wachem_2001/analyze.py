"""Light numpy analysis of the digitised van Wachem et al. (2001) reference curves.

The rows are points digitised from figures (irregular time spacing, clustered
at extrema), so statistics are given two ways:
  * "points": plain statistics over the digitised points;
  * "time-weighted": statistics of the piecewise-linear curve through the
    points, resampled on a uniform grid (dt = 1 ms).
Peaks are local maxima of the resampled curve after a light Gaussian
smoothing (sigma given below), kept if their prominence exceeds a threshold and
they are at least `min_sep` apart (the higher one wins).
"""
import json

import numpy as np

DT = 1e-3


def load(name):
    d = np.loadtxt(name, delimiter=",", skiprows=1)
    return d[:, 0], d[:, 1]


def resample(t, y, dt=DT):
    tg = np.arange(t[0], t[-1] + 0.5 * dt, dt)
    tg = tg[tg <= t[-1]]
    return tg, np.interp(tg, t, y)


def gauss_smooth(y, sigma_pts):
    if sigma_pts <= 0:
        return y.copy()
    r = int(4 * sigma_pts)
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma_pts) ** 2)
    k /= k.sum()
    yp = np.pad(y, r, mode="edge")
    return np.convolve(yp, k, mode="valid")


def prominence(y, i):
    # standard topographic prominence on a 1-D signal
    left = y[: i + 1]
    higher_l = np.where(left > y[i])[0]
    lo_l = y[(higher_l[-1] if higher_l.size else 0): i + 1].min()
    right = y[i:]
    higher_r = np.where(right > y[i])[0]
    lo_r = y[i: (i + higher_r[0] if higher_r.size else len(y))].min()
    return y[i] - max(lo_l, lo_r)


def find_peaks(tg, y, prom_min, min_sep):
    idx = [i for i in range(1, len(y) - 1) if y[i] > y[i - 1] and y[i] >= y[i + 1]]
    idx = [i for i in idx if prominence(y, i) >= prom_min]
    # enforce min separation, keeping the highest
    idx.sort(key=lambda i: -y[i])
    kept = []
    for i in idx:
        if all(abs(tg[i] - tg[j]) >= min_sep for j in kept):
            kept.append(i)
    return sorted(kept)


def summary(name, col, unit, sigma_s, prom_frac, min_sep, also_minima=True):
    t, y = load(name)
    tg, yg = resample(t, y)
    ys = gauss_smooth(yg, sigma_s / DT)
    ptp = y.max() - y.min()
    out = {
        "file": name, "quantity": col, "unit": unit, "n_rows": int(len(t)),
        "t_first_s": float(t[0]), "t_last_s": float(t[-1]),
        "span_s": float(t[-1] - t[0]),
        "mean_points": float(y.mean()),
        "mean_time_weighted": float(yg.mean()),
        "std_points": float(y.std(ddof=0)),
        "std_time_weighted": float(yg.std(ddof=0)),
        "min": float(y.min()), "t_at_min_s": float(t[y.argmin()]),
        "max": float(y.max()), "t_at_max_s": float(t[y.argmax()]),
        "peak_to_peak": float(ptp),
        "peak_finder": {"resample_dt_s": DT, "gauss_sigma_s": sigma_s,
                        "min_prominence": float(prom_frac * ptp),
                        "min_separation_s": min_sep},
    }
    for kind, sign in (("maxima", 1.0), ("minima", -1.0)):
        if kind == "minima" and not also_minima:
            continue
        pk = find_peaks(tg, sign * ys, prom_frac * ptp, min_sep)
        times = tg[pk]
        per = np.diff(times)
        out[kind] = {
            "times_s": [round(float(v), 4) for v in times],
            "values_smoothed": [round(float(v), 5) for v in ys[pk]],
            "periods_s": [round(float(v), 4) for v in per],
            "mean_period_s": float(per.mean()) if per.size else None,
            "median_period_s": float(np.median(per)) if per.size else None,
            "freq_from_mean_period_Hz": float(1 / per.mean()) if per.size else None,
            # span between first and last peak / number of intervals
            "mean_period_first_last_s": float((times[-1] - times[0]) / (len(times) - 1)) if len(times) > 1 else None,
        }
    # dominant frequency of the uniformly resampled, de-meaned curve (zero padded FFT)
    yd = yg - yg.mean()
    n = 1 << 16
    spec = np.abs(np.fft.rfft(yd * np.hanning(len(yd)), n)) ** 2
    f = np.fft.rfftfreq(n, DT)
    band = (f > 0.5) & (f < 20)
    out["fft_peak_Hz_0.5_20"] = float(f[band][spec[band].argmax()])
    return out


if __name__ == "__main__":
    res = {
        "height": summary("height.csv", "bed height", "m", 0.02, 0.15, 0.2),
        "relative_pressure": summary("relative_pressure.csv", "relative pressure", "Pa", 0.02, 0.15, 0.2),
        "voidage": summary("voidage.csv", "voidage", "-", 0.02, 0.15, 0.2),
    }
    # sensitivity: no smoothing
    res["sensitivity_no_smoothing"] = {
        k: summary(f, "", "", 0.0, 0.15, 0.2)["maxima"]["times_s"]
        for k, f in (("height", "height.csv"), ("relative_pressure", "relative_pressure.csv"),
                     ("voidage", "voidage.csv"))
    }
    with open("analysis.json", "w") as fh:
        json.dump(res, fh, indent=1)
    print(json.dumps(res, indent=1))
