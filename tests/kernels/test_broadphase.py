"""Broad phase against brute force (periodic and walled, polydisperse): each pair listed once, in the
row of its owner by the slab rule; the slab lists; contact history carried across neighbour rebuilds,
also to a pair's new owner."""

import numpy as np
import pytest

from tests.conftest import make_scene
from tidem.kernels.geometry import slab_axis_for, slab_layout
from tidem.sim.kernel_settings import quiet_bounds


def brute_force_pairs(x, r, skin, lengths, periodic):
    d = x[None, :, :] - x[:, None, :]
    for a in range(3):
        if periodic[a]:
            d[..., a] -= lengths[a] * np.round(d[..., a] / lengths[a])
    dist = np.linalg.norm(d, axis=2)
    reach = r[:, None] + r[None, :] + skin
    close = dist < reach
    np.fill_diagonal(close, False)
    return {(i, j) for i, j in zip(*np.nonzero(close))}


def random_spheres(rng, n, lo, hi, d_max):
    """n non-overlapping centres (for spheres up to d_max) by rejection, no periodic wrap."""
    pts = np.empty((n, 3))
    k = 0
    while k < n:
        p = rng.uniform(lo, hi)
        if k == 0 or np.linalg.norm(pts[:k] - p, axis=1).min() > d_max:
            pts[k] = p
            k += 1
    return pts


def listed_pairs(S, n):
    """The rows' (owner, partner) entries."""
    nbr = S.nbr.to_numpy()
    cnt = S.nbr_n.to_numpy()
    return {(i, int(nbr[i, k])) for i in range(n) for k in range(cnt[i])}


def unordered(pairs):
    return {(min(i, j), max(i, j)) for i, j in pairs}


def touching_first(solver, n, lengths, periodic):
    """Assert that each row lists the partners that touch first, then the others in their groups by gap
    (`quiet_bounds`), each group by partner index; that nbr_touch counts those that touch, nbr_end
    holds where each quiet group but the last ends and nbr_gap each group's smallest gap (float32; an
    empty group's 1e30); returns the number of touching pairs."""
    S = solver.state
    bounds = quiet_bounds(solver.model)
    x, r = S.x.to_numpy(), S.radius.to_numpy()
    nbr, cnt = S.nbr.to_numpy(), S.nbr_n.to_numpy()
    n_touch, end, gap = S.nbr_touch.to_numpy(), S.nbr_end.to_numpy(), S.nbr_gap.to_numpy()
    touching = 0
    for i in range(n):
        row = nbr[i, :cnt[i]]
        d = x[row] - x[i]
        for a in range(3):
            if periodic[a]:
                d[:, a] -= lengths[a] * np.round(d[:, a] / lengths[a])
        gaps = np.linalg.norm(d, axis=1) - r[row] - r[i]
        group = (gaps >= 0.0) + sum(gaps >= b for b in bounds)  # 0: touching, 1 + the quiet group
        assert np.array_equal(row, row[np.lexsort((row, group))]), f"row {i}: {row}, groups {group}"
        assert n_touch[i] == (group == 0).sum(), f"row {i}"
        for g in range(len(bounds) + 1):
            members = group == g + 1
            if g < len(bounds):
                assert end[i, g] == (group <= g + 1).sum(), f"row {i}, group {g}"
            expected = gaps[members].min() if members.any() else None
            assert gap[i, g] == pytest.approx(expected, rel=1e-6) if expected is not None else gap[i, g] > 1e29, \
                f"row {i}, group {g}"
        touching += int((group == 0).sum())
    return touching


THIN = np.array([0.02, 0.0055, 0.0055])  # y and z: 2 search cells of the 2.6 mm reach (2 mm spheres, skin 0.3)
TALL = np.array([0.012, 0.012, 0.04])  # slabs along z (15 cells, 14 slabs)
DEEP = np.array([0.012, 0.04, 0.012])  # slabs along y


@pytest.mark.parametrize("periodic, hi, n", [(["x", "y"], None, 400), ([], None, 400), (["z"], None, 400),
                                             (["x", "y", "z"], None, 400), (["y"], THIN, 40), (["y", "z"], THIN, 40),
                                             ([], TALL, 400), (["z"], TALL, 400), (["y"], DEEP, 400)])
def test_neighbour_list_matches_brute_force(solver_for, periodic, hi, n):
    """Also for periodic axes of two search cells (a slab a few grains deep), each scanned once, and
    for slabs along each axis (the build skips the layer behind and tells i's layer from the next by
    the cell runs: `kernels/broadphase.py`)."""
    rng = np.random.default_rng(11)
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.02, 0.018, 0.015]) if hi is None else hi
    x = random_spheres(rng, n, lo + 0.001, hi - 0.001, 0.002)
    raw = make_scene(
        domain={"min": lo.tolist(), "max": hi.tolist(), "periodic": periodic, "walls": "none", "gravity": [0, 0, 0]},
        particles=[{"name": "p", "material": "steel", "positions": x.tolist(), "seed": 4,
                    "diameter": {"distribution": "uniform", "min": 0.001, "max": 0.002}}],
        numerics={"skin": 0.3, "max_neighbors": 64},
    )
    s = solver_for(raw)
    if hi is THIN:
        assert all(s.model.grid.cells[a] == 2 for a in range(3) if hi[a] < 0.01), "thin axes must have two cells"
    if hi is TALL or hi is DEEP:
        assert s.model.grid.slab_axis == int(np.argmax(hi)), "slabs along the long axis"
    S = s.state
    r = S.radius.to_numpy()
    lengths = hi - lo
    per = [a in periodic for a in "xyz"]
    expected = brute_force_pairs(S.x.to_numpy(), r, s.model.skin, lengths, per)
    assert len(expected) > n, "the test must have many pairs"
    listed = listed_pairs(S, n)
    assert len(listed) == len(expected) // 2 and unordered(listed) == unordered(expected), "each pair once"
    assert touching_first(s, n, lengths, per) == 0  # (none touch here: the quiet groups by partner index)
    # the owner: the particle in the slab before the partner's, or in one slab the lower scene index
    axis, count = slab_layout(s.model.grid)
    assert count == s.model.grid.cells[axis] and (count <= 2 or count % 2 == 0), "slabs: an even count of cell layers"
    slab, ident = S.slab.to_numpy()[:n], S.ident.to_numpy()[:n]
    width = lengths[axis] / count
    assert np.array_equal(slab, np.clip(np.floor((S.x.to_numpy()[:n, axis] - lo[axis]) / width), 0, count - 1))
    wrap = count if per[axis] else 10**9
    for i, j in listed:
        ahead, behind = (slab[i] + 1) % wrap, (slab[i] - 1) % wrap
        if slab[j] == slab[i] or (slab[j] == ahead and slab[j] == behind):
            assert ident[i] < ident[j]
        else:
            assert slab[j] == ahead, f"pair {i, j}: slab {slab[j]} does not follow slab {slab[i]}"
    # the slab lists: every particle once, each slab in index order
    start, order = S.slab_start.to_numpy(), S.slab_list.to_numpy()[:n]
    for q in range(count):
        members = order[start[q]:start[q + 1]]
        assert np.array_equal(members, np.flatnonzero(slab == q))


def test_history_follows_partner_across_rebuild(solver_for):
    """Tag every history slot with its pair; after particles move and the list is rebuilt,
    each surviving pair that touches finds its own tag, and each new pair and each pair apart
    starts from zero. Twice: the rows the
    second build starts from list the touching partners first, so their history moves within the
    row in chains and cycles."""
    rng = np.random.default_rng(5)
    g = (np.arange(8) + 0.5) * 0.0024
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    x += rng.uniform(-0.0002, 0.0002, x.shape)
    n = len(x)
    raw = make_scene(
        domain={"min": [0, 0, 0], "max": [0.0192, 0.0192, 0.0192], "periodic": ["x", "y", "z"], "walls": "none",
                "gravity": [0, 0, 0]},
        materials={"steel": {"density": 7800.0, "youngs_modulus": 2e11, "restitution": 0.5, "friction": 0.5,
                             "rolling_friction": 0.1}},
        contact={"model": "hysteretic"},
        particles=[{"name": "p", "material": "steel", "positions": x.tolist(),
                    "diameter": {"distribution": "mono", "value": 0.002}}],
        numerics={"skin": 0.5, "max_neighbors": 48},
    )
    s = solver_for(raw)
    S = s.state
    K = s.model.max_neighbors
    for _ in range(2):
        before = listed_pairs(S, n)
        nbr, cnt = S.nbr.to_numpy(), S.nbr_n.to_numpy()
        tag = np.zeros((n, K, 3))
        for i in range(n):
            for k in range(cnt[i]):
                tag[i, k] = [i, nbr[i, k], 1.0]
        S.ft.from_numpy(tag)
        S.mr.from_numpy(2 * tag)
        S.dmax.from_numpy(tag[:, :, 1].copy())
        S.x.from_numpy(S.x.to_numpy() + rng.normal(0, 0.0006, (n, 3)))
        s._rebuild(n)
        after = listed_pairs(S, n)
        assert len(before & after) > 100 and len(after - before) > 100 and len(before - after) > 100
        flipped = {(i, j) for i, j in after if (j, i) in before}
        assert len(flipped) > 20, "particles crossed into other slabs: pairs changed owner"
        assert touching_first(s, n, [0.0192] * 3, [True] * 3) > 100, "many pairs must touch"
        ft, mr, dmax = S.ft.to_numpy(), S.mr.to_numpy(), S.dmax.to_numpy()
        nbr, cnt, touch = S.nbr.to_numpy(), S.nbr_n.to_numpy(), S.nbr_touch.to_numpy()
        assert (cnt - touch).sum() > 100, "many listed pairs must be apart"
        for i in range(n):
            for k in range(cnt[i]):
                j = nbr[i, k]
                want = np.zeros(3)
                if k >= touch[i]:  # apart at the build: no history (the next contact pass would zero it)
                    pass
                elif (i, j) in before:
                    want = np.array([i, j, 1.0])
                elif (j, i) in before:  # the new owner sees the springs of the old one with the other sign
                    want = -np.array([j, i, 1.0])
                assert np.array_equal(ft[i, k], want)
                assert np.array_equal(mr[i, k], 2 * want)
                assert dmax[i, k] == abs(want[1])


def test_the_counting_sort_in_parallel_loops_builds_the_same_rows(solver_for, monkeypatch):
    """Beds above broadphase.SERIAL_PARTICLES (and every bed on a GPU) count, sum (a grid of more than
    SCAN_BLOCK cells in blocks) and scatter the particles into cells in parallel loops; smaller ones
    on the CPU in one thread. Both give the same rows, slab lists and histories, entry for entry."""
    import tidem.kernels.broadphase as broadphase

    rng = np.random.default_rng(5)
    hi = np.array([0.04, 0.04, 0.04])  # 15^3 search cells of the 2.6 mm reach: over SCAN_BLOCK
    x = random_spheres(rng, 400, np.full(3, 0.001), np.array([0.025, 0.025, 0.011]), 0.00185)  # some touch
    raw = make_scene(
        domain={"min": [0.0, 0.0, 0.0], "max": hi.tolist(), "periodic": ["x"], "walls": "none", "gravity": [0, 0, 0]},
        particles=[{"name": "p", "material": "steel", "positions": x.tolist(),
                    "diameter": {"distribution": "mono", "value": 0.002}}],
        numerics={"skin": 0.3, "max_neighbors": 64, "max_overlap": 0.5},
    )
    serial = solver_for(raw)
    monkeypatch.setattr(broadphase, "SERIAL_PARTICLES", 0)
    parallel = solver_for(raw)
    assert serial.model.grid.n_cells > broadphase.SCAN_BLOCK
    assert serial.state.nbr_touch.to_numpy().sum() > 50, "the test must have touching pairs"
    for s in (serial, parallel):
        for _ in range(30):
            s.step()
        s.rebuild()
    assert serial.rebuilds == parallel.rebuilds >= 3
    for name in ("nbr_n", "nbr", "nbr_touch", "slab_start", "slab_list", "ft", "x"):
        a, b = getattr(serial.state, name).to_numpy(), getattr(parallel.state, name).to_numpy()
        if name == "nbr":  # beyond a row's count its slots are scratch
            keep = np.arange(a.shape[1])[None, :] < serial.state.nbr_n.to_numpy()[:, None]
            a, b = a[keep], b[keep]
        assert np.array_equal(a, b), name


def test_capacity_overflow_is_an_error(solver_for):
    from tidem.sim.solver import RunError

    side = 0.001 + 0.00205 * np.arange(4)  # a cubic lattice just wider than d, with a skin that reaches the
    x = np.stack(np.meshgrid(side, side, side, indexing="ij"), axis=-1).reshape(-1, 3)  # face diagonals:
    raw = make_scene(  # 18 neighbours within reach, about half of them in the particle's own row
        domain={"min": [0, 0, 0], "max": [0.01, 0.01, 0.01], "walls": "none", "gravity": [0, 0, 0]},
        particles=[{"name": "p", "material": "steel", "positions": x.tolist(),
                    "diameter": {"distribution": "mono", "value": 0.002}}],
        numerics={"max_neighbors": 4, "max_overlap": 0.5, "skin": 0.5},
    )
    with pytest.raises(RunError, match="numerics.max_neighbors"):
        solver_for(raw)


def test_slabs_go_across_gravity_unless_the_column_is_narrow():
    """Slabs along x are stretches of the x-major storage order (`kernels/geometry.py`, slab_axis_for)."""
    down = (0.0, 0.0, -9.81)
    assert slab_axis_for((56, 2, 142), down) == 0  # the bubbling bed: 56 slabs along x, not 142 along z
    assert slab_axis_for((20, 30, 10), down) == 1
    assert slab_axis_for((3, 3, 38), down) == 2  # a narrow column
    assert slab_axis_for((3, 3, 2), down) == 0
