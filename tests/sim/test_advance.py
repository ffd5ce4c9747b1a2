"""`Solver.advance(k)` runs each step's closing kick and the next step's kick-drift in one
kernel (`kernels/integrate.py`), each slab kicked in the contacts' second pass as soon as its sums
are complete, while other slabs' pairs are still evaluated (`kernels/contact.py`). Neither may
change a bit: a pair that read a neighbour already moved on, or a compiler merging the two
half-kicks, shows at 1e-16 and more. The atomic sums that a GPU takes give the same trajectories to
rounding.
The merging needs Taichi's IR optimization, which the suite otherwise leaves off (conftest), so
these kernels are compiled with it, as a run compiles them."""

import numpy as np
import pytest
import taichi as ti

from tests.particles.test_storage_order import shuffled_bed
from tidem.kernels.contact import BLOCKS, block_count
from tidem.kernels.geometry import slab_layout

FIELDS = ("x", "v", "w", "f", "tq", "T", "ft", "mr", "ncontact", "ovl")


def hot_and_cold_bed() -> dict:
    """The sheared, settling bed of test_storage_order with rolling friction, half of it hot:
    contacts add forces, rolling moments and heat to both particles."""
    raw = shuffled_bed(3)
    group = raw["particles"][0]
    x = group["positions"]
    half = len(x) // 2
    raw["materials"]["glass"].update(conductivity=1.0, heat_capacity=800.0)
    raw["particles"] = [dict(group, name="hot", positions=x[:half], temperature=400.0),
                        dict(group, name="cold", positions=x[half:], temperature=300.0)]
    raw["heat"] = {"fluid_layer": 0.2}
    raw["domain"]["max"][2] = 0.042  # cells 2.3 mm wide: 18 slabs along z (10 cells across), in blocks of two and three
    return raw


@pytest.fixture
def optimized():
    cfg = ti.lang.impl.current_cfg()
    before = cfg.advanced_optimization
    cfg.advanced_optimization = True
    yield
    cfg.advanced_optimization = before


def sheared(solver):
    S = solver.state
    shear = np.where(np.arange(solver.n)[:, None] % 2 == 0, 1.0, -1.0) * np.array([0.05, 0.02, 0.0])
    S.v.from_numpy(shear[S.ident.to_numpy()])
    return solver


def test_advance_gives_the_bits_of_single_steps(solver_for, optimized):
    raw = hot_and_cold_bed()
    single, fused = sheared(solver_for(raw)), sheared(solver_for(raw))
    single.split_passes = True  # forces and kick as kernels of their own; `fused` takes them in one launch
    for _ in range(200):
        single.step()
    for k in (1, 49, 50, 100):
        fused.advance(k)
    assert fused.steps == single.steps == 200 and fused.t == single.t
    assert single.rebuilds >= 3, "the window must hold neighbour rebuilds (and storage sorts)"
    assert max(block_sizes(slab_layout(single.model.grid)[1])) >= 3, "slabs kicked in the first pass, too"
    assert single.state.ncontact.to_numpy().sum() > single.n, "the bed must be in contact"
    T = single.state.T.to_numpy()
    assert np.ptp(T[T < 399.0]) > 0.05, "heat must flow between the halves"
    for name in FIELDS:
        assert np.array_equal(getattr(single.state, name).to_numpy(), getattr(fused.state, name).to_numpy()), name


def block_sizes(n_slabs: int) -> list[int]:
    blocks = block_count(n_slabs)
    return [(b + 1) * n_slabs // blocks - b * n_slabs // blocks for b in range(blocks)]


def test_blocks_are_even_in_number_and_two_slabs_or_more():
    """Two threads take as many blocks; a block of one slab would be swept in the second pass
    beside the slab before it, both adding to its particles."""
    assert [block_count(n) for n in (1, 2, 3)] == [1, 1, 1]
    for n in range(4, 300, 2):
        sizes = block_sizes(n)
        assert len(sizes) % 2 == 0 and len(sizes) <= BLOCKS and min(sizes) >= 2 and sum(sizes) == n, n
    assert len(block_sizes(90)) == BLOCKS


def test_steps_until_stops_at_the_first_output_or_window_end(solver_for):
    s = solver_for(hot_and_cold_bed())
    dt = s.dt
    assert s.steps_until(lambda t: t >= 7.5 * dt, 50, 1000) == 8
    assert s.steps_until(lambda t: False, 50, 1000) == 50
    assert s.steps_until(lambda t: False, 50, 20) == 20
    s.advance(45)
    assert s.steps_until(lambda t: False, 50, 1000) == 5


def test_atomic_sums_follow_the_slab_sums(solver_for, monkeypatch):
    """The GPU's form of the contact passes (every particle a thread, atomic sums; run here on the CPU)
    against the slabs: the same bed to rounding (which grows about 10x per 50 steps in this sheared
    bed, `tests/particles/test_storage_order.py`); a pair evaluated twice or missed moves particles by 1e-6 m."""
    from functools import partial

    import tidem.sim.solver
    from tidem.kernels.contact import make_force_kernel

    raw = hot_and_cold_bed()
    slabs = sheared(solver_for(raw))
    monkeypatch.setattr(tidem.sim.solver, "make_force_kernel", partial(make_force_kernel, atomic=True))
    atomic = sheared(solver_for(raw))
    for _ in range(100):
        slabs.step()
        atomic.step()
    assert slabs.rebuilds >= 2 and slabs.state.ncontact.to_numpy().sum() > slabs.n
    assert np.array_equal(slabs.state.ident.to_numpy(), atomic.state.ident.to_numpy()), "the same storage order"
    for name in ("x", "v", "w", "T"):
        a, b = getattr(slabs.state, name).to_numpy(), getattr(atomic.state, name).to_numpy()
        assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max(), name


def test_one_size_and_material_as_constants_follow_the_loaded_values(solver_for, monkeypatch):
    """Where all particles have one radius and mass and one material, the contact passes take them and
    the pair parameters as constants of the kernel (`Model.uniform_particles`, `Model.one_material`)
    instead of loading them: the same bed as with the loads, to rounding; the bed with a second size
    or material loads them."""
    from tidem.scene.load import validate
    from tidem.sim.model import Model, build_model

    raw = hot_and_cold_bed()
    constants = sheared(solver_for(raw))
    assert constants.model.uniform_particles() is not None
    assert constants.model.one_material() is not None
    monkeypatch.setattr(Model, "uniform_particles", lambda model: None)
    monkeypatch.setattr(Model, "one_material", lambda model: None)
    loads = sheared(solver_for(raw))
    for _ in range(100):
        constants.step()
        loads.step()
    assert constants.rebuilds >= 2 and constants.state.ncontact.to_numpy().sum() > constants.n
    for name in ("x", "v", "w", "T"):
        a, b = getattr(constants.state, name).to_numpy(), getattr(loads.state, name).to_numpy()
        assert np.abs(a - b).max() <= 1e-10 * np.abs(a).max(), name
    monkeypatch.undo()
    raw["particles"][1]["diameter"] = {"distribution": "mono", "value": 0.00199}
    two_sizes = build_model(validate(raw))
    assert two_sizes.uniform_particles() is None and two_sizes.one_material() is not None
    raw["materials"]["steel"] = dict(raw["materials"]["glass"], density=7800.0)
    raw["particles"][0]["material"] = "steel"
    assert build_model(validate(raw)).one_material() is None


@pytest.mark.parametrize("fluid_layer, every", [(0.0, 1), (0.2, 4)])
def test_skipping_quiet_partners_changes_no_bit(solver_for, monkeypatch, fluid_layer, every):
    """The contact passes skip the groups of a particle's partners that did not touch it at the neighbour
    build while twice the largest displacement since then is below a group's smallest gap
    (`kernels/pair_contact.py`; with the gas lens only between conduction evaluations, every `every`
    steps here). Skipped or
    evaluated, such a pair adds nothing, and the build zeroed its history: the sheared bed, in which
    pairs close and open between builds, follows the run that evaluates every pair bit for bit."""
    import tidem.sim.solver

    raw = hot_and_cold_bed()
    raw["heat"] = {"fluid_layer": fluid_layer, "conduction_interval": every}
    quiet = sheared(solver_for(raw))
    margin = tidem.sim.solver.quiet_margin(quiet.model)
    monkeypatch.setattr(tidem.sim.solver, "quiet_margin", lambda model: 0.0)  # every listed pair evaluated
    every_pair = sheared(solver_for(raw))
    skipped = 0
    for _ in range(200):
        quiet.step()
        every_pair.step()
        S = quiet.state  # the next pass's reach, about (a particle wrapped around the domain overstates it)
        moved = np.linalg.norm(S.x.to_numpy() - S.x_build.to_numpy(), axis=1).max()
        reach = 2.0 * moved + margin
        count, within = S.nbr_n.to_numpy(), S.nbr_touch.to_numpy()
        ends = np.column_stack([S.nbr_end.to_numpy(), count])
        for g, gap in enumerate(S.nbr_gap.to_numpy().T):  # up to the last quiet group within reach
            within = np.where(gap <= reach, ends[:, g], within)
        skipped += int((count - within).sum())
    assert quiet.rebuilds >= 3 and quiet.state.ncontact.to_numpy().sum() > quiet.n
    assert skipped > 5 * quiet.n, "quiet partners skipped thousands of times"
    for name in FIELDS:
        assert np.array_equal(getattr(quiet.state, name).to_numpy(), getattr(every_pair.state, name).to_numpy()), name
    quiet.rebuild()  # every particle at its build position: the next pass reaches only its rounding margin
    assert quiet.state.max_disp[None] == 0.0


def test_a_partner_beyond_half_the_skin_is_reached_before_the_next_build(solver_for, monkeypatch):
    """Two grains 0.7 skin apart, closing head on: each has moved 0.35 skin when they touch, less than
    the half skin that calls a neighbour build, so their contact comes from the row's second quiet
    group (gaps between half the skin and the skin, `quiet_bounds`), which the pass reaches once twice
    the largest displacement passes its gap: the grains bounce, bit for bit as when every listed pair
    is evaluated."""
    import tidem.sim.solver
    from tests.conftest import make_scene

    raw = make_scene(particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 0.01},
                                 "positions": [[-0.00605, 0.0, 0.0], [0.00605, 0.0, 0.0]]}],
                     numerics={"skin": 0.3})

    def closing(solver):
        x = solver.state.x.to_numpy()
        solver.state.v.from_numpy(np.outer(-np.sign(x[:, 0]), [0.5, 0.0, 0.0]))
        return solver

    quiet = closing(solver_for(raw))
    monkeypatch.setattr(tidem.sim.solver, "quiet_margin", lambda model: 0.0)  # every listed pair evaluated
    every_pair = closing(solver_for(raw))
    S = quiet.state
    owner = int(np.argmax(S.nbr_n.to_numpy()))
    assert S.nbr_n[owner] == 1 and S.nbr_touch[owner] == 0 and S.nbr_end[owner, 0] == 0, "the second group"
    assert S.nbr_gap[owner, 1] == pytest.approx(0.0021, rel=1e-6)
    builds = quiet.rebuilds
    touched = False
    for _ in range(5000):
        quiet.step()
        every_pair.step()
        x = S.x.to_numpy()
        if not touched and abs(x[1, 0] - x[0, 0]) < 0.01:
            touched = True
            assert quiet.rebuilds == builds, "touching before a build: from the second group"
        if touched and np.all(S.v.to_numpy()[:, 0] * np.sign(x[:, 0]) > 0.4):
            break
    assert touched and np.all(S.v.to_numpy()[:, 0] * np.sign(S.x.to_numpy()[:, 0]) > 0.4), "the grains bounce"
    for name in ("x", "v", "f", "ft"):
        assert np.array_equal(getattr(S, name).to_numpy(), getattr(every_pair.state, name).to_numpy()), name
