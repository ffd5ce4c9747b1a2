"""What the hydrodynamics figure (`tidem.render.series_plots`) and the `pressure_fluctuation`
and `bed_height` observables share: the second half of a time series, the amplitude spectrum
of a fluctuating signal and its dominant frequency, the bed's top and its weight per area.

Spectrum: the samples are put on uniform steps (linear interpolation; a run's samples fall on
whole time steps, so their spacing varies slightly), the least-squares line is removed
(detrending, so a slow drift does not pass for a low frequency), a Hann window is applied and
numpy's real FFT taken; amplitudes are scaled by 2 / sum(window), so a sine of amplitude A
shows as A at its frequency. The dominant frequency is the highest peak above zero, refined by
a parabola through the logarithms of the peak bin and its two neighbours (Gaussian
interpolation, exact for a Gaussian peak; a Hann-windowed sine comes within a few per cent of
a bin). A window of duration D resolves frequencies only in steps of 1/D, and a peak a few
periods long is noise as often as not, so the frequency counts only where the window holds
at least `MIN_PERIODS` periods of it (f D >= 5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_PERIODS = 5
"""Periods of a frequency the window must hold before the frequency is reported."""

BED_TOP_PERCENTILE = 99
"""The bed top is this percentile of the particle centres' z (ignores a few thrown particles)."""


def second_half(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The samples with t >= t_last / 2 (the observables' "second half") and finite y."""
    keep = (t >= 0.5 * t[-1]) & np.isfinite(y)
    return t[keep], y[keep]


def spectrum(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz], amplitudes [unit of y]) of y(t), detrended and Hann-windowed (module
    docstring); empty arrays with fewer than 4 samples or no time span."""
    if len(t) < 4 or t[-1] <= t[0]:
        return np.zeros(0), np.zeros(0)
    tu = np.linspace(t[0], t[-1], len(t))
    yu = np.interp(tu, t, y)
    yu = yu - np.polyval(np.polyfit(tu, yu, 1), tu)
    window = np.hanning(len(tu))
    amplitude = 2.0 * np.abs(np.fft.rfft(yu * window)) / window.sum()
    return np.fft.rfftfreq(len(tu), tu[1] - tu[0]), amplitude


@dataclass(frozen=True)
class Peak:
    """The dominant frequency of a window and how many of its periods the window holds."""

    frequency_Hz: float
    periods: float
    amplitude: float
    """Height of the spectrum's peak bin [unit of the signal]."""

    @property
    def resolved(self) -> bool:
        """Whether the window holds at least MIN_PERIODS periods (the frequency counts)."""
        return self.periods >= MIN_PERIODS


def dominant_frequency(t: np.ndarray, y: np.ndarray) -> Peak | None:
    """The highest peak of `spectrum(t, y)` above zero frequency (module docstring), or None
    with fewer than 4 samples or a signal with nothing but a straight line (below 1e-9 of |y|)."""
    f, a = spectrum(t, y)
    if len(f) < 3 or a[1:].max() <= 1e-9 * np.abs(y).max():
        return None
    k = 1 + int(np.argmax(a[1:]))
    shift = 0.0
    if k + 1 < len(a) and min(a[k - 1], a[k], a[k + 1]) > 0:
        lo, mid, hi = np.log(a[k - 1:k + 2])
        curve = lo - 2.0 * mid + hi
        shift = 0.5 * (lo - hi) / curve if curve < 0 else 0.0
    frequency = (k + shift) * (f[1] - f[0])
    return Peak(frequency_Hz=float(frequency), periods=float(frequency * (t[-1] - t[0])), amplitude=float(a[k]))


def bed_top(z: np.ndarray) -> float:
    """Height of the bed's top [m]: the BED_TOP_PERCENTILE percentile of the centres' z (NaN
    without particles)."""
    return float(np.percentile(z, BED_TOP_PERCENTILE)) if len(z) else float("nan")


def bed_weight_per_area(mass: float, gravity, lo, hi) -> float:
    """The bed's weight over the cross-section normal to gravity [Pa]: mass |g| / A, A the
    domain's extent across the axis gravity mostly points along (the pressure drop a fully
    fluidized bed carries; `mass` [kg], `gravity` [m/s^2], `lo`, `hi` the domain's corners [m])."""
    g = np.asarray(gravity, dtype=float)
    axis = int(np.argmax(np.abs(g)))
    extent = np.asarray(hi, dtype=float) - np.asarray(lo, dtype=float)
    area = float(np.prod(np.delete(extent, axis)))
    return float(mass * np.linalg.norm(g) / area)
