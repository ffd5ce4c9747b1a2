"""Re-sorting particle storage into cell order (`tidem.particles.storage_order`) relabels particles and
changes nothing else: the same bed run with and without sorting follows the same trajectories
(to rounding, since sums run in another order), the storage ends in cell order, the Verlet rows
stay sorted with each pair in one row, and outputs still name particles by their scene index."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.kernels.storage_sort import make_storage_permuter
from tidem.particles.storage_order import SCRATCH, SORT_MIN_PARTICLES, new_order, permute_storage, scene_order

N_SIDE = (12, 10, 10)  # 1200 spheres, above SORT_MIN_PARTICLES


def shuffled_bed(seed: int) -> dict:
    """A frictional bed of 2 mm spheres, stored in random order, settling onto a floor with a
    shear of its initial velocities, so that contacts build tangential history as it moves."""
    rng = np.random.default_rng(seed)
    d = 0.002
    grid = np.stack(np.meshgrid(*[np.arange(k) for k in N_SIDE], indexing="ij"), axis=-1).reshape(-1, 3)
    x = (grid + 0.5) * d * 1.001 + rng.uniform(-2e-5, 2e-5, grid.shape)
    x = x[rng.permutation(len(x))]
    lo, hi = [0.0, 0.0, 0.0], [N_SIDE[0] * d * 1.001, N_SIDE[1] * d * 1.001, 0.04]
    return make_scene(
        domain={"min": lo, "max": hi, "periodic": ["x", "y"], "walls": ["z-"], "gravity": [0.0, 0.0, -9.81]},
        materials={"glass": {"density": 2500.0, "youngs_modulus": 5e6, "poisson_ratio": 0.3, "restitution": 0.5,
                             "friction": 0.5, "rolling_friction": 0.05}},
        particles=[{"name": "bed", "material": "glass", "positions": x.tolist(),
                    "diameter": {"distribution": "mono", "value": d}}],
        numerics={"skin": 0.05, "sort_interval": 1},
    )


def run(solver_for, raw, sort_interval, steps):
    raw = dict(raw, numerics=dict(raw["numerics"], sort_interval=sort_interval))
    s = solver_for(raw)
    S = s.state
    shear = np.where(np.arange(s.n)[:, None] % 2 == 0, 1.0, -1.0) * np.array([0.05, 0.02, 0.0])  # by scene index
    S.v.from_numpy(shear[S.ident.to_numpy()])
    for _ in range(steps):
        s.step()
    return s


def assert_same_trajectories(P, Q, tol):
    """Positions, velocities and spins of Q (in any storage order) equal P's (scene order) to tol."""
    for name in ("x", "v", "w"):
        a, b = getattr(P, name).to_numpy(), scene_order(Q, getattr(Q, name).to_numpy())
        assert np.abs(a - b).max() <= tol * np.abs(a).max(), name


def test_a_shuffled_storage_mid_run_follows_the_same_trajectories(solver_for):
    """Relabel every particle at random while contacts carry history (the hardest case of a sort):
    a lost spring, a partner renumbered wrongly or a row left unsorted moves particles by 1e-6 m
    and more; a different summation order only by rounding."""
    raw = shuffled_bed(3)
    assert len(raw["particles"][0]["positions"]) >= SORT_MIN_PARTICLES
    plain = run(solver_for, raw, 0, 150)
    shuffled = run(solver_for, raw, 0, 150)
    assert (plain.state.ft.to_numpy() ** 2).sum() > 0, "contacts must hold tangential history"
    names = [name for name in shuffled.state.particle_fields if name not in SCRATCH]
    permute = make_storage_permuter(shuffled.state, names)
    permute_storage(shuffled.state, permute, np.random.default_rng(1).permutation(shuffled.n), shuffled.n)
    shuffled.rebuild()
    for _ in range(150):
        plain.step()
        shuffled.step()
    # rounding differences of the sums grow in this sheared bed, about 10x per 50 steps: 1e-16 after 5 steps,
    # 1e-13 after 50, 1e-12 (spins) after 150; an error of the sort is 1e-6 m and more
    assert_same_trajectories(plain.state, shuffled.state, 1e-10)


def test_sorted_and_unsorted_runs_follow_the_same_trajectories(solver_for):
    raw = shuffled_bed(3)
    plain = run(solver_for, raw, 0, 200)
    sorted_ = run(solver_for, raw, 1, 200)
    assert plain.rebuilds >= 3, "the bed must move enough to rebuild several times"
    assert not np.array_equal(sorted_.state.ident.to_numpy(), np.arange(sorted_.n)), "the bed must be re-sorted"
    assert_same_trajectories(plain.state, sorted_.state, 1e-9)
    assert sorted_.state.ncontact.to_numpy().sum() == plain.state.ncontact.to_numpy().sum()


def test_after_a_sort_storage_is_in_cell_order_and_rows_are_consistent(solver_for):
    s = run(solver_for, shuffled_bed(5), 1, 1)
    S = s.state
    ident = S.ident.to_numpy()
    assert sorted(ident) == list(range(s.n))
    order = new_order(S.x_build.to_numpy(), S.active.to_numpy().astype(bool), s.model.grid.lo,
                      np.array(s.model.grid.cell_size))
    assert np.array_equal(order, np.arange(s.n)), "positions at the last build are in cell order"
    nbr, cnt = S.nbr.to_numpy(), S.nbr_n.to_numpy()
    pairs = set()
    for i in range(s.n):
        row = nbr[i, :cnt[i]]
        assert len(np.unique(row)) == len(row) and i not in row, "each partner once, never the particle itself"
        pairs |= {(min(i, j), max(i, j)) for j in row}
    assert len(pairs) == cnt[:s.n].sum(), "each pair in one row only"


def test_the_device_sort_of_a_gpu_permutes_fields_and_partners_as_the_host_sort(solver_for):
    """A GPU sorts on the device (`kernels/storage_sort.py`), run here on the CPU: a shuffled bed with
    tangential history ends in cell order, every field moved with its particle, each row naming
    the same partners (by scene index) with its history, unused slots -1; the bed then follows the
    host-sorted run's trajectories to rounding. A partner left unrenumbered, or a row moved
    without its history, moves the bed by 1e-6 m and more."""
    from tidem.particles.placement import spatial_key

    raw = shuffled_bed(3)
    host, device = run(solver_for, raw, 0, 150), run(solver_for, raw, 0, 150)
    S = device.state
    names = [name for name in S.particle_fields if name not in SCRATCH]
    before = {name: getattr(S, name).to_numpy() for name in names}
    device._cell_order(device.n)
    order = S.sorted_idx.to_numpy()[:device.n]
    assert sorted(order) == list(range(device.n)) and not np.array_equal(order, np.arange(device.n))
    make_storage_permuter(S, names)(device.n)
    after = {name: getattr(S, name).to_numpy() for name in names}
    for name in names:
        if name != "nbr":
            assert np.array_equal(after[name], before[name][order]), name
    key = spatial_key(after["x"], device.model.grid.lo, np.array(device.model.grid.cell_size))
    assert (np.diff(key) >= 0).all(), "cell order"
    nbr_b, nbr_a, n_b, n_a = before["nbr"], after["nbr"], before["nbr_n"], after["nbr_n"]
    for k, old in enumerate(order):
        assert list(after["ident"][nbr_a[k, :n_a[k]]]) == list(before["ident"][nbr_b[old, :n_b[old]]])
        assert (nbr_a[k, n_a[k]:] == -1).all()
    assert (after["ft"] ** 2).sum() > 0
    device.rebuild()
    for _ in range(150):
        host.step()
        device.step()
    assert_same_trajectories(host.state, device.state, 1e-10)


def test_scene_order_inverts_the_storage_permutation(solver_for):
    s = run(solver_for, shuffled_bed(7), 1, 1)
    S = s.state
    radius_scene = scene_order(S, S.ident.to_numpy())
    assert np.array_equal(radius_scene, np.arange(s.n))


@pytest.mark.parametrize("interval", [-1, 1.5])
def test_sort_interval_must_be_a_non_negative_integer(interval):
    from tidem.scene.errors import SceneError
    from tidem.scene.load import validate

    with pytest.raises(SceneError, match="numerics.sort_interval"):
        validate(make_scene(numerics={"sort_interval": interval}))
