"""The time series' bed top and temperature range: the GPU form (a height histogram and reductions
on the device, run here on the CPU) against the host arrays."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.results.particle_stats import HEIGHT_BINS, histogram_percentile

SAND = {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.9, "friction": 0.3,
        "conductivity": 3.0, "heat_capacity": 800.0}


@pytest.mark.parametrize("q", [0.0, 50.0, 99.0, 100.0])
def test_histogram_percentile_is_within_a_bin_of_numpys(q):
    rng = np.random.default_rng(4)
    z = np.concatenate([rng.uniform(0.0, 0.05, 3000), rng.uniform(0.05, 0.09, 40)])
    width = 0.2 / 4096
    counts = np.bincount((z / width).astype(int), minlength=4096)
    assert histogram_percentile(counts, 0.0, width, q) == pytest.approx(np.percentile(z, q), abs=width)
    assert histogram_percentile(counts[:1] * 0 + 1, 0.0, width, q) == pytest.approx(0.5 * width)
    assert np.isnan(histogram_percentile(np.zeros(8), 0.0, width, q))


def test_device_form_of_the_sample_equals_the_host_arrays(solver_for, monkeypatch):
    """Bed top within one bin (domain height / HEIGHT_BINS), the lowest and highest temperature
    exactly and their mean to rounding, inactive particles left out in both."""
    import tidem.results.particle_stats

    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.05], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": 0.002},
                    "region": {"min": [0, 0, 0], "max": [0.02, 0.02, 0.02]}}],
        heat={"initial_temperature": 300.0},
    )
    s = solver_for(raw)
    rng = np.random.default_rng(1)
    T = 300.0 + 50.0 * rng.random(s.n)
    T[7] = 1000.0  # hottest, but inactive: not counted
    s.state.T.from_numpy(T)
    active = s.state.active.to_numpy()
    active[7] = 0
    s.state.active.from_numpy(active)
    for _ in range(50):
        s.step()
    host = s.particle_stats.sample(s.n, bed=True)
    monkeypatch.setattr(tidem.results.particle_stats, "in_order", lambda: False)
    device = tidem.results.particle_stats.ParticleStats(s.state, (0.0, 0.05), heat=True)
    try:
        got = device.sample(s.n, bed=True)
    finally:
        device.release()
    assert got["bed_top"] == pytest.approx(host["bed_top"], abs=0.05 / HEIGHT_BINS)
    assert got["T_min_K"] == host["T_min_K"] and got["T_max_K"] == host["T_max_K"] < 1000.0
    assert got["T_mean_K"] == pytest.approx(host["T_mean_K"], rel=1e-12)
    assert set(host) == set(got)
