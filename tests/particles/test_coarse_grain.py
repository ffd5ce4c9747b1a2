"""Coarse-grained parcels (particles[i].coarse_grain = k: a parcel of diameter k d stands for
k^3 grains of diameter d) keep the grains' restitution, terminal velocity and lumped heating
time; combinations whose scaling is not implemented are refused naming the key."""

import math

import pytest

from tests.conftest import make_scene
from tests.kernels.test_gas import MU, RHO_G, SAND, cd_schiller_naumann, nu_ranz_marshall
from tidem.scene.errors import SceneError


def falling(k: float, d: float = 3e-4) -> dict:
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 3.0], "walls": "none", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": d}, "coarse_grain": k,
                    "positions": [[0.01, 0.01, 2.9]]}],
        gas={"cell_size": 0.02, "coupling_interval": 5},
        numerics={"dt": 2e-4, "force_dt": True},
    )


def terminal_velocity(d: float, rho_p: float = 2500.0) -> float:
    """(rho_p - rho_g) V g = C_D(Re) (pi d^2/4) rho_g v^2 / 2 (Schiller-Naumann), by bisection."""
    lo, hi = 0.01, 20.0
    for _ in range(100):
        vt = 0.5 * (lo + hi)
        drag = cd_schiller_naumann(RHO_G * vt * d / MU) * math.pi * d * d / 8 * RHO_G * vt * vt
        lo, hi = (vt, hi) if drag < (rho_p - RHO_G) * math.pi * d**3 / 6 * 9.81 else (lo, vt)
    return vt


def test_a_parcel_falls_at_its_grains_terminal_velocity(solver_for):
    s = solver_for(falling(2.0))
    assert 2 * s.state.radius.to_numpy()[0] == pytest.approx(6e-4), "the parcel is twice the grain"
    while s.t < 1.4:
        s.step()
    v = -s.state.v.to_numpy()[0, 2]
    grain, parcel_sized = terminal_velocity(3e-4), terminal_velocity(6e-4)
    assert parcel_sized > 1.3 * grain, "a grain of the parcel's size would fall clearly faster"
    assert v == pytest.approx(grain, rel=0.02)


def test_a_parcel_heats_in_its_grains_lumped_time(solver_for):
    d, u, t_gas, t_p, k = 2e-3, 1.0, 400.0, 300.0, 2.0
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.1], "walls": "none", "gravity": [0, 0, -9.81]},
        materials={"sand": {**SAND, "heat_capacity": 100.0}},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": d}, "coarse_grain": k,
                    "positions": [[0.01, 0.01, 0.05]], "fixed": True, "temperature": t_p}],
        heat={"gas_conductivity": 0.026, "initial_temperature": t_gas, "fluid_layer": 0.0},
        gas={"cell_size": 0.02, "inlet_velocity": u, "inlet_temperature": t_gas, "coupling_interval": 1},
        numerics={"dt": 1e-3, "force_dt": True},
    )
    s = solver_for(raw)
    for _ in range(3000):
        s.step()
    re = RHO_G * u * d / MU
    h = nu_ranz_marshall(re, 1005.0 * MU / 0.026) * 0.026 / d
    rate = h * math.pi * d * d / (2500 * math.pi * d**3 / 6 * 100.0)  # the grain's H / (m c)
    assert rate * s.t > 1.0, "the test covers most of the heating"
    expected = t_gas - (t_gas - t_p) * math.exp(-rate * s.t)
    assert s.state.T.to_numpy()[0] - t_p == pytest.approx(expected - t_p, rel=0.01)


@pytest.mark.parametrize("law", ["hertz_mindlin", "linear"])
def test_parcels_rebound_with_their_grains_restitution(solver_for, law):
    """contact.parcel_restitution = "grains": a head-on impact of two equal particles at 0.5 m/s each rebounds
    with the grains' restitution at k = 1 and 2."""
    ratios = []
    for k in (1.0, 2.0):
        d = 1e-3 * k
        raw = make_scene(
            contact={"model": law, "parcel_restitution": "grains"},
            materials={"sand": {**SAND, "restitution": 0.6}},
            particles=[{"name": "p", "material": "sand", "diameter": {"value": 1e-3}, "coarse_grain": k,
                        "positions": [[-0.51 * d, 0, 0], [0.51 * d, 0, 0]],
                        "velocities": [[0.5, 0, 0], [-0.5, 0, 0]]}],
            numerics={"dt_fraction": 0.02},
        )
        s = solver_for(raw)
        for _ in range(20000):
            s.step()
            if s.state.ncontact.to_numpy()[0] == 0 and s.state.v.to_numpy()[0, 0] < 0.0:
                break
        ratios.append(-s.state.v.to_numpy()[0, 0] / 0.5)
    assert ratios[0] == pytest.approx(0.6, rel=0.02)
    assert ratios[1] == pytest.approx(ratios[0], rel=0.01)


@pytest.mark.parametrize("law", ["hertz_mindlin", "hysteretic"])
def test_kinetic_theory_parcels_rebound_with_the_restitution_that_keeps_their_grains_dissipation(solver_for, law):
    """contact.parcel_restitution = "kinetic_theory": a head-on impact of two k = 2 parcels of grains with
    e = 0.9 rebounds with e_p = sqrt(1 - k (1 - e^2)) = 0.787 (Lu et al.'s EMMS-DPM; the grains' own 0.9
    is 14 % away), and a parcel hitting a wall keeps the wall pair's 0.9; 2 %."""
    d = 2e-3  # the parcel
    raw = make_scene(
        domain={"walls": "auto", "wall_material": "sand"},
        contact={"model": law},  # parcel_restitution: "kinetic_theory", the default
        materials={"sand": {**SAND, "restitution": 0.9}},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": 1e-3}, "coarse_grain": 2.0,
                    "positions": [[-0.51 * d, 0, 0], [0.51 * d, 0, 0], [0.1 - 0.51 * d, 0.05, 0]],
                    "velocities": [[0.5, 0, 0], [-0.5, 0, 0], [0.5, 0, 0]]}],
        numerics={"dt_fraction": 0.02, "max_overlap": 0.2},
    )
    s = solver_for(raw)
    while s.t < 6 * s.model.scales.contact:  # both impacts over, no other on the way
        s.step()
    v = s.state.v.to_numpy()[:, 0]
    assert -v[0] / 0.5 == pytest.approx(math.sqrt(1 - 2 * (1 - 0.81)), rel=0.02)
    assert -v[2] / 0.5 == pytest.approx(0.9, rel=0.02)


def test_kinetic_theory_parcel_restitution_is_refused_where_it_has_no_value():
    """k (1 - e^2) >= 1 leaves no restitution that keeps the grains' dissipation; one under the hysteretic law's
    floor is refused as a material's would be; a material's parcels need one k."""
    from tidem.particles.contact_params import hysteretic_floor_errors
    from tidem.scene.load import validate

    raw = heated_bed(coarse_grain=2.0)
    raw["materials"]["sand"]["restitution"] = 0.7  # 2 (1 - 0.49) = 1.02
    with pytest.raises(SceneError) as err:
        validate(raw)
    assert "k (1 - e^2) = 1.02 must stay below 1; use coarse_grain below 1.96" in str(err.value)
    raw["materials"]["sand"]["restitution"] = 0.9
    validate(raw)
    raw["contact"] = {"model": "hysteretic"}  # e_p = 0.0245 at k = 5.26: under the law's force floor
    raw["particles"][0]["coarse_grain"] = 5.26
    assert "kinetic-theory restitution 0.0245, below what the hysteretic law" in hysteretic_floor_errors(validate(raw).scene)[0]
    raw["contact"] = {}
    raw["particles"][0]["coarse_grain"] = 2.0
    del raw["heat"]
    raw["particles"].append({**raw["particles"][0], "name": "q", "coarse_grain": 1.5,
                             "region": {"min": [0, 0, 0.02], "max": [0.02, 0.02, 0.03]}})
    with pytest.raises(SceneError) as err:
        validate(raw)
    assert "particles[1].coarse_grain: with contact.parcel_restitution" in str(err.value)
    raw["contact"] = {"parcel_restitution": "grains"}
    validate(raw)  # the grains' restitution: any k, mixed


def heated_bed(**group) -> dict:
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.04], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": 1e-3},
                    "region": {"min": [0, 0, 0], "max": [0.02, 0.02, 0.01]}, **group}],
        heat={"gas_conductivity": 0.026, "initial_temperature": 300.0, "fluid_layer": 0.0},
    )


@pytest.mark.parametrize("edit, fragment", [
    ({"coarse_grain": 0.5}, "particles[0].coarse_grain"),
    ({"coarse_grain": float("nan")}, "particles[0].coarse_grain"),
    ({"coarse_grain": 20.0}, "particles[0].coarse_grain"),
    ({"coarse_grain": "2x"}, "particles[0].coarse_grain"),
])
def test_bad_coarse_grain_values_are_named(edit, fragment):
    from tidem.scene.load import validate

    with pytest.raises(SceneError) as err:
        validate(heated_bed(**edit))
    assert fragment in str(err.value)


def test_mixed_coarse_grain_with_heat_is_refused():
    from tidem.scene.load import validate

    raw = heated_bed(coarse_grain=2.0)
    raw["materials"]["coarse_sand"] = raw["materials"]["sand"]  # the parcel restitution: one k per material
    raw["particles"].append({**raw["particles"][0], "name": "q", "material": "coarse_sand", "coarse_grain": 1.5,
                             "region": {"min": [0, 0, 0.02], "max": [0.02, 0.02, 0.03]}})
    with pytest.raises(SceneError) as err:
        validate(raw)
    assert "particles[*].coarse_grain: with [heat] every group needs the same coarse_grain" in str(err.value)
    raw["particles"][1]["coarse_grain"] = 2.0
    validate(raw)
    del raw["heat"]
    raw["particles"][1]["coarse_grain"] = 1.5
    validate(raw)  # mixed k without heat: parcel geometry per group


LENS = 0.4  # heat.fluid_layer


def heat_rate(solver_for, k: float, case: str, d: float = 1e-3) -> float:
    """Heat rate [W] into a cold (300 K) fixed particle of grains d at k: from a 400 K twin
    ('pair'; touching at 1 % relative overlap, or 'pair_gap' at a gap of 0.1 % of the radius,
    inside the smallest gap s_min where the lens is not self-similar) or from the 400 K bottom
    wall ('wall'; 'wall_gap' at 5 % of the radius)."""
    r = 0.5 * k * d
    shift = {"pair": -0.01, "pair_gap": 0.001, "wall": -0.01, "wall_gap": 0.05}[case] * r
    pair = case.startswith("pair")
    positions = [[0.01, 0.01, 0.01], [0.01, 0.01, 0.01 + 2 * r + 2 * shift]] if pair else [[0.01, 0.01, r + shift]]
    group = {"material": "sand", "diameter": {"value": d}, "coarse_grain": k, "fixed": True}
    groups = [{"name": "cold", **group, "temperature": 300.0, "positions": positions[:1]}]
    walls = [{"point": [0, 0, 0], "normal": [0, 0, 1], "temperature": 400.0}]
    if pair:
        groups.append({"name": "hot", **group, "temperature": 400.0, "positions": positions[1:]})
        walls = []
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.02], "walls": "none", "gravity": [0, 0, 0]},
        materials={"sand": SAND}, particles=groups, walls=walls,
        heat={"gas_conductivity": 0.026, "initial_temperature": 300.0, "fluid_layer": LENS, "roughness": 1e-6},
    )
    s = solver_for(raw)
    return float(s.state.q.to_numpy()[0])


@pytest.mark.parametrize("case, power", [("pair", 1), ("pair_gap", 1), ("wall", 2), ("wall_gap", 2)])
def test_parcels_conduct_as_the_grains_they_stand_for(solver_for, case, power):
    """At the same relative overlap or gap, a pair of k = 2 parcels conducts k times a pair of
    grains (contact spot and gas lens: the bed's conductivity H/d is kept), and a parcel on a
    wall k^2 times a grain (the k^2 grains on its share of the wall: flux per wall area kept)."""
    grain, parcel = heat_rate(solver_for, 1.0, case), heat_rate(solver_for, 2.0, case)
    assert grain > 0.0
    assert parcel / grain == pytest.approx(2.0**power, rel=1e-9)


def test_a_char_parcel_burns_k3_grains_at_the_grains_rate(solver_for):
    """First step, still gas at 1123 K: the carbon a k = 2 parcel of 1 mm grains burns is 8
    times one grain's series rate (Field kinetics and film with the grain's diameter)."""
    from tests.kernels.test_reactions import char_scene, series_rate
    from tidem.heat.reactions import REACTED

    raw = char_scene([[0.008, 0.008, 0.008]], size=0.016)
    raw["particles"][0]["coarse_grain"] = 2.0
    raw["gas"]["cell_size"] = 0.008
    s = solver_for(raw)
    s.step()
    burnt = s.state.rsum.to_numpy()[REACTED] / s.dt
    assert burnt == pytest.approx(8 * series_rate(1e-3, 1123.0)[0], rel=1e-9)
    assert series_rate(2e-3, 1123.0)[0] * 8 > 1.2 * burnt, "the parcel's own size would burn clearly faster"


def test_a_sublimating_parcel_lasts_its_grains_d2_time(solver_for):
    """Nu = 2 in still gas held at 8000 K: a k = 2 parcel of 10 um grains is gone after the
    grain's t = rho L d^2 / (8 k dT) (2 %), a quarter of the time its own size would take."""
    from tests.kernels.test_reactions import K_AR, L_U, T_S, plasma_scene

    raw = plasma_scene([[0.001, 0.001, 0.001]], cp=520.0 * 1e4)
    raw["particles"][0]["coarse_grain"] = 2.0
    s = solver_for(raw)
    while s.state.active.to_numpy()[0] and s.steps < 5000:
        s.step()
    expected = 2200.0 * L_U * 1e-10 / (8 * K_AR * (8000.0 - T_S))
    t_sub = s.state.rt1.to_numpy()[0] - s.state.rt0.to_numpy()[0] + s.dt
    assert t_sub == pytest.approx(expected, rel=0.02)


@pytest.mark.parametrize("k, parcels", [(1.0, 800), (2.0, 100), (1.5, 237)])
def test_count_counts_grains_so_the_bed_mass_stays(k, parcels):
    """`count` of a region fill is in grains: k^3 grains per parcel, the bed's mass kept to one parcel."""
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    raw = heated_bed(coarse_grain=k, count=800)
    model = build_model(validate(raw))
    assert len(model.radius) == parcels
    grain_mass = 2500.0 * math.pi * 1e-9 / 6
    assert model.mass.sum() == pytest.approx(800 * grain_mass, rel=0.5 * k**3 / 800)


def test_passages_under_four_parcels_are_named_with_the_k_that_fits():
    """Advice, not an error: the narrowest passage under 4 parcels, with the largest k that fits it."""
    from tidem.scene.load import load
    from tidem.scene.passages import narrow_passages

    assert narrow_passages(load("lab_fluidized_bundle").scene) == []  # k = 3: tube gaps of 12.2 mm hold 4.1 parcels
    notes = narrow_passages(load("lab_fluidized_bundle", ["particles[0].coarse_grain=4"]).scene)
    assert len(notes) == 1
    assert "particles[0].coarse_grain = 4: the gap between tubes[1] and tubes[2] is 12.2 mm, 3.1 parcels" in notes[0]
    assert "(and 6 more passages under 4 parcels)" in notes[0] and "use coarse_grain <= 3 or" in notes[0]
    assert narrow_passages(load("lab_fluidized_bundle", ["particles[0].coarse_grain=1"]).scene) == []


def test_a_periodic_slab_a_few_parcels_deep_is_named():
    from tidem.scene.load import validate
    from tidem.scene.passages import narrow_passages

    raw = heated_bed(coarse_grain=2.0)
    raw["domain"]["max"] = [0.02, 0.007, 0.05]
    raw["domain"]["periodic"] = ["y"]
    raw["particles"][0]["region"] = {"min": [0, 0, 0], "max": [0.02, 0.007, 0.01]}
    notes = narrow_passages(validate(raw).scene)
    assert len(notes) == 1 and "the domain's y extent is 7 mm, 3.5 parcels of 2 mm" in notes[0]
    assert "use coarse_grain <= 1.7 or" in notes[0]
