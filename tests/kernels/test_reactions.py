"""Reacting particles against closed forms and conservation: char combustion in the kinetic,
film-diffusion and mixed regimes (Field 1969 kinetics in series with Ranz-Marshall film
transfer), carbon, O2 and energy balances to rounding, burnout without NaN or a dangling
contact, polymerization heat against the lumped ODE, sublimation against the d^2 law, and a
sublimating cloud that cools its gas by exactly the heat it takes."""

import math
import re

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.heat.reactions import (ENTHALPY_OUT, GONE, H_CO, H_CO2, HEAT_RELEASED, LATENT, M_C, M_O2, O2_USED, R_GAS,
                                  REACTED)
from tidem.scene.errors import SceneError
from tidem.sim.solver import RunError

T_BED, RHO_G, MU_G, CP_G, K_G = 1123.0, 0.315, 4.5e-5, 1150.0, 0.07
D_O2, X_O2, P = 2.0e-4, 0.21, 101325.0
CHAR = {"density": 1200.0, "youngs_modulus": 1e7, "restitution": 0.9, "friction": 0.3, "conductivity": 0.2,
        "heat_capacity": 1000.0}
SAND = {"density": 2500.0, "youngs_modulus": 1e7, "restitution": 0.9, "friction": 0.3, "conductivity": 3.0,
        "heat_capacity": 800.0}


def char_scene(positions, d=1e-3, reaction=None, inlet=0.0, size=0.008, sand=None, gas=None, **numerics):
    groups = [{"name": "char", "material": "char", "diameter": {"value": d}, "positions": positions, "fixed": True}]
    if sand:
        groups.append({"name": "sand", "material": "sand", "diameter": {"value": 1e-3}, "positions": sand,
                       "fixed": True})
    return make_scene(
        domain={"min": [0, 0, 0], "max": [size, size, size], "walls": "none", "gravity": [0, 0, 0]},
        materials={"char": CHAR, "sand": SAND},
        particles=groups,
        heat={"initial_temperature": T_BED, "gas_conductivity": K_G},
        gas={"cell_size": 0.004, "density": RHO_G, "viscosity": MU_G, "heat_capacity": CP_G, "coupling_interval": 1,
             "inlet_velocity": inlet, "oxygen": {"mole_fraction": X_O2, "diffusivity": D_O2}, **(gas or {})},
        reactions=[{"type": "char_combustion", "group": "char", **(reaction or {})}],
        numerics={"dt": 1e-4, "force_dt": True, **numerics},
    )


def series_rate(d, T, A=0.8596, E=1.494e5, phi=0.0, sh=2.0, Tg=T_BED, x=X_O2):
    """Carbon rate [kg/s] of a char particle (Field kinetics in series with the film)."""
    k_s = A * math.exp(-E / (R_GAS * T))
    nu = 1 - phi / 2
    k_d = M_C / nu * sh * D_O2 / (d * R_GAS * 0.5 * (T + Tg))
    return math.pi * d * d * x * P / (1 / k_s + 1 / k_d), math.pi * d * d * x * P * k_s, math.pi * d * d * x * P * k_d


@pytest.mark.parametrize("A, regime", [(0.8596, "mixed"), (1e-6, "kinetic"), (1e6, "diffusion")])
def test_char_rate_matches_closed_form(solver_for, A, regime):
    """First step: particle and gas at 1123 K, still gas (Sh = 2), O2 at 0.21: the carbon burnt
    is the series rate times dt; in the limits it is the kinetic or film rate alone."""
    s = solver_for(char_scene([[0.004, 0.004, 0.004]], reaction={"pre_exponential": A}))
    s.step()
    burnt = s.state.rsum.to_numpy()[REACTED] / s.dt
    series, kinetic, film = series_rate(1e-3, T_BED, A=A)
    assert burnt == pytest.approx(series, rel=1e-9)
    if regime == "kinetic":
        assert burnt == pytest.approx(kinetic, rel=1e-4)
    elif regime == "diffusion":
        assert burnt == pytest.approx(film, rel=1e-4)
    else:
        assert 0.1 < kinetic / film < 0.5, "Field's kinetics at 1123 K: mixed control for 1 mm char"


def o2_after_one_step(s, Y):
    """Set the gas' O2 mass fractions to Y, take one DEM step without a gas step (the first of two per gas step),
    and return the O2 each cell was charged and the carbon burnt per second."""
    s.gas.G.Y.from_numpy(Y)
    s.step()
    return s.gas.G.o2_sink.to_numpy(), s.state.rsum.to_numpy()[REACTED] / s.dt


def test_a_cell_without_oxygen_gives_none(solver_for):
    """A char particle at the corner shared by eight cells, the four cells at x < 4 mm emptied of O2:
    it burns at the series rate of half the O2 fraction, and the whole O2 it took is charged to the four
    cells that hold O2 (with the cloud-in-cell weights alone, half was charged to the empty cells, which
    then went negative and stopped char_combustion runs)."""
    s = solver_for(char_scene([[0.004, 0.004, 0.004]], gas={"coupling_interval": 2}))
    Y = s.gas.G.Y.to_numpy()
    Y[0] = 0.0
    sink, burnt = o2_after_one_step(s, Y)
    assert burnt == pytest.approx(series_rate(1e-3, T_BED, x=X_O2 / 2)[0], rel=1e-9)
    assert np.all(sink[0] == 0.0)
    assert sink[1].sum() == pytest.approx(s.state.rsum.to_numpy()[O2_USED], rel=1e-12)
    assert np.ptp(sink[1]) <= 1e-12 * sink[1].max(), "the four full cells give alike"


def test_a_char_beside_a_tube_takes_no_oxygen_from_inside_it(solver_for):
    """Cells whose centre lies in a tube hold no gas: a char particle whose cloud-in-cell cube reaches
    two of them sees the O2 of the fluid cells alone, and none of what it takes is charged to the solid
    cells (whose charge the gas step never collects: that O2 would have left the balance)."""
    raw = char_scene([[0.004, 0.004, 0.004]], gas={"coupling_interval": 2})
    raw["tubes"] = [{"center": [0.002, 0.0, 0.002], "axis": "y", "diameter": 0.003, "material": "sand"}]
    s = solver_for(raw)
    solid = s.gas.G.solid.to_numpy() == 1
    assert solid.sum() == 2, "the cells at x = z = 2 mm lie in the tube"
    sink, burnt = o2_after_one_step(s, s.gas.G.Y.to_numpy())
    assert burnt == pytest.approx(series_rate(1e-3, T_BED)[0], rel=1e-9)
    assert np.all(sink[solid] == 0.0)
    assert sink.sum() == pytest.approx(s.state.rsum.to_numpy()[O2_USED], rel=1e-12)


def totals(s):
    """Carbon [kg], O2 [kg] and energy [J] ledgers that must stay constant."""
    S, G = s.state, s.gas.G
    r = S.rsum.to_numpy()
    b = G.bsum.to_numpy()
    active = S.active.to_numpy().astype(bool)
    char = active & (s.model.reaction_index >= 0)
    V = s.gas.gg.volume
    eps, Y, T = G.eps.to_numpy(), G.Y.to_numpy(), G.T.to_numpy()
    carbon = S.mass.to_numpy()[char].sum() + r[REACTED]
    o2 = RHO_G * V * (eps * Y).sum() - G.o2_sink.to_numpy().sum() + r[O2_USED] - b[1]
    mc = 1.0 / S.inv_heat_cap.to_numpy()
    energy = (mc * S.T.to_numpy())[active].sum() + RHO_G * CP_G * V * (eps * T).sum() + G.Qs.to_numpy().sum() \
        - b[0] + r[ENTHALPY_OUT] - r[HEAT_RELEASED]
    return np.array([carbon, o2, energy]), r


@pytest.mark.parametrize("phi", [0.0, 0.5])
def test_carbon_oxygen_and_energy_balances_close(solver_for, phi):
    """Three char particles in a gas flowing at 0.1 m/s for 300 steps: carbon, O2 and energy
    ledgers stay constant to 1e-9 of what moved; heat released = enthalpy x moles reacted."""
    pos = [[0.003, 0.004, 0.002], [0.005, 0.004, 0.004], [0.004, 0.003, 0.006]]
    s = solver_for(char_scene(pos, reaction={"co_fraction": phi}, inlet=0.1))
    before, _ = totals(s)
    for _ in range(300):
        s.step()
    after, r = totals(s)
    moles = r[REACTED] / M_C
    assert r[HEAT_RELEASED] == pytest.approx(moles * ((1 - phi) * H_CO2 + phi * H_CO), rel=1e-9)
    assert r[O2_USED] == pytest.approx(moles * (1 - phi / 2) * M_O2, rel=1e-9)
    assert s.state.T.to_numpy().max() > T_BED + 1.0, "burning char heats up"
    moved = np.array([r[REACTED], r[O2_USED], r[HEAT_RELEASED]])
    assert np.all(np.abs(after - before) <= 1e-6 * moved), (after - before) / moved


def test_burning_cloud_takes_the_same_oxygen_on_every_run(solver_for):
    """3375 char particles in 8 gas cells, one gas step per step, on all threads: the O2 they take and
    the heat of those that burn out reach the gas cells in particle order (`kernels/reactions.py`), so
    two runs agree to the last bit (summed by atomics in the parallel loop, the order of the adds
    varied from run to run and with it the last bits of the gas' O2 and of every particle after it)."""
    ticks = (np.arange(15) + 0.5) * 0.008 / 15
    pos = np.stack(np.meshgrid(ticks, ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 3).tolist()
    runs = []
    for _ in range(2):
        s = solver_for(char_scene(pos, d=4e-4))
        for _ in range(30):
            s.step()
        runs.append((s.gas.G.Y.to_numpy(), s.state.mass.to_numpy(), s.state.T.to_numpy(), s.gas.G.Qs.to_numpy()))
    assert runs[0][1].min() < runs[0][1].max(), "the char must burn"
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_a_cell_emptied_within_one_gas_step_is_refused_by_name(solver_for):
    """The same cloud with a gas step of 10 DEM steps: its 422 chars a cell, film-limited, would take
    several times the O2 their cell holds before the gas step sees it (the take is explicit); the run
    stops with the cell's position and the setting that shortens the gas step, not with negative O2."""
    ticks = (np.arange(15) + 0.5) * 0.008 / 15
    pos = np.stack(np.meshgrid(ticks, ticks, ticks, indexing="ij"), axis=-1).reshape(-1, 3).tolist()
    s = solver_for(char_scene(pos, d=4e-4, reaction={"pre_exponential": 1e3}, gas={"coupling_interval": 10}))
    with pytest.raises(RunError) as stop:
        for _ in range(40):
            s.step()
    message = str(stop.value)
    assert "took more O2 from a gas cell" in message and "gas.coupling_interval (now 10)" in message
    assert re.search(r"the cell centred at \(0\.00[26], 0\.00[26], 0\.00[26]\) m", message), message


def test_burnt_out_particle_disappears_cleanly(solver_for):
    """A 0.2 mm char particle (100 kg/m3) touching a sand grain burns out in the film-limited
    regime: it is removed, nothing turns NaN, the neighbour list no longer holds the pair (in
    either particle's row), and carbon and O2 still balance."""
    light = {**CHAR, "density": 100.0, "heat_capacity": 1e5}
    raw = char_scene([[0.004, 0.004, 0.0044]], d=2e-4, reaction={"pre_exponential": 1e3}, sand=[[0.004, 0.004, 0.0038]])
    raw["materials"]["char"] = light
    s = solver_for(raw)

    def listed(S):
        nbr, cnt = S.nbr.to_numpy(), S.nbr_n.to_numpy()
        return 0 in nbr[1, :cnt[1]] or 1 in nbr[0, :cnt[0]]

    assert listed(s.state), "the two particles are neighbours"
    before, _ = totals(s)
    for _ in range(3000):
        s.step()
        if not s.state.active.to_numpy()[0]:
            break
    S = s.state
    assert not S.active.to_numpy()[0] and S.rsum.to_numpy()[GONE] == 1
    assert S.active.to_numpy()[1] == 1
    assert not listed(S)
    for _ in range(20):
        s.step()
    s.check()
    for name in ("x", "v", "T", "mass", "radius"):
        assert np.isfinite(getattr(S, name).to_numpy()).all(), name
    assert np.isfinite(s.gas.G.T.to_numpy()).all() and np.isfinite(s.gas.G.Y.to_numpy()).all()
    after, r = totals(s)
    assert r[REACTED] == pytest.approx(light["density"] * math.pi / 6 * 2e-4**3, rel=1e-12)
    assert np.all(np.abs(after - before)[:2] <= 1e-9 * np.array([r[REACTED], r[O2_USED]]))
    assert abs(after[2] - before[2]) <= 1e-6 * r[HEAT_RELEASED]


def poly_scene(E):
    return make_scene(
        materials={"pe": {"density": 717.0, "youngs_modulus": 1e7, "conductivity": 0.3, "heat_capacity": 2000.0}},
        particles=[{"name": "pe", "material": "pe", "diameter": {"value": 1e-3}, "positions": [[0, 0, 0]],
                    "temperature": 353.15}],
        heat={"initial_temperature": 353.15},
        reactions=[{"type": "polymerization", "group": "pe", "rate_constant": 1e-9, "monomer_pressure": 1e6,
                    "activation_energy": E, "reference_temperature": 353.15, "enthalpy": 3.34e6}],
        numerics={"dt": 1e-3, "force_dt": True},
    )


@pytest.mark.parametrize("E", [0.0, 1.0e5])
def test_polymerization_heats_as_the_lumped_ode(solver_for, E):
    """An isolated particle: c dT/dt = k p_M exp(-E/R (1/T - 1/T_ref)) dH (fine RK4 reference)."""
    s = solver_for(poly_scene(E))
    for _ in range(1000):
        s.step()
    a, E_R, T = 1e-3 * 3.34e6 / 2000.0, E / R_GAS, 353.15
    f = lambda T: a * math.exp(-E_R * (1 / T - 1 / 353.15))  # noqa: E731
    h = s.t / 4000
    for _ in range(4000):
        k1 = f(T); k2 = f(T + h / 2 * k1); k3 = f(T + h / 2 * k2); k4 = f(T + h * k3)  # noqa: E702
        T += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert T - 353.15 > 1.0
    assert s.state.T.to_numpy()[0] - 353.15 == pytest.approx(T - 353.15, rel=1e-3)
    assert s.state.rsum.to_numpy()[HEAT_RELEASED] == pytest.approx(
        (s.state.T.to_numpy()[0] - 353.15) * s.model.heat_capacity[0], rel=1e-9)


def test_growing_particle_gains_the_polymer_it_makes(solver_for):
    """With growth and E = 0 the mass grows as m0 (1 + k p_M dt)^n (exp(k p_M t) to O(dt)) at
    constant density, so d = d0 (m/m0)^(1/3); heat released = dH x polymer made, and the
    particles' heat content grows by the heat released plus the monomer's sensible heat
    (rsum[ENTHALPY_OUT] < 0), to rounding. At max_diameter the particle stops reacting."""
    raw = poly_scene(0.0)
    raw["reactions"][0].update(rate_constant=1e-6, growth=True, max_diameter=1.05e-3)  # k p_M = 1 /s
    s = solver_for(raw)
    m0, c = s.model.mass[0], 2000.0
    for _ in range(100):
        s.step()
    m, r = s.state.mass.to_numpy()[0], s.state.radius.to_numpy()[0]
    assert m == pytest.approx(m0 * (1 + 1e-3) ** 100, rel=1e-9)
    assert 2 * r == pytest.approx(1e-3 * (m / m0) ** (1 / 3), rel=1e-9)
    sums = s.state.rsum.to_numpy()
    assert sums[REACTED] == pytest.approx(m - m0, rel=1e-9)
    assert sums[HEAT_RELEASED] == pytest.approx(3.34e6 * (m - m0), rel=1e-9)
    heat = m * c * s.state.T.to_numpy()[0] - m0 * c * 353.15
    assert heat == pytest.approx(sums[HEAT_RELEASED] - sums[ENTHALPY_OUT], rel=1e-9)
    for _ in range(200):  # d0 e^(t/3) reaches 1.05 mm at t = 0.146 s
        s.step()
    assert 2 * s.state.radius.to_numpy()[0] == pytest.approx(1.05e-3, rel=2e-3)
    made = s.state.rsum.to_numpy()[REACTED]
    s.step()
    assert s.state.rsum.to_numpy()[REACTED] == made, "a particle at max_diameter no longer reacts"


def test_slowly_growing_particle_keeps_its_density(solver_for):
    """k p_M = 9e-3 /s: the mass grows by 9e-6 a step, just below where the radius follows the mass by
    the cube root's series (`kernels/reactions.py`) instead of pow; after 1000 steps d = d_0 (m/m_0)^(1/3)
    to the rounding of 1000 products (a wrong x^2 coefficient would be 1e-9 off)."""
    raw = poly_scene(0.0)
    raw["reactions"][0].update(rate_constant=9e-9, growth=True, max_diameter=1.05e-3)
    s = solver_for(raw)
    m0 = s.model.mass[0]
    for _ in range(1000):
        s.step()
    m, r = s.state.mass.to_numpy()[0], s.state.radius.to_numpy()[0]
    assert m == pytest.approx(m0 * (1 + 9e-6) ** 1000, rel=1e-12)
    assert 2 * r == pytest.approx(1e-3 * (m / m0) ** (1 / 3), rel=1e-12)


def test_growing_particles_find_each_other(solver_for):
    """Two fixed particles 0.3 d_0 apart, beyond the neighbour skin (0.1 d_max): growth alone
    must trigger the rebuilds that put them in each other's list before they touch."""
    raw = poly_scene(0.0)
    raw["particles"][0].update(positions=[[0, 0, 0], [1.3e-3, 0, 0]], fixed=True)
    raw["reactions"][0].update(rate_constant=1e-6, growth=True, max_diameter=1.5e-3)
    s = solver_for(raw)
    rebuilds = s.rebuilds
    touched_at = None
    while touched_at is None and s.t < 1.0:
        s.step()
        if s.state.ncontact.to_numpy()[0] > 0:
            touched_at = 2 * s.state.radius.to_numpy()[0]
    assert s.rebuilds > rebuilds
    assert touched_at == pytest.approx(1.3e-3, rel=2e-3), "they touch as soon as d reaches the distance"


K_AR, RHO_AR, MU_AR, CP_AR = 0.5, 0.054, 2.6e-4, 520.0
SIO2 = {"density": 2200.0, "youngs_modulus": 1e7, "conductivity": 1.4, "heat_capacity": 1000.0}
T_S, L_U = 2500.0, 1.25e7


def plasma_scene(positions, T_gas=8000.0, cp=CP_AR, size=0.002):
    return make_scene(
        domain={"min": [0, 0, 0], "max": [size, size, size], "walls": "none", "gravity": [0, 0, 0]},
        contact={"model": "none"},
        materials={"sio2": SIO2},
        particles=[{"name": "powder", "material": "sio2", "diameter": {"value": 1e-5}, "positions": positions,
                    "fixed": True, "temperature": T_S}],
        heat={"initial_temperature": T_gas, "gas_conductivity": K_AR},
        gas={"cell_size": size, "density": RHO_AR, "viscosity": MU_AR, "heat_capacity": cp, "coupling_interval": 1},
        reactions=[{"type": "sublimation", "group": "powder", "temperature": T_S, "latent_heat": L_U}],
        numerics={"dt": 1.25e-7},
    )


def test_single_particle_follows_the_d2_law(solver_for):
    """Nu = 2 in still gas held at 8000 K (a huge gas heat capacity): t = rho L d0^2 / (8 k dT)."""
    s = solver_for(plasma_scene([[0.001, 0.001, 0.001]], cp=CP_AR * 1e4))
    while s.state.active.to_numpy()[0] and s.steps < 5000:
        s.step()
    expected = 2200.0 * L_U * 1e-10 / (8 * K_AR * (8000.0 - T_S))
    t_sub = s.state.rt1.to_numpy()[0] - s.state.rt0.to_numpy()[0] + s.dt  # first seen after one step
    assert s.steps > 200, "the particle's life spans many steps"
    assert t_sub == pytest.approx(expected, rel=0.02)


def test_sublimating_cloud_cools_its_gas_by_the_heat_taken(solver_for):
    """20 particles in 8 mm^3 of 8 kK plasma (they need a quarter of its heat above T_s): the
    gas cools and loses exactly the heat the particles take (latent, sensible, and the vapour's
    enthalpy, including what particles hand back as they vanish), to 1e-9."""
    rng = np.random.default_rng(3)
    s = solver_for(plasma_scene(rng.uniform(0.0002, 0.0018, (20, 3)).tolist()))
    G, S = s.gas.G, s.state
    V = s.gas.gg.volume

    def gas_energy():
        return RHO_AR * CP_AR * V * (G.eps.to_numpy() * G.T.to_numpy()).sum() + G.Qs.to_numpy().sum() \
            - G.bsum.to_numpy()[0]

    def particle_energy():
        active = S.active.to_numpy().astype(bool)
        r = S.rsum.to_numpy()
        return (S.T.to_numpy() / S.inv_heat_cap.to_numpy())[active].sum() + r[LATENT] + r[ENTHALPY_OUT]

    g0, p0 = gas_energy(), particle_energy()
    T0 = G.T.to_numpy().mean()
    for _ in range(1500):
        s.step()
    taken = particle_energy() - p0
    assert G.T.to_numpy().mean() < T0 - 100.0, "a loaded plasma cools"
    assert S.rsum.to_numpy()[GONE] > 0, "some particles sublimated completely"
    assert g0 - gas_energy() == pytest.approx(taken, rel=1e-9)


@pytest.mark.parametrize("change, fragment", [
    (lambda r: r["reactions"][0].update(group="coal"), "reactions[0].group: no particle group named 'coal'"),
    (lambda r: r["gas"].pop("oxygen"), "add gas.oxygen"),
    (lambda r: r.pop("heat"), "needs a [heat] table"),
    (lambda r: r["contact"].update(model="none") if "contact" in r else r.update(contact={"model": "none"},
                                                                                   domain={**r["domain"], "walls": "auto"}),
     "set domain.walls = \"none\""),
])
def test_bad_reaction_input_is_named(change, fragment):
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    raw = char_scene([[0.004, 0.004, 0.004]])
    change(raw)
    with pytest.raises(SceneError) as err:
        build_model(validate(raw))
    assert fragment in str(err.value)


def test_too_long_step_for_sublimation_is_refused():
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    raw = plasma_scene([[0.001, 0.001, 0.001]])
    raw["numerics"]["dt"] = 1e-6
    with pytest.raises(SceneError) as err:
        build_model(validate(raw))
    assert "reactions[0]: a step of 1e-06 s sublimates up to 1.2 % of the smallest particle's mass" in str(err.value)
    assert "numerics.dt <= 8.3" in str(err.value)
