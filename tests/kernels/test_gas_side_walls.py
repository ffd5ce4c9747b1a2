"""`gas.side_walls = "no_slip"`: gas rising between two side walls takes plane Poiseuille flow."""

import numpy as np
import pytest

from tests.conftest import make_scene

W, H_CELL, U, MU = 0.012, 0.001, 0.05, 1e-3  # channel width, cell, mean velocity; a viscous gas develops fast


def test_gas_between_no_slip_side_walls_takes_the_parabola_of_plane_poiseuille_flow(solver_for):
    """Air entering uniformly at 0.05 m/s between two walls 12 cells apart (periodic in y), viscosity 1e-3 Pa s
    (Re = 0.7, viscous time W^2 / (pi^2 nu) = 18 ms): after 0.1 s the profile 12 mm up is Poiseuille's
    parabola u = 6 U x (W - x) / W^2 within 2 % of its centre velocity (centre / mean 1.5), and within 0.2 %
    the steady solution of the discrete equations, whose mirror ghost (-u beyond the wall) adds G h^2 / 8 to
    the parabola: u ~ x (W - x) + h^2 / 4, centre / mean 1.4795 at 12 cells. The mean stays U (1e-9). Free
    slip, the default, would keep the inlet's flat profile (centre / mean 1)."""
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [W, 0.002, 0.024], "walls": "auto", "periodic": ["y"],
                "gravity": [0, 0, -9.81]},
        particles=[{"name": "p", "material": "steel", "diameter": {"value": 1e-4}, "fixed": True,
                    "positions": [[0.0005, 0.001, 0.0235]]}],
        gas={"cell_size": H_CELL, "inlet_velocity": U, "viscosity": MU, "coupling_interval": 1,
             "averaging_length": "cells", "side_walls": "no_slip"},
        numerics={"dt": 1e-4, "force_dt": True, "t_end": 0.1},
    )
    s = solver_for(raw)
    for _ in range(1000):
        s.step()
    w = s.gas.G.u[2].to_numpy()[:, :, 12].mean(axis=1)  # u_z on the faces at z = 12 mm, across x
    x = (np.arange(len(w)) + 0.5) * H_CELL
    assert w.mean() == pytest.approx(U, rel=1e-9)
    assert np.abs(w - 6 * U * x * (W - x) / W**2).max() < 0.02 * 1.5 * U
    discrete = x * (W - x) + H_CELL**2 / 4
    assert w == pytest.approx(U * discrete / discrete.mean(), rel=0.002)
