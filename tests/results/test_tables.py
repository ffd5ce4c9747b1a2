"""`tidem.results.tables.tube_alpha_columns`: each heated tube's alpha at one time-series sample, by hand."""

import math
from types import SimpleNamespace

import pytest

from tidem.results.tables import tube_alpha_columns


def model_with(tubes, heat=True):
    """The parts of a Model the columns read: [heat]'s reference temperature, the tubes, the domain's length."""
    return SimpleNamespace(features=SimpleNamespace(heat=heat), tubes=tubes, grid=SimpleNamespace(length=(0.1, 0.004, 0.2)),
                           scene=SimpleNamespace(heat=SimpleNamespace(initial_temperature=293.15)))


def test_alpha_of_a_hot_tube_and_of_a_heated_foil():
    hot = dict(name="tubes[0]", mask=[1.0, 0.0, 1.0], r=0.0075, T=353.15, flux=None)  # along y: 4 mm in the domain
    foil = dict(name="tubes[1]", mask=[1.0, 0.0, 1.0], r=0.0075, T=None, flux=5000.0)
    cold = dict(name="tubes[2]", mask=[1.0, 0.0, 1.0], r=0.0075, T=None, flux=None)
    row = {"tubes0_heat_W": 1.5, "tubes0_gas_heat_W": 0.3, "tubes1_foil_T_K": 318.15, "tubes1_heat_W": 0.9}
    got = tube_alpha_columns(model_with([hot, foil, cold]), row)
    area = 2 * math.pi * 0.0075 * 0.004
    assert got == {"tubes0_alpha_W_m2K": pytest.approx(1.8 / (area * 60.0)), "tubes1_alpha_W_m2K": pytest.approx(200.0)}
    assert tube_alpha_columns(model_with([hot], heat=False), row) == {}
