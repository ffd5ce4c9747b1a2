"""`Solver.advance(k)` runs each step's closing kick and the next step's kick-drift in one
kernel (`kernels/integrate.py`), with the contacts' partner pass reading the positions of the
force pass and the owners' touching stamps (`kernels/contact.py`). Neither may change a bit: a
partner pass that read a neighbour already moved on, or a compiler merging the two half-kicks,
shows at 1e-16 and more.
The merging needs Taichi's IR optimization, which the suite otherwise leaves off (conftest), so
these kernels are compiled with it, as a run compiles them."""

import numpy as np
import pytest
import taichi as ti

from tests.test_storage_order import shuffled_bed

FIELDS = ("x", "v", "w", "f", "tq", "T", "ft", "mr", "ncontact", "ovl")


def hot_and_cold_bed() -> dict:
    """The sheared, settling bed of test_storage_order with rolling friction, half of it hot:
    contacts hand over forces, rolling moments and heat."""
    raw = shuffled_bed(3)
    group = raw["particles"][0]
    x = group["positions"]
    half = len(x) // 2
    raw["materials"]["glass"].update(conductivity=1.0, heat_capacity=800.0)
    raw["particles"] = [dict(group, name="hot", positions=x[:half], temperature=400.0),
                        dict(group, name="cold", positions=x[half:], temperature=300.0)]
    raw["heat"] = {}
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
    assert single.state.ncontact.to_numpy().sum() > single.n, "the bed must be in contact"
    T = single.state.T.to_numpy()
    assert np.ptp(T[T < 399.0]) > 0.05, "heat must flow between the halves"
    for name in FIELDS:
        assert np.array_equal(getattr(single.state, name).to_numpy(), getattr(fused.state, name).to_numpy()), name


def test_steps_until_stops_at_the_first_output_or_window_end(solver_for):
    s = solver_for(hot_and_cold_bed())
    dt = s.dt
    assert s.steps_until(lambda t: t >= 7.5 * dt, 50, 1000) == 8
    assert s.steps_until(lambda t: False, 50, 1000) == 50
    assert s.steps_until(lambda t: False, 50, 20) == 20
    s.advance(45)
    assert s.steps_until(lambda t: False, 50, 1000) == 5
