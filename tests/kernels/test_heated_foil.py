"""Heated-foil tubes (fixed heat flux, source 3's measurement) and wall radiation: the foil
against its closed-form two-body solution, heat conservation, conduction along the foil
against the decay of a ring mode, and the radiation term against a hand calculation."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.kernels.heat import STEFAN_BOLTZMANN, schluender_alpha_wp

STEEL = {"density": 7800.0, "youngs_modulus": 2e9, "poisson_ratio": 0.3, "restitution": 0.5, "friction": 0.3,
         "conductivity": 16.0, "heat_capacity": 500.0}
R, R_TUBE, DEPTH, BINS = 0.005, 0.01, 0.02, 8
FLUX, FOIL_C, T0 = 1000.0, 200.0, 300.0


def foil_scene(overlap=1e-5, angle_deg=80.0, **tube):
    """One fixed steel sphere touching a heated-foil tube at `angle_deg` from its top."""
    a = math.radians(angle_deg)
    centre = R_TUBE + R - overlap
    return make_scene(
        domain={"min": [-0.05, 0.0, -0.05], "max": [0.05, DEPTH, 0.05], "walls": "none", "gravity": [0, 0, 0]},
        materials={"steel": STEEL},
        tubes=[{"center": [0.0, 0.0, 0.0], "axis": "y", "diameter": 2 * R_TUBE, "heat_flux": FLUX,
                "foil_heat_capacity": FOIL_C, **tube}],
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[centre * math.sin(a), 0.01, centre * math.cos(a)]], "fixed": True}],
        heat={"initial_temperature": T0, "angle_bins": BINS},
        numerics={"dt": 1e-3, "force_dt": True},
    )


def two_body(c_f, c_p, power, h, t):
    """Foil (C_f, heated with P) and sphere (C_p) joined by H, both from T0:
    C_f T_f' = P - H (T_f - T_p), C_p T_p' = H (T_f - T_p). D = T_f - T_p relaxes to
    D_inf = P C_p / (H (C_f + C_p)) at the rate H (1/C_f + 1/C_p); the sum follows
    C_f T_f + C_p T_p = (C_f + C_p) T0 + P t. Returns (T_f, T_p, rate t)."""
    rate = h * (1 / c_f + 1 / c_p)
    d = power * c_p / (h * (c_f + c_p)) * (1 - math.exp(-rate * t))
    t_f = T0 + (power * t + c_p * d) / (c_f + c_p)
    return t_f, t_f - d, rate * t


def touching_conductance(overlap):
    """Contact spot plus Schluender's coefficient over pi r^2 of the steel sphere [W/K]."""
    return 2 * 16.0 * math.sqrt(R * overlap) + schluender_alpha_wp(0.026, 2 * R, 1e-6 + 6.8e-8) * math.pi * R**2


C_SPHERE = 7800 * 4 / 3 * math.pi * R**3 * 500.0


def test_foil_and_touching_sphere_follow_the_two_body_solution(solver_for):
    """Bin b of the foil (C_f = C_A A_b, heated with P = q A_b) and the sphere follow
    `two_body`; untouched bins rise as q t / C_A."""
    overlap = 1e-5
    s = solver_for(foil_scene(overlap))
    area = 2 * math.pi * R_TUBE / BINS * DEPTH
    for _ in range(5000):
        s.step()
    t = s.t
    t_f, t_p, relaxed = two_body(FOIL_C * area, C_SPHERE, FLUX * area, touching_conductance(overlap), t)
    assert relaxed > 2.0, "the test covers the relaxation"
    foil = s.state.tube_bin_T.to_numpy()[0]
    touched = int(80.0 / (360.0 / BINS))
    assert foil[touched] - T0 == pytest.approx(t_f - T0, rel=0.01)
    assert s.state.T.to_numpy()[0] - T0 == pytest.approx(t_p - T0, rel=0.01)
    others = np.delete(foil, touched)
    assert np.allclose(others - T0, FLUX * t / FOIL_C, rtol=1e-9)
    # heat: electric heating = foil heat + sphere heat, to rounding
    stored = FOIL_C * area * (foil - T0).sum() + C_SPHERE * (s.state.T.to_numpy()[0] - T0)
    assert stored == pytest.approx(FLUX * 2 * math.pi * R_TUBE * DEPTH * t, rel=1e-9)


@pytest.mark.parametrize("every", [1, 4])
def test_heated_foil_wall_and_touching_sphere_follow_the_two_body_solution(solver_for, every):
    """A plane wall with a heat flux: one foil over the domain's cross-section A (C_f = C_A A,
    P = q A); the sphere on it follows `two_body`, and the heat is conserved to rounding, also
    with heat.conduction_interval = 4 (the foil takes the held flow each step, the sphere four
    steps of it at once: they balance after every 4 steps)."""
    overlap, c_a, flux, c_sphere = 1e-5, 1.0, 1.0, C_SPHERE / 100  # relaxes within a second
    raw = make_scene(
        materials={"steel": {**STEEL, "heat_capacity": 5.0}},
        walls=[{"point": [0, 0, -0.1], "normal": [0, 0, 1], "heat_flux": flux, "foil_heat_capacity": c_a}],
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0, 0, -0.1 + R - overlap]], "fixed": True}],
        heat={"initial_temperature": T0, "conduction_interval": every},
        numerics={"dt": 1e-3, "force_dt": True},
    )
    s = solver_for(raw)
    area = 0.2 * 0.2
    for _ in range(3000):
        s.step()
    t_f, t_p, relaxed = two_body(c_a * area, c_sphere, flux * area, touching_conductance(overlap), s.t)
    foil, sphere = s.state.plane_foil_T.to_numpy()[0], s.state.T.to_numpy()[0]
    assert relaxed > 2.0 and sphere - T0 > 1.0
    assert foil - T0 == pytest.approx(t_f - T0, rel=0.01)
    assert sphere - T0 == pytest.approx(t_p - T0, rel=0.01)
    stored = c_a * area * (foil - T0) + c_sphere * (sphere - T0)
    assert stored == pytest.approx(flux * area * s.t, rel=1e-9)
    assert s.heat_summary()["walls0_foil_T_K"] == foil


def test_alpha_of_a_foil_is_the_flux_over_the_foil_excess(solver_for):
    """Source 3 eq. 4: alpha(omega) = q / (T_foil(omega) - T_ref), time-averaged since
    heat.profile_start; the storage share says how far from steady the foil still is."""
    from tidem.results.tables import alpha_profile

    s = solver_for(foil_scene())
    s.step()  # the profile starts at the end of the first step (heat.profile_start = 0)
    sums = np.zeros(BINS)
    for _ in range(200):
        sums += s.dt * s.state.tube_bin_T.to_numpy()[0]  # the kernel integrates T before the update
        s.step()
    rows, means = alpha_profile(s.model, s)
    excess = sums / (s.t - s.profile_t0) - T0
    assert [r["alpha_W_m2K"] for r in rows] == pytest.approx(list(FLUX / excess), rel=1e-6)
    assert means[0]["mean_alpha_W_m2K"] == pytest.approx(np.mean(FLUX / excess), rel=1e-6)
    assert means[0]["alpha_of_mean_excess_W_m2K"] == pytest.approx(FLUX / excess.mean(), rel=1e-6)
    assert 90.0 < means[0]["foil_storage_pct"] < 100.0, "200 ms into a 2 s transient, the foil still stores most"


def test_conduction_along_the_foil_decays_a_ring_mode(solver_for):
    """With no particle near it, a foil perturbed by A cos(omega) keeps its mean rising as
    q t / C_A and loses the mode as exp(-G t / (C_A r^2)) (heat equation on the ring, k = 1/r),
    within 1 % (36 bins: the discrete Laplacian is 0.25 % weaker)."""
    g = 0.05  # W/K: a 3 mm steel sheet
    raw = foil_scene(foil_conductance=g)
    raw["particles"][0]["positions"] = [[0.04, 0.01, 0.04]]
    raw["heat"]["angle_bins"] = 36
    s = solver_for(raw)
    omega = (np.arange(36) + 0.5) * 2 * math.pi / 36
    s.state.tube_bin_T.from_numpy(T0 + 10.0 * np.cos(omega)[None, :])
    for _ in range(1000):
        s.step()
    foil = s.state.tube_bin_T.to_numpy()[0]
    amplitude = 2 * np.mean((foil - foil.mean()) * np.cos(omega))
    decay = math.exp(-g * s.t / (FOIL_C * R_TUBE**2))
    assert decay < 0.5, "the mode has decayed by more than half"
    assert amplitude == pytest.approx(10.0 * decay, rel=0.01)
    assert foil.mean() - T0 == pytest.approx(FLUX * s.t / FOIL_C, rel=1e-9)


def test_radiation_from_a_hot_wall_matches_the_hand_calculation(solver_for):
    """A sphere (eps 0.8) touching a 1000 K wall (eps 0.5): conduction plus
    C sigma pi r^2 (T_w^4 - T_p^4), C = 1 / (1/0.8 + 1/0.5 - 1) = 0.4444."""
    overlap = 1e-5
    raw = make_scene(
        domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "walls": ["z-"], "wall_temperature": 1000.0,
                "wall_material": "wall", "gravity": [0, 0, 0]},
        materials={"steel": {**STEEL, "emissivity": 0.8}, "wall": {**STEEL, "emissivity": 0.5}},
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0, 0, -0.1 + R - overlap]], "temperature": 300.0, "fixed": True}],
        heat={"radiation": True},
        numerics={"dt": 1e-4, "force_dt": True},
    )
    s = solver_for(raw)
    h = 2 * 16.0 * math.sqrt(R * overlap) + schluender_alpha_wp(0.026, 2 * R, 1e-6 + 6.8e-8) * math.pi * R**2
    radiation = STEFAN_BOLTZMANN * math.pi * R**2 * (1000.0**4 - 300.0**4) / (1 / 0.8 + 1 / 0.5 - 1)
    assert radiation > 0.1 * h * 700.0, "radiation is a sizeable share at 1000 K"
    assert s.state.q.to_numpy()[0] == pytest.approx(h * 700.0 + radiation, rel=1e-9)
    raw["heat"]["radiation"] = False
    s = solver_for(raw)
    assert s.state.q.to_numpy()[0] == pytest.approx(h * 700.0, rel=1e-9)
