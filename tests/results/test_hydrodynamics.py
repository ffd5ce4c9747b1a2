"""Spectrum, dominant frequency, bed top and bed weight per area (`tidem.results.hydrodynamics`) on
signals and beds whose answers are known by hand."""

import numpy as np
import pytest

from tidem.results.hydrodynamics import bed_top, bed_weight_per_area, dominant_frequency, second_half, spectrum


def noisy_sine(frequency, duration=2.0, amplitude=30.0, drift=50.0, noise=5.0):
    """A pressure-like record: 500 Pa, a sine, a linear drift and white noise, sampled every ~1 ms
    on slightly uneven steps (as whole time steps fall)."""
    rng = np.random.default_rng(1)
    t = np.cumsum(np.r_[0.0, 0.001 + rng.uniform(-4e-6, 4e-6, int(duration / 0.001))])
    y = 500.0 + amplitude * np.sin(2 * np.pi * frequency * t + 0.3) + drift * t + rng.normal(0.0, noise, len(t))
    return t, y


@pytest.mark.parametrize("frequency", [3.1, 7.0, 7.3, 12.45])
def test_the_dominant_frequency_of_a_noisy_drifting_sine(frequency):
    t, y = noisy_sine(frequency)
    peak = dominant_frequency(t, y)
    assert peak.frequency_Hz == pytest.approx(frequency, abs=0.02)  # a bin is 0.5 Hz wide
    assert peak.periods == pytest.approx(frequency * (t[-1] - t[0]), rel=0.01)
    assert peak.resolved
    assert 20.0 < peak.amplitude < 31.0  # the Hann window scales a sine to its amplitude on a bin


def test_a_peak_with_fewer_than_five_periods_is_not_resolved():
    t, y = noisy_sine(2.0, duration=2.0)  # 4 periods
    peak = dominant_frequency(t, y)
    assert peak.frequency_Hz == pytest.approx(2.0, abs=0.1)
    assert not peak.resolved


def test_a_drift_is_no_frequency():
    """A straight line (a bed that settles) leaves nothing after detrending; a flat record and
    too few samples give no peak."""
    t = np.linspace(0.0, 1.0, 501)
    f, a = spectrum(t, 3.0 + 40.0 * t)
    assert np.all(a < 1e-9)
    assert dominant_frequency(t, np.full_like(t, 7.0)) is None
    assert dominant_frequency(t[:3], t[:3]) is None


def test_second_half_drops_the_start_and_missing_values():
    t = np.linspace(0.0, 1.0, 11)
    y = t.copy()
    y[-1] = np.nan
    th, yh = second_half(t, y)
    assert th.tolist() == pytest.approx([0.5, 0.6, 0.7, 0.8, 0.9]) and yh.tolist() == pytest.approx(th.tolist())


def test_bed_top_and_weight_per_area():
    z = np.arange(1000) * 1e-4  # 0 .. 99.9 mm
    assert bed_top(z) == pytest.approx(np.percentile(z, 99))
    assert np.isnan(bed_top(np.zeros(0)))
    # 1 kg on 0.1 x 0.02 m under g along -z: 9.81 / 0.002 Pa; gravity along -x uses the y-z section
    assert bed_weight_per_area(1.0, [0, 0, -9.81], [0, 0, 0], [0.1, 0.02, 0.5]) == pytest.approx(4905.0)
    assert bed_weight_per_area(1.0, [-9.81, 0, 0], [0, 0, 0], [0.1, 0.02, 0.5]) == pytest.approx(981.0)
