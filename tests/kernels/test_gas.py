"""Gas phase against Ergun, the bed weight, Wen-Yu, the single-sphere terminal velocity and
the lumped heating with Ranz-Marshall; conservation of gas mass, exchanged momentum and heat."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.scene.errors import SceneError

MU, RHO_G, D = 1.8e-5, 1.2, 0.001
SAND = {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.9, "friction": 0.3,
        "conductivity": 3.0, "heat_capacity": 800.0}


def ergun_gradient(eps, u, d=D):
    """Ergun (1952) pressure gradient [Pa/m] at superficial velocity u."""
    return 150 * (1 - eps) ** 2 * MU * u / (eps**3 * d * d) + 1.75 * (1 - eps) * RHO_G * u * u / (eps**3 * d)


def cd_schiller_naumann(re):
    return 24 / re * (1 + 0.15 * re**0.687) if re < 1000 else 0.44


def packed_column(u, **gas):
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.008, 0.008, 0.04], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": D}, "fixed": True,
                    "region": {"min": [0, 0, 0], "max": [0.008, 0.008, 0.024]}}],
        gas={"cell_size": 0.004, "inlet_velocity": u, "coupling_interval": 1, **gas},
        numerics={"dt": 1e-4, "force_dt": True},
    )


@pytest.mark.parametrize("u", [0.05, 0.3, 1.0])
def test_packed_bed_pressure_gradient_is_ergun(solver_for, u):
    """The drag law against Ergun in the uniform interior of a packed bed, over the cells' own averaging: the
    averaging length (12 d) would spread the loose layers at the floor and the bed top into these few cells
    (the default's packed bed: tests/kernels/test_gas_averaging.py)."""
    s = solver_for(packed_column(u, averaging_length="cells"))
    for _ in range(20):
        s.step()
    G = s.gas.G
    p = G.p.to_numpy().mean(axis=(0, 1))
    eps = G.eps.to_numpy().mean(axis=(0, 1))
    # cells 1..4 lie wholly inside the bed (bed top at 0.024 m = 6 cells)
    grad = (p[1] - p[4]) / (3 * 0.004)
    expected = ergun_gradient(eps[1:5].mean(), u) + RHO_G * 9.81
    assert np.ptp(eps[1:5]) < 0.01, "the bed interior is uniform"
    assert grad == pytest.approx(expected, rel=0.05)
    # continuity holds to the solver tolerance
    assert s.gas.divergence * 0.004 / u < 1e-6
    assert s.gas.residual < 1e-8


@pytest.mark.parametrize("drag, u", [("beetstra", 0.005), ("beetstra", 0.3), ("tang", 1.0)])
def test_packed_bed_with_beetstra_or_tang_drag_has_its_gradient_and_carman_kozenys_at_low_re(solver_for, drag, u):
    """drag = "beetstra" or "tang": the packed bed's gradient is n K U / eps^2 = 18 mu phi U F(phi, Re) / (eps d^2)
    within 5 % (as Ergun's above), F the published correlation (Tang's at Re 67, inside its fitted range).
    At Re ~ 0.3 Beetstra's correlation lies 1-2 % above Carman-Kozeny's 180 mu phi^2 U / (eps^3 d^2), its own
    low-Re term, so the bed is within 10 % of that (a drag off by a factor eps, the usual slip in this
    normalization, would be 2.5 times it)."""
    s = solver_for(packed_column(u, drag=drag, averaging_length="cells"))  # the interior uniform, as above
    for _ in range(20):
        s.step()
    p = s.gas.G.p.to_numpy().mean(axis=(0, 1))
    eps = float(s.gas.G.eps.to_numpy().mean(axis=(0, 1))[1:5].mean())
    grad = (p[1] - p[4]) / (3 * 0.004) - RHO_G * 9.81
    phi, re = 1 - eps, RHO_G * u * D / MU  # Re = eps rho w d / mu with w = u / eps
    f = beetstra_f(phi, re) if drag == "beetstra" else tang_f(phi, re)
    assert grad == pytest.approx(18 * MU * phi * u * f / (eps * D * D), rel=0.05)
    if u < 0.01:
        assert grad == pytest.approx(180 * MU * phi**2 * u / (eps**3 * D * D), rel=0.10)


def test_pressure_probes_read_the_layer_means_and_the_ergun_gradient(solver_for):
    """gas.pressure_probes: a probe on a layer's centre reads that layer's mean pressure, one between
    two centres their linear interpolation, and two probes in the packed bed differ by Ergun's
    gradient (plus the gas weight) over their distance; a height outside the domain is refused."""
    from tidem.gas.probes import probe_column

    u = 0.3
    s = solver_for(packed_column(u, pressure_probes=[0.006, 0.007, 0.018]))
    for _ in range(20):
        s.step()
    probes = s.gas.summary()
    p = s.gas.G.p.to_numpy().mean(axis=(0, 1))
    eps = s.gas.G.eps.to_numpy().mean(axis=(0, 1))
    assert list(probes).count(probe_column(0.006)) == 1 and probe_column(0.006) == "gas_pressure_z6mm_Pa"
    assert probes[probe_column(0.006)] == pytest.approx(p[1], rel=1e-12)
    assert probes[probe_column(0.007)] == pytest.approx(0.75 * p[1] + 0.25 * p[2], rel=1e-12)
    drop = probes[probe_column(0.006)] - probes[probe_column(0.018)]
    assert drop / 0.012 == pytest.approx(ergun_gradient(eps[1:5].mean(), u) + RHO_G * 9.81, rel=0.05)
    with pytest.raises(SceneError, match=r"gas.pressure_probes\[1\]: z = 0.05 m lies outside"):
        solver_for(packed_column(u, pressure_probes=[0.01, 0.05]))


def fluid_bed(inlet, t_ramp=0.0, voidage="layered"):
    """About 900 particles in a periodic slab; soft (2 MPa, overlaps up to 10 % allowed while
    the starting lattice collapses) and frictionless, so that the bed settles to a random
    packing near Wen-Yu's eps_mf and the test runs in seconds."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.016, 0.004, 0.06], "periodic": ["y"], "walls": "auto",
                "gravity": [0, 0, -9.81], "wall_friction": 0.0},
        materials={"sand": {**SAND, "youngs_modulus": 2e6, "friction": 0.0}},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": D},
                    "region": {"min": [0, 0, 0], "max": [0.016, 0.004, 0.02]}}],
        gas={"cell_size": 0.004, "inlet_velocity": inlet, "inlet_ramp": t_ramp, "coupling_interval": 10,
             "voidage": voidage},
        numerics={"max_overlap": 0.1},
    )


def wen_yu_umf(rho_p=2500.0, d=D):
    ar = d**3 * RHO_G * (rho_p - RHO_G) * 9.81 / MU**2
    return (math.sqrt(33.7**2 + 0.0408 * ar) - 33.7) * MU / (RHO_G * d)


def cd_di_felice(re):
    return (0.63 + 4.8 / math.sqrt(re)) ** 2


def beetstra_f(phi, re):
    """Beetstra, van der Hoef & Kuipers (2007) eq. 9, monodisperse: the drag over the Stokes drag at
    the superficial slip velocity."""
    eps = 1 - phi
    inertial = 0.413 * re / (24 * eps**2) * (1 / eps + 3 * eps * phi + 8.4 * re**-0.343) \
        / (1 + 10 ** (3 * phi) * re ** (-(1 + 4 * phi) / 2))
    return 10 * phi / eps**2 + eps**2 * (1 + 1.5 * math.sqrt(phi)) + inertial


def tang_f(phi, re):
    """Tang, Peters, Kuipers, Kriebitzsch & van der Hoef (2015), monodisperse static arrays: the drag over the
    Stokes drag at the superficial slip velocity."""
    eps = 1 - phi
    inertial = re * (0.11 * phi * (1 + phi) - 0.00456 / eps**4 + re**-0.343 * (0.169 * eps + 0.0644 / eps**4))
    return 10 * phi / eps**2 + eps**2 * (1 + 1.5 * math.sqrt(phi)) + inertial


def cd_beetstra(re):
    """One sphere (phi = 0): C_D = 24 F / Re."""
    return 24 * beetstra_f(0.0, re) / re


@pytest.mark.parametrize("drag, cd, vt_guess", [("gidaspow", cd_schiller_naumann, 2.24),
                                                ("di_felice", cd_di_felice, 2.08),
                                                ("beetstra", cd_beetstra, 2.17)])
def test_single_particle_falls_at_the_terminal_velocity(solver_for, drag, cd, vt_guess):
    d, rho_p = 3e-4, 2500.0
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 3.0], "walls": "none", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": d}, "positions": [[0.01, 0.01, 2.9]]}],
        gas={"cell_size": 0.02, "coupling_interval": 5, "drag": drag},
        numerics={"dt": 2e-4, "force_dt": True},
    )
    s = solver_for(raw)
    while s.t < 1.4:
        s.step()
    v = -s.state.v.to_numpy()[0, 2]
    # (rho_p - rho_g) V g = C_D(Re) (pi d^2 / 4) rho_g v^2 / 2, solved by bisection
    lo, hi = 0.01, 10.0
    for _ in range(100):
        vt = 0.5 * (lo + hi)
        drag_force = cd(RHO_G * vt * d / MU) * math.pi * d * d / 8 * RHO_G * vt * vt
        lo, hi = (vt, hi) if drag_force < (rho_p - RHO_G) * math.pi * d**3 / 6 * 9.81 else (lo, vt)
    assert vt == pytest.approx(vt_guess, abs=0.05), "the particle is in the intermediate regime"
    assert v == pytest.approx(vt, rel=0.02)


def nu_ranz_marshall(re, pr):
    return 2 + 0.6 * math.sqrt(re) * pr ** (1 / 3)


def nu_gunn_single(re, pr):
    """Gunn (1978) at voidage 1."""
    return 2 * (1 + 0.7 * re**0.2 * pr ** (1 / 3)) + 0.13 * re**0.7 * pr ** (1 / 3)


@pytest.mark.parametrize("model, nusselt", [("ranz_marshall", nu_ranz_marshall), ("gunn", nu_gunn_single)])
def test_fixed_particle_heats_as_lumped_solution(solver_for, model, nusselt):
    d, u, t_gas, t_p = 2e-3, 1.0, 400.0, 300.0
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.1], "walls": "none", "gravity": [0, 0, -9.81]},
        materials={"sand": {**SAND, "heat_capacity": 100.0}},  # thermal time 0.8 s
        particles=[{"name": "p", "material": "sand", "diameter": {"value": d}, "positions": [[0.01, 0.01, 0.05]],
                    "fixed": True, "temperature": t_p}],
        heat={"gas_conductivity": 0.026, "initial_temperature": t_gas},
        gas={"cell_size": 0.02, "inlet_velocity": u, "inlet_temperature": t_gas, "coupling_interval": 1,
             "heat_transfer": model},
        numerics={"dt": 1e-3, "force_dt": True},
    )
    s = solver_for(raw)
    for _ in range(3000):
        s.step()
    re = RHO_G * u * d / MU
    pr = 1005.0 * MU / 0.026
    h = nusselt(re, pr) * 0.026 / d
    m = 2500 * math.pi * d**3 / 6
    rate = h * math.pi * d * d / (m * 100.0)
    assert rate * s.t > 1.0, "the test covers most of the heating"
    expected = t_gas - (t_gas - t_p) * math.exp(-rate * s.t)
    assert s.state.T.to_numpy()[0] - t_p == pytest.approx(expected - t_p, rel=0.01)


@pytest.mark.parametrize("averaging_length, drag_averaging, voidage", [
    ("cells", "cells", "layered"), (None, "cells", "layered"), (None, "length", "layered"), (None, "length", "cell")])
def test_drag_on_the_gas_balances_the_drag_on_the_particles(solver_for, averaging_length, drag_averaging, voidage):
    """Over the cells' own averaging, with the voidage filtered to the default averaging length, 12 d
    (`kernels/gas_smoothing.py`; the drag on its cloud-in-cell weights), and with the drag spread over that length
    and the gas velocity read through the transposed filter (`kernels/exchange_filter.py`, eqs. (3)-(4))."""
    raw = fluid_bed(0.8, voidage=voidage)
    raw["gas"]["averaging_length"] = averaging_length
    raw["gas"]["drag_averaging"] = drag_averaging
    s = solver_for(raw)
    for _ in range(400):
        s.step()
    s.gas.step(s.t)
    S, G = s.state, s.gas.G
    on_particles = (S.gK.to_numpy()[:, None] * (S.gu.to_numpy() - S.v.to_numpy())).sum(axis=0)
    on_gas = np.array([(G.B[c].to_numpy() * G.u[c].to_numpy() - G.Bv[c].to_numpy()).sum() for c in range(3)])
    assert abs(on_particles[2]) > 1e-4, "the gas carries a good part of the bed"
    assert on_gas == pytest.approx(on_particles, rel=1e-9, abs=1e-12)


def test_closed_gas_and_particles_keep_their_heat(solver_for):
    raw = packed_column(0.0, coupling_interval=1)
    raw["heat"] = {"initial_temperature": 293.15}
    raw["gas"]["initial_temperature"] = 500.0
    s = solver_for(raw)
    G = s.gas

    def total():
        solid = float((s.model.heat_capacity * s.state.T.to_numpy()).sum())
        gas = RHO_G * 1005.0 * G.gg.volume * float((G.G.eps.to_numpy() * G.G.T.to_numpy()).sum())
        return solid + gas

    before = total()
    for _ in range(200):
        s.step()
    assert G.G.T.to_numpy().mean() < 450.0, "heat moved from gas to particles"
    assert total() == pytest.approx(before, rel=1e-9)


def test_gas_conduction_decays_a_sine_at_the_analytic_rate(solver_for):
    """Still air, periodic in x, T = 300 K + 10 K sin(2 pi x / L) over 16 cells of 16 mm: the
    mode decays as exp(-alpha k^2 t), alpha = k_g / (rho c) (the explicit scheme on 16 cells per
    wavelength is 0.5 % slower). One fixed 1 mm particle (the scene needs one) sits at a zero
    of the mode; its pull on the two cells around it costs under 0.1 %."""
    length, t0, amp, h = 0.256, 300.0, 10.0, 0.016
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [length, h, h], "periodic": ["x", "y"], "walls": "auto",
                "gravity": [0, 0, 0]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": D}, "fixed": True,
                    "positions": [[length / 2, h / 2, h / 2]], "temperature": t0}],
        heat={"initial_temperature": t0, "gas_conductivity": 0.026},
        gas={"cell_size": h, "coupling_interval": 1, "initial_temperature": t0},
        numerics={"dt": 0.05, "force_dt": True},
    )
    s = solver_for(raw)
    G = s.gas.G
    k = 2 * math.pi / length
    mode = np.sin(k * (np.arange(16) + 0.5) * h)[:, None, None]
    G.T.from_numpy(t0 + amp * mode)
    start = s.t
    for _ in range(600):
        s.step()
    analytic = math.exp(-0.026 / (RHO_G * 1005.0) * k * k * (s.t - start))
    left = float(((G.T.to_numpy() - t0) * mode).sum() / (mode * mode).sum()) / amp
    assert analytic < 0.7, "the test covers a good part of the decay"
    assert left == pytest.approx(analytic, rel=0.01)
    assert s.state.T.to_numpy()[0] == pytest.approx(t0, abs=1e-9)


def tube_in_still_gas(**gas):
    """A closed box of still air at 300 K around a 400 K tube of 24 mm (gas cells of 3 mm),
    one fixed particle in a corner."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.06, 0.012, 0.06], "periodic": ["y"], "walls": "auto",
                "gravity": [0, 0, 0]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": D}, "fixed": True,
                    "positions": [[0.004, 0.003, 0.004]], "temperature": 300.0}],
        tubes=[{"center": [0.03, 0.0, 0.03], "axis": "y", "diameter": 0.024, "temperature": 400.0}],
        heat={"initial_temperature": 300.0},
        gas={"cell_size": 0.003, "coupling_interval": 1, "initial_temperature": 300.0, **gas},
        numerics={"dt": 1e-3, "force_dt": True},
    )


@pytest.mark.parametrize("shape", ["cut", "cells"])
def test_tube_heats_still_gas_by_churchill_bernstein_and_the_gas_keeps_it(solver_for, shape):
    """Re = 0: Nu = 0.3, h = 0.3 k / D over the whole tube surface pi D L; the heat the tube
    gives equals the gas's (and particle's) heat gain, with the tube cut into the grid (the gas holding
    the part of each cut cell outside it) and as the staircase of cells."""
    s = solver_for(tube_in_still_gas(tube_shape=shape))
    G = s.gas
    assert G.walls

    def total():
        solid = float((s.model.heat_capacity * s.state.T.to_numpy()).sum())
        part = G.G.part.to_numpy() if shape == "cut" else 1.0  # the gas part of each cell
        return solid + RHO_G * 1005.0 * G.gg.volume * float((G.G.eps.to_numpy() * G.G.T.to_numpy() * part).sum())

    s.step()  # the tube's gas heat is counted from here on (heat.profile_start = 0)
    h = 0.3 * 0.026 / 0.024
    first = float(G.G.wall_rate.to_numpy()[0])
    assert first == pytest.approx(h * math.pi * 0.024 * 0.012 * 100.0, rel=2e-3), "h A (T_w - T) at the start"
    before = total()
    for _ in range(200):
        s.step()
    assert G.G.T.to_numpy().max() > 300.5
    gained = total() - before
    assert gained == pytest.approx(float(G.G.wall_energy.to_numpy()[0]), rel=1e-9)
    assert G.summary()["tubes0_gas_heat_W"] == pytest.approx(float(G.G.wall_rate.to_numpy()[0]))
    assert not gas_phase(tube_in_still_gas(tube_convection="none")).walls


def gas_phase(raw):
    """The gas phase of a scene alone: its fields and what it decided, no kernel compiled."""
    import taichi as ti

    from tidem.gas.phase import GasPhase
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.state import allocate

    model = build_model(validate(raw))
    return GasPhase(model, allocate(model), ti.f64)


@pytest.mark.parametrize("centre", [(0.025, 0.045), (0.05, 0.04), (0.05, 0.045), (0.052, 0.043)])
def test_a_tube_thinner_than_a_gas_cell_still_fills_one(centre):
    """A 6 mm tube on 10 mm cells holds no cell centre: it fills the one row of cells nearest
    its axis (on a cell edge or corner too) and keeps its whole surface pi D L for the gas
    convection."""
    from tidem.gas.geometry import solid_cells, tube_walls
    from tidem.kernels.gas_grid import GasGrid

    gg = GasGrid(lo=(0.0, 0.0, 0.0), cells=(10, 2, 10), h=(0.01, 0.01, 0.01), periodic=(False, True, False))
    tube = {"c": [centre[0], 0.0, centre[1]], "mask": [1.0, 0.0, 1.0], "r": 0.003, "T": 350.0}
    assert solid_cells(gg, [tube]).sum() == 2  # one cell across, two along the tube
    walls = tube_walls(gg, [tube])
    assert walls["wall_A"].sum() == pytest.approx(math.pi * 0.006 * 0.02, rel=1e-12)


@pytest.mark.parametrize("gas, fragment", [
    ({"cell_size": 0.0015}, "gas.cell_size: cells of"),
    ({"cell_size": 0.004, "nozzles": [{"x": [0.0, 0.02], "velocity": 1.0}]}, "gas.nozzles[0].x"),
    ({"cell_size": 0.004, "inlet_temperature": 400.0}, "gas temperatures need a [heat] table"),
    ({"cell_size": 0.004, "averaging_length": 0.008}, "gas.averaging_length: 0.008 m is no longer than"),
    ({"cell_size": 0.004, "averaging_length": -0.01}, "gas.averaging_length: must be > 0"),
    ({"cell_size": 0.004, "averaging_length": "cell"}, 'gas.averaging_length: expected a length in m or "cells"'),
])
def test_bad_gas_input_is_named(gas, fragment):
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    raw = packed_column(0.1)
    raw["gas"] = gas
    with pytest.raises(SceneError) as err:
        build_model(validate(raw))
    assert fragment in str(err.value)


def test_gpu_form_of_the_gas_follows_the_serial_form(solver_for, monkeypatch):
    """On a GPU the deposits of the coupling are atomic sums over particles in parallel, the grid's
    loops run in parallel and the pressure solve is the parallel CG in launches of 8 iterations, which
    may go past its tolerance (`kernels/ordered.py`, `kernels/gas_flow.py`); run here on the CPU, that
    form gives the serial form's bed and gas (this thin grid's pressure solved directly,
    `kernels/gas_band.py`) to rounding and the CG's tolerance (1e-8). A deposit lost to a race, or a
    CG stopped early, moves the bed by far more (two iterations: 1e-3)."""
    import tidem.kernels.gas_band
    import tidem.kernels.gas_coupling
    import tidem.kernels.gas_energy
    import tidem.kernels.gas_flow
    import tidem.kernels.gas_grid

    raw = fluid_bed(0.8)
    raw["heat"] = {"initial_temperature": 293.15}
    raw["gas"]["initial_temperature"] = 400.0
    serial = solver_for(raw)
    for module in (tidem.kernels.gas_band, tidem.kernels.gas_coupling, tidem.kernels.gas_energy,
                   tidem.kernels.gas_flow, tidem.kernels.gas_grid):
        monkeypatch.setattr(module, "in_order", lambda: False)
    parallel = solver_for(raw)
    assert not tidem.kernels.gas_flow.serial_solve(parallel.gas.solid.size) and parallel.gas.cg_batch == 8
    assert serial.gas.band > 0 and parallel.gas.band == 0
    for _ in range(300):
        serial.step()
        parallel.step()
    assert serial.gas.iterations == 0 and parallel.gas.iterations > 1
    assert np.abs(serial.state.v.to_numpy()).max() > 0.01, "the bed moves"
    for name in ("x", "v", "T"):
        a, b = getattr(serial.state, name).to_numpy(), getattr(parallel.state, name).to_numpy()
        assert np.abs(a - b).max() <= 1e-7 * np.abs(a).max(), name
    for name in ("p", "T"):
        a, b = getattr(serial.gas.G, name).to_numpy(), getattr(parallel.gas.G, name).to_numpy()
        assert np.abs(a - b).max() <= 1e-7 * np.abs(a).max(), "gas " + name


def tube_in_packed_bed(u=0.3, **gas):
    """An 8 mm tube at 400 K in a fixed bed of 1 mm grains at 300 K, air at u (4 mm cells)."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.024, 0.004, 0.04], "periodic": ["y"], "walls": "auto",
                "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": D}, "fixed": True,
                    "region": {"min": [0, 0, 0], "max": [0.024, 0.004, 0.03]}, "temperature": 300.0}],
        tubes=[{"center": [0.012, 0.0, 0.015], "axis": "y", "diameter": 0.008, "temperature": 400.0}],
        heat={"initial_temperature": 300.0},
        gas={"cell_size": 0.004, "inlet_velocity": u, "coupling_interval": 1, "initial_temperature": 300.0,
             **gas},
        numerics={"dt": 1e-4, "force_dt": True},
    )


@pytest.mark.parametrize("convection, u", [("martin_nilles", 0.3), ("martin_nilles", 1.0),
                                           ("churchill_bernstein", 0.3)])
def test_tube_to_gas_convection_in_a_packed_bed_is_the_correlation(solver_for, convection, u):
    """The heat a tube gives the gas of each cell around it equals the correlation at that cell's
    voidage and gas velocity: Martin & Nilles' packed-bed wall term in the cell's packed share
    phi = (1 - eps) / 0.6 (its superficial velocity eps |u| at most Wen-Yu's U_mf) and
    Churchill-Bernstein in the rest, or Churchill-Bernstein times eps."""
    from tidem.analytic.fluidized_bed_heat import (cylinder_cross_flow, packed_bed_wall_convection,
                                                   wen_yu_minimum_fluidization)
    from tidem.kernels.gas_energy import EPS_PACKED

    s = solver_for(tube_in_packed_bed(u, tube_convection=convection))
    s.step()
    G = s.gas
    cells = G.cell_fields()
    area, t_wall = G.G.wall_A.to_numpy(), G.G.wall_T.to_numpy()
    around = (area > 0) & (G.solid == 0)
    eps, temp = cells["voidage"][around], cells["temperature"][around]
    speed = np.linalg.norm(cells["velocity"][around], axis=-1)
    assert eps.max() < 0.7 and speed.min() > 0.1, "the cells around the tube hold grains and flowing gas"
    h_cb = cylinder_cross_flow(RHO_G * speed * 0.008 / MU, 1005.0 * MU / 0.026) * 0.026 / 0.008
    if convection == "martin_nilles":
        phi = np.minimum(1.0, (1.0 - eps) / (1.0 - EPS_PACKED))
        u_mf = wen_yu_minimum_fluidization(D, 2500.0, RHO_G, MU)
        assert ((eps * speed).min() < u_mf) and ((eps * speed).max() > u_mf) == (u > u_mf), "the cap acts above U_mf"
        h_pb = np.array([packed_bed_wall_convection(min(e * v, u_mf), D, RHO_G, MU, 0.026, 1005.0)
                         for e, v in zip(eps, speed)])
        h = phi * h_pb + (1.0 - phi) * h_cb
        assert (h > h_cb * eps).all(), "grains at the wall raise the gas convection"
    else:
        h = h_cb * eps
    expected = float((h * area[around] * (t_wall[around] - temp)).sum())
    assert float(G.G.wall_rate.to_numpy()[0]) == pytest.approx(expected, rel=1e-9)
