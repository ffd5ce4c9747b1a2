"""The grouped time-series figures (`tidem.render.series_plots`): which figures a run's columns
give, on a synthetic bubbling-bed record, and the running mean by hand."""

import numpy as np
import pytest

from tidem.render.series_plots import _label, plot_series, running_mean


def record(gas=True, heat=True):
    t = np.linspace(0.0, 2.0, 2001)
    data = {"time_s": t, "step": np.arange(len(t)), "kinetic_energy_J": 1e-4 * (1 + np.sin(t)),
            "rotational_energy_J": 1e-6 * (1 + np.cos(t)), "potential_energy_J": 5e-3 - 1e-3 * t,
            "coordination": np.full_like(t, 1.2), "particles": np.full_like(t, 100.0),
            "max_overlap_ratio": np.full_like(t, 0.02)}
    if gas:
        data.update(gas_pressure_drop_Pa=520.0 + 80.0 * np.sin(2 * np.pi * 7.0 * t), bed_height_m=0.06 + 0.01 * np.sin(t),
                    gas_cg_iterations=np.full_like(t, 140.0), gas_residual=np.full_like(t, 9e-9),
                    gas_divergence_per_s=np.full_like(t, 1e-5))
    if heat:
        data.update(T_mean_K=293.15 + 0.1 * t, T_min_K=np.full_like(t, 293.15), T_max_K=300.0 - np.exp(-t),
                    tubes0_heat_W=1.6 + 0.3 * np.sin(20 * t), tubes0_alpha_W_m2K=160.0 + 30 * np.sin(20 * t))
    return data


@pytest.mark.parametrize("gas, heat, figures", [
    (True, True, {"energy", "hydrodynamics", "heat", "solver", "timeseries"}),
    (False, False, {"energy", "solver", "timeseries"}),
])
def test_the_figures_follow_the_columns(tmp_path, gas, heat, figures):
    run = {"bed_weight_per_area_Pa": 521.0, "precision": "float64", "scene_echo": {"gas": {"tolerance": 1e-8}}}
    written = plot_series(record(gas, heat), run, tmp_path)
    assert {p.stem for p in written} == figures
    assert all(p.parent == tmp_path and p.stat().st_size > 10_000 for p in written)


def test_running_mean_and_labels():
    t = np.arange(10.0)
    y = np.r_[np.zeros(5), np.ones(5)]
    y[7] = np.nan
    got = running_mean(t, y, 2.0)  # the sample and its two neighbours
    assert got[0] == 0.0 and got[4] == pytest.approx(1 / 3) and got[5] == pytest.approx(2 / 3)
    assert got[7] == 1.0 and got[9] == 1.0, "NaNs are skipped, the ends take fewer samples"
    assert _label("tubes0_alpha_W_m2K") == "tubes0 alpha [W/(m$^2$ K)]"
    assert _label("discharged_mass_kg") == "discharged mass [kg]" and _label("gas_pressure_drop_Pa") == "Pressure drop [Pa]"


def test_a_folder_without_a_time_series_gets_no_plots_and_no_error(tmp_path):
    """`tidem render` on a folder of snapshots alone (no timeseries.csv) draws the frames and no plots."""
    from tidem.render.plots import plot_timeseries

    assert plot_timeseries(tmp_path) == []
    assert not (tmp_path / "plots").exists()
