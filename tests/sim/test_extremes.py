"""Stability at the extremes: every combination of extreme inputs either runs
stably (no NaN, overlaps within 5 % of the radius, energy that does not grow, temperatures
within the inputs' bounds) or is refused before the first step with a message naming the
limit and a stable value. And float64 runs are bit-identical when repeated."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.sim.model import build_model
from tidem.sim.solver import Solver


def cluster(d, youngs, restitution, friction, **extra):
    """27 spheres on a loose lattice falling onto the floor of a box 6 d wide."""
    g = (np.arange(3) - 1.0) * 1.3 * d
    pos = np.stack(np.meshgrid(g, g, g + 2.5 * d, indexing="ij"), -1).reshape(-1, 3)
    mat = {"density": 2500.0, "youngs_modulus": youngs, "poisson_ratio": 0.3, "restitution": restitution,
           "friction": friction}
    raw = make_scene(
        domain={"min": [-3 * d, -3 * d, 0.0], "max": [3 * d, 3 * d, 8 * d], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"steel": mat},
        particles=[{"name": "p", "material": "steel", "diameter": {"value": d}, "positions": pos.tolist(),
                    "velocities": np.tile([0.0, 0.0, -0.5], (27, 1)).tolist()}],
        numerics={"dt_fraction": 0.2, "check_interval": 10, "impact_velocity": 2.0},
    )
    for key, value in extra.items():
        raw.setdefault(key, {}).update(value)
    return raw


def sand_slab(**tables):
    """A 12 mm x 4 mm slab of 1 mm sand, 12 mm deep, periodic in y, for the gas extremes."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.012, 0.004, 0.04], "periodic": ["y"], "walls": "auto",
                "gravity": [0, 0, -9.81]},
        materials={"sand": {"density": 2500.0, "youngs_modulus": 1e7, "restitution": 0.5, "friction": 0.3}},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": 0.001},
                    "region": {"min": [0, 0, 0], "max": [0.012, 0.004, 0.012]}}],
        **tables)


def total_energy(s):
    e = s.energies()
    return e["kinetic_energy_J"] + e["rotational_energy_J"] + e["potential_energy_J"]


CORNERS = [(d, E, e, mu) for d in (1e-5, 0.02) for E in (1e5, 2e11) for e, mu in ((0.01, 1.0), (1.0, 0.0))]


@pytest.mark.parametrize("d, youngs, restitution, friction", CORNERS)
def test_contact_extremes_run_stably_or_are_refused(solver_for, d, youngs, restitution, friction):
    raw = cluster(d, youngs, restitution, friction)
    try:
        s = solver_for(raw)
    except SceneError as err:  # too soft for the stated impact speed: refused with a stiffness that works
        msg = str(err)
        assert "overlaps particles by" in msg and "use youngs_modulus >= " in msg
        need = max(float(part.split(",")[0]) for part in msg.split("use youngs_modulus >= ")[1:])
        raw["materials"]["steel"]["youngs_modulus"] = need * 1.01
        s = solver_for(raw)
    e0 = total_energy(s)
    for _ in range(400):
        s.step()  # RunError (NaN, overlap > 5 %) would fail the test
    x = s.state.x.to_numpy()
    assert np.isfinite(x).all()
    assert s.state.ovl.to_numpy().max() <= 0.05
    assert total_energy(s) <= e0 * (1 + 1e-6) + 1e-300, "energy must not grow with e <= 1"


@pytest.mark.parametrize("d, youngs", [(1e-5, 2e11), (0.02, 1e9)])
def test_time_step_past_the_contact_limit_is_refused_with_a_stable_value(d, youngs):
    raw = cluster(d, youngs, 0.5, 0.5)
    limit = build_model(validate(raw)).scales.limit
    raw["numerics"]["dt"] = 1.5 * limit
    with pytest.raises(SceneError) as err:
        build_model(validate(raw))
    msg = str(err.value)
    assert "above the stability limit" in msg and "use dt <= " in msg
    stable = float(msg.split("use dt <= ")[1].split(",")[0])
    assert stable == pytest.approx(limit, rel=1e-2)
    raw["numerics"]["dt"] = 0.95 * stable
    assert build_model(validate(raw)).dt == 0.95 * stable


@pytest.mark.parametrize("t_hot, conductivity", [(10_000.0, 400.0), (10_000.0, 0.1)])
def test_hot_contacts_stay_within_the_input_temperatures(solver_for, t_hot, conductivity):
    raw = cluster(0.002, 2e8, 0.5, 0.5)
    raw["materials"]["steel"].update(conductivity=conductivity, heat_capacity=10.0)
    raw["heat"] = {"initial_temperature": 300.0}
    raw["particles"][0]["temperature"] = 300.0
    raw["particles"].append({**raw["particles"][0], "name": "hot", "temperature": t_hot,
                             "positions": [[0.0, 0.0, 0.0011]], "velocities": [[0.0, 0.0, 0.0]]})
    raw["particles"][0]["positions"] = [[x, y, z + 0.004] for x, y, z in raw["particles"][0]["positions"]]
    try:
        s = solver_for(raw)
    except SceneError as err:  # refused: the message names the conduction limit
        assert "explicit conduction limit" in str(err)
        return
    for _ in range(800):
        s.step()
    T = s.state.T.to_numpy()
    assert np.isfinite(T).all() and T.min() >= 300.0 - 1e-9 and T.max() <= t_hot + 1e-9


def test_thermal_limit_refuses_then_names_a_stable_setting():
    raw = cluster(0.002, 2e8, 0.5, 0.5)
    raw["materials"]["steel"].update(conductivity=400.0, heat_capacity=1e-4)
    raw["heat"] = {}
    with pytest.raises(SceneError, match="explicit conduction limit"):
        build_model(validate(raw))


@pytest.mark.parametrize("rho_gas", [0.02, 20.0])
def test_gas_density_extremes(solver_for, rho_gas):
    raw = sand_slab(gas={"cell_size": 0.004, "density": rho_gas, "inlet_velocity": 0.6, "coupling_interval": 10},
        numerics={"max_overlap": 0.1},
    )
    s = solver_for(raw)
    for _ in range(600):
        s.step()
    assert np.isfinite(s.state.v.to_numpy()).all() and np.isfinite(s.gas.G.p.to_numpy()).all()
    assert s.gas.residual < 1e-7


def test_a_forced_step_past_the_drag_relaxation_time_is_refused_with_a_stable_step():
    """force_dt lifts the contact limit only: a 10 um dust at a forced 1e-4 s step would
    overshoot its drag relaxation (about 2e-5 s in the Ergun range) and is still refused."""
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.001, 0.001, 0.004], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": {"density": 2500.0, "youngs_modulus": 1e5, "restitution": 0.5, "friction": 0.3}},
        particles=[{"name": "dust", "material": "sand", "diameter": {"value": 1e-5},
                    "region": {"min": [0, 0, 0], "max": [0.001, 0.001, 0.0005]}}],
        gas={"cell_size": 0.0005, "inlet_velocity": 0.01},
        numerics={"dt": 1e-4, "force_dt": True},
    )
    with pytest.raises(SceneError) as err:
        build_model(validate(raw))
    msg = str(err.value)
    assert "drag relaxation time" in msg and "use numerics.dt <=" in msg
    stable = float(msg.split("use numerics.dt <= ")[1].split()[0])
    assert 1e-6 < stable < 1e-4
    raw["numerics"]["dt"] = stable
    assert build_model(validate(raw)).dt == stable


def test_float64_runs_are_bit_identical():
    raw = cluster(0.002, 2e8, 0.5, 0.5, numerics={"check_interval": 50})
    finals = []
    for _ in range(2):
        s = Solver(build_model(validate(raw)))
        for _ in range(500):
            s.step()
        finals.append((s.state.x.to_numpy().copy(), s.state.v.to_numpy().copy(), s.state.w.to_numpy().copy()))
        s.release()
    for a, b in zip(*finals):
        assert np.array_equal(a, b)


def test_float64_gas_runs_are_bit_identical():
    """Fluidized particles and gas: the deposits onto the gas grid are summed in particle
    order, so two runs agree to the bit on any thread count."""
    raw = sand_slab(gas={"cell_size": 0.004, "inlet_velocity": 0.9, "coupling_interval": 5},
        numerics={"max_overlap": 0.1},
    )
    finals = []
    for _ in range(2):
        s = Solver(build_model(validate(raw)))
        for _ in range(300):
            s.step()
        finals.append((s.state.x.to_numpy().copy(), s.gas.G.p.to_numpy().copy()))
        s.release()
    for a, b in zip(*finals):
        assert np.array_equal(a, b)


def test_the_health_check_names_the_first_bad_particle_and_the_worst_overlap(solver_for):
    """The health check's reductions run on the device (`kernels/diagnostics.py`): a NaN position is
    reported for the first active particle that has one (by scene index), an inactive one is not;
    an overlap above numerics.max_overlap names the particle with the largest, and its ratio."""
    from tidem.sim.solver import RunError

    s = solver_for(cluster(0.002, 2e8, 0.5, 0.5))
    S = s.state
    s.check()  # a healthy start
    ident = S.ident.to_numpy()
    x = S.x.to_numpy()
    active = S.active.to_numpy()
    x[[1, 2]] = np.nan
    active[1] = 0
    S.x.from_numpy(x)
    S.active.from_numpy(active)
    with pytest.raises(RunError, match=f"particle {ident[2]} has a non-finite position"):
        s.check()
    assert s.sample_tallies()["worst_at"][0] == s.health()[0] < s.n  # a time-series sample's pass finds it too
    x[[1, 2]] = 0.01
    S.x.from_numpy(x)
    ovl = np.zeros_like(S.ovl.to_numpy())
    ovl[[0, 3]] = [0.02, 0.2]
    S.ovl.from_numpy(ovl)
    limit = s.model.scene.numerics.max_overlap
    assert 0.02 < limit < 0.2
    with pytest.raises(RunError, match=f"particle {ident[3]} overlaps a neighbour or wall by 20.0 %"):
        s.check()
    assert s.health() == (s.n, 3, pytest.approx(0.2))
    tallies = s.sample_tallies()  # a time-series sample's reductions: the same largest overlap and energies
    assert s.largest_overlap(tallies) == s.health()[2] and tallies["worst_at"][0] == s.n
    assert s.energies(tallies) == s.energies()
