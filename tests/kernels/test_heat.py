"""Heat conduction against the two-body lumped solution, conservation, the surface balance
and a hand calculation of Schluender's wall coefficient."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.kernels.heat import pfp_conductance_np, schluender_alpha_wp

STEEL = {"density": 7800.0, "youngs_modulus": 2e9, "poisson_ratio": 0.3, "restitution": 0.5, "friction": 0.3,
         "conductivity": 16.0, "heat_capacity": 500.0}
R = 0.005


def test_alpha_wp_hand_calculation():
    # lambda = 0.026 W/(m K), d = 1 mm, l + h_R = 1.068 um:
    # x = 2 * 1.068e-6 / 1e-3 = 2.136e-3; 4 lambda / d = 104;
    # (1 + x) ln(1 + 1/x) - 1 = 1.002136 * ln(469.16) - 1 = 5.1644  ->  537.1 W/(m^2 K)
    assert schluender_alpha_wp(0.026, 1e-3, 1.068e-6) == pytest.approx(537.1, rel=1e-3)


def touching_pair(overlap, **heat):
    """Two fixed steel spheres overlapping by `overlap`, at 423.15 and 293.15 K; dt = 0.1 s."""
    return make_scene(
        materials={"steel": STEEL},
        particles=[{"name": "hot", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[-R + overlap / 2, 0, 0]], "temperature": 423.15, "fixed": True},
                   {"name": "cold", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[R - overlap / 2, 0, 0]], "temperature": 293.15, "fixed": True}],
        heat=heat,
        numerics={"dt": 0.1, "force_dt": True},
    )


def touching_pair_conductance(overlap):
    """Contact spot (Batchelor & O'Brien, a = sqrt(R* delta)) and the gas lens around it [W/K]."""
    h = 2 * 16.0 * math.sqrt(R / 2 * overlap)
    return h + pfp_conductance_np(0.026, R / 2, -overlap, 1e-6 + 6.8e-8, 0.4 * R)


@pytest.mark.parametrize("every", [1, 10])
def test_two_fixed_spheres_relax_as_the_lumped_solution(solver_for, every):
    """Also with heat.conduction_interval = 10 (explicit steps of 1 s, rate x 1 s = 0.005: within 1 %)."""
    overlap = 1e-5
    s = solver_for(touching_pair(overlap, conduction_interval=every))
    m = 7800 * 4 / 3 * math.pi * R**3
    rate = touching_pair_conductance(overlap) * 2 / (m * 500.0)
    for _ in range(2000):
        s.step()
    T = s.state.T.to_numpy()
    expected = 130.0 * math.exp(-rate * s.t)
    assert s.t * rate > 0.5, "the test covers a good part of the relaxation"
    assert T[0] - T[1] == pytest.approx(expected, rel=0.01)
    assert T.mean() == pytest.approx(358.15, rel=1e-12)
    assert np.allclose(s.state.x.to_numpy()[:, 0], [-R + overlap / 2, R - overlap / 2])


def test_conduction_every_m_steps_is_one_explicit_step_of_m_dt(solver_for):
    """heat.conduction_interval = 10: the first step carries the heat of ten steps at the first
    temperatures (one explicit Euler step of 10 dt), the next nine none."""
    overlap, m_c = 1e-5, 7800 * 4 / 3 * math.pi * R**3 * 500.0
    s = solver_for(touching_pair(overlap, conduction_interval=10))
    flow = touching_pair_conductance(overlap) * 130.0  # into the cold sphere [W]
    s.step()
    after_one = s.state.T.to_numpy()
    assert after_one == pytest.approx([423.15 - 10 * 0.1 * flow / m_c, 293.15 + 10 * 0.1 * flow / m_c], rel=1e-12)
    for _ in range(9):
        s.step()
    assert np.array_equal(s.state.T.to_numpy(), after_one)
    s.step()
    assert s.state.T.to_numpy()[1] > after_one[1]


@pytest.mark.parametrize("gap", [-1e-5, 0.0, 5e-7, 2e-5, 1e-3])
def test_pfp_closed_form_is_the_lens_integral(gap):
    """H = int 2 pi k r dr / max(s, s_min), s = gap + r^2 / (2 R*), over s < delta_f (midpoint rule)."""
    k, r_eff, s_min, delta_f = 0.026, 0.0025, 1.068e-6, 0.002
    r0 = math.sqrt(max(0.0, -2 * r_eff * gap))
    r1 = math.sqrt(max(0.0, 2 * r_eff * (delta_f - gap)))
    r = np.linspace(r0, r1, 2_000_001)
    mid = 0.5 * (r[1:] + r[:-1])
    s = np.maximum(gap + mid**2 / (2 * r_eff), s_min)
    integral = float(np.sum(2 * np.pi * k * mid / s * np.diff(r)))
    assert pfp_conductance_np(k, r_eff, gap, s_min, delta_f) == pytest.approx(integral, rel=1e-4)


def test_spheres_apart_exchange_heat_through_the_gas_lens(solver_for):
    """Two fixed spheres 20 um apart: only the gas lens conducts; lumped two-body solution."""
    gap = 2e-5
    raw = make_scene(
        materials={"steel": STEEL},
        particles=[{"name": "hot", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[-R - gap / 2, 0, 0]], "temperature": 423.15, "fixed": True},
                   {"name": "cold", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[R + gap / 2, 0, 0]], "temperature": 293.15, "fixed": True}],
        heat={},
        numerics={"dt": 1.0, "force_dt": True},
    )
    s = solver_for(raw)
    m = 7800 * 4 / 3 * math.pi * R**3
    h = pfp_conductance_np(0.026, R / 2, gap, 1e-6 + 6.8e-8, 0.4 * R)
    rate = h * 2 / (m * 500.0)
    for _ in range(2000):
        s.step()
    T = s.state.T.to_numpy()
    assert s.t * rate > 0.2
    assert T[0] - T[1] == pytest.approx(130.0 * math.exp(-rate * s.t), rel=0.01)
    raw["heat"] = {"fluid_layer": 0.0}
    s = solver_for(raw)
    for _ in range(10):
        s.step()
    assert np.array_equal(s.state.T.to_numpy(), [423.15, 293.15]), "fluid_layer = 0 turns the gas path off"


@pytest.mark.parametrize("precision, every", [("float64", 1), ("mixed", 1), ("float64", 7)])
def test_isolated_bed_keeps_its_heat(solver_for, precision, every):
    """Each pair's heat flow is added to one partner and subtracted from the other, the same value
    (with precision 'mixed' rounded to float32 once, for both): the bed's heat stays to rounding,
    also when the conduction is evaluated every 7th step (heat.conduction_interval)."""
    rng = np.random.default_rng(1)
    g = (np.arange(4) - 1.5) * 0.00995  # slightly overlapping: long contacts
    pos = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    raw = make_scene(
        domain={"min": [-0.03, -0.03, -0.03], "max": [0.03, 0.03, 0.03], "gravity": [0, 0, -9.81],
                "walls": ["x-", "x+", "y-", "y+", "z-", "z+"]},
        materials={"steel": {**STEEL, "heat_capacity": 0.05}},  # thermal time ~ 0.02 s: heat moves
        particles=[{"name": "bed", "material": "steel", "diameter": {"distribution": "mono", "value": 0.01},
                    "positions": pos.tolist(), "velocities": rng.normal(0, 0.05, pos.shape).tolist()}],
        heat={"conduction_interval": every},
        numerics={"precision": precision},
    )
    s = solver_for(raw)
    s.state.T.from_numpy(rng.uniform(300, 900, len(pos)))
    c = 7800 * 4 / 3 * math.pi * 0.005**3 * 0.05
    q0 = c * s.state.T.to_numpy().sum()
    spread0 = s.state.T.to_numpy().std()
    touched = 0
    for _ in range(10000):
        s.step()
        touched = max(touched, int(s.state.ncontact.to_numpy().sum()))
    assert touched > 10
    assert c * s.state.T.to_numpy().sum() == pytest.approx(q0, rel=1e-12)
    assert s.state.T.to_numpy().std() < 0.95 * spread0, "heat was exchanged"


@pytest.mark.parametrize("every", [1, 5])
def test_heat_from_a_hot_tube_equals_heat_gained_by_the_bed(solver_for, every):
    """The tube's delivered heat (its flow times dt, or times 5 dt at every 5th step with
    heat.conduction_interval = 5) is what the bed gains."""
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.06, 0.012, 0.08], "periodic": ["x"], "gravity": [0, 0, -9.81],
                "walls": ["y-", "y+", "z-"]},
        materials={"steel": STEEL},
        tubes=[{"center": [0.03, 0, 0.025], "axis": "y", "diameter": 0.02, "temperature": 500.0}],
        particles=[{"name": "bed", "material": "steel", "diameter": {"distribution": "mono", "value": 0.004},
                    "region": {"min": [0, 0, 0], "max": [0.06, 0.012, 0.06]}, "temperature": 300.0}],
        heat={"conduction_interval": every},
    )
    s = solver_for(raw)
    c = 7800 * 4 / 3 * math.pi * 0.002**3 * 500.0
    e0 = c * s.state.T.to_numpy().sum()
    while s.t < 0.1:
        s.step()
    gained = c * s.state.T.to_numpy().sum() - e0
    delivered = s.heat_summary()["tubes0_heat_J"]
    assert gained > 1e-3
    assert delivered == pytest.approx(gained, rel=0.01)


def test_wall_contact_conductance_matches_the_formula(solver_for):
    overlap = 1e-5
    raw = make_scene(
        domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "walls": ["z-"], "wall_temperature": 400.0,
                "gravity": [0, 0, 0]},
        materials={"steel": STEEL},
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0, 0, -0.1 + R - overlap]], "temperature": 300.0, "fixed": True}],
        heat={"gas_conductivity": 0.03, "gas_mean_free_path": 7e-8, "roughness": 2e-6},
        numerics={"dt": 1e-4, "force_dt": True},
    )
    s = solver_for(raw)
    h = 2 * 16.0 * math.sqrt(R * overlap) + schluender_alpha_wp(0.03, 2 * R, 2.07e-6) * math.pi * R**2
    assert s.state.q.to_numpy()[0] == pytest.approx(h * 100.0, rel=1e-9)
    gap = 1e-4  # apart from the wall: the gas lens with R* = r (a wall is a sphere of infinite radius)
    raw["particles"][0]["positions"] = [[0, 0, -0.1 + R + gap]]
    s = solver_for(raw)
    h = pfp_conductance_np(0.03, R, gap, 2.07e-6, 0.4 * R)
    assert h > 0 and s.state.q.to_numpy()[0] == pytest.approx(h * 100.0, rel=1e-9)
    assert s.state.surf_rate.to_numpy()[0] == pytest.approx(h * 100.0, rel=1e-9)


def test_unstable_thermal_step_is_refused():
    from tidem.scene.errors import SceneError
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    raw = make_scene(materials={"steel": {**STEEL, "heat_capacity": 1e-9}}, heat={})
    with pytest.raises(SceneError, match="explicit conduction limit"):
        build_model(validate(raw))
    raw = touching_pair(1e-5, conduction_interval=5000)  # m c / H ~ 200 s, evaluated every 500 s
    with pytest.raises(SceneError, match=r"heat.conduction_interval: .* every 5000 steps, an explicit step of 500 s, "
                                         r"above the conduction limit .*; lower heat.conduction_interval to \d+ or less"):
        build_model(validate(raw))


def test_no_heat_table_builds_no_thermal_state(solver_for):
    s = solver_for(make_scene())
    assert not hasattr(s.state, "T")
    assert not s.model.features.heat
    assert "heat" not in " ".join(s.model.features.kernels())


def test_tube_heat_lands_in_the_angle_bin_of_the_contact(solver_for):
    """A fixed particle on the flank of a hot tube at omega = 80 deg from the top: all the tube's
    heat goes through the sector [45, 90) deg, and the profile's mean equals the tube's heat flow."""
    from tidem.results.tables import alpha_profile

    r_t, overlap = 0.01, 1e-5
    raw = make_scene(
        domain={"min": [-0.05, 0.0, -0.05], "max": [0.05, 0.02, 0.05], "walls": "none", "gravity": [0, 0, 0]},
        materials={"steel": STEEL},
        tubes=[{"center": [0.0, 0.0, 0.0], "axis": "y", "diameter": 2 * r_t, "temperature": 400.0}],
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[(r_t + R - overlap) * math.sin(math.radians(80)), 0.01,
                                   (r_t + R - overlap) * math.cos(math.radians(80))]],
                    "temperature": 300.0, "fixed": True}],
        heat={"initial_temperature": 300.0, "angle_bins": 8},
        numerics={"dt": 1e-3, "force_dt": True},
    )
    s = solver_for(raw)
    for _ in range(10):
        s.step()
    rows, means = alpha_profile(s.model, s)
    hot = [r for r in rows if r["alpha_W_m2K"] > 0]
    assert [r["angle_deg"] for r in hot] == [67.5]
    area = 2 * math.pi * r_t * 0.02
    flow = s.heat_summary()["tubes0_heat_W"]
    assert means[0]["mean_alpha_W_m2K"] == pytest.approx(flow / area / 100.0, rel=1e-3)


def test_a_tubes_alpha_splits_into_contact_spot_gas_gap_and_gas_lens(solver_for):
    """Two fixed particles by a hot tube, one touching it (overlap 1e-5 m), one 0.1 mm off it: the tube's
    mean alpha splits into the touching one's contact spot 2 k sqrt(R delta) and Schluender gap
    alpha_WP pi R^2 (source 3 eq. 20) and the other one's gas lens (Rong & Horio), each to 1e-6."""
    from tidem.results.tables import alpha_profile

    r_t, overlap, gap = 0.01, 1e-5, 1e-4
    on, off = r_t + R - overlap, r_t + R + gap
    raw = make_scene(
        domain={"min": [-0.05, 0.0, -0.05], "max": [0.05, 0.02, 0.05], "walls": "none", "gravity": [0, 0, 0]},
        materials={"steel": STEEL},
        tubes=[{"center": [0.0, 0.0, 0.0], "axis": "y", "diameter": 2 * r_t, "temperature": 400.0}],
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0.0, 0.01, on], [0.0, 0.01, -off]], "temperature": 300.0, "fixed": True}],
        heat={"initial_temperature": 300.0, "angle_bins": 8, "gas_conductivity": 0.03, "gas_mean_free_path": 7e-8,
              "roughness": 2e-6},
        numerics={"dt": 1e-6, "force_dt": True},
    )
    s = solver_for(raw)
    for _ in range(10):
        s.step()
    _rows, means = alpha_profile(s.model, s)
    area = 2 * math.pi * r_t * 0.02  # conductance [W/K] per alpha [W/(m^2 K)]
    split = {key: means[0][f"{key}_alpha_W_m2K"] * area for key in ("contact_spot", "gas_gap", "gas_lens")}
    assert split["contact_spot"] == pytest.approx(2 * 16.0 * math.sqrt(R * overlap), rel=1e-6)
    assert split["gas_gap"] == pytest.approx(schluender_alpha_wp(0.03, 2 * R, 2.07e-6) * math.pi * R**2, rel=1e-6)
    assert split["gas_lens"] == pytest.approx(pfp_conductance_np(0.03, R, gap, 2.07e-6, 0.4 * R), rel=1e-6)
    assert sum(split.values()) == pytest.approx(means[0]["mean_alpha_W_m2K"] * area, rel=1e-12)
