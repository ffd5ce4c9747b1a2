"""Initial overlaps (`tidem.particles.overlaps`): the cell search finds the same pairs as brute force,
periodic axes included."""

import numpy as np
import pytest

from tidem.particles.overlaps import overlapping_pairs


@pytest.mark.parametrize("periodic, lengths", [((False, False, False), [0.05, 0.03, 0.04]),
                                               ((True, False, True), [0.05, 0.03, 0.04]),
                                               ((True, True, False), [0.008, 0.013, 0.02])])  # 1 and 2 cells
def test_cell_search_finds_every_overlapping_pair(periodic, lengths):
    rng = np.random.default_rng(3)
    lengths = np.array(lengths)
    x = rng.uniform(0, 1, (400, 3)) * lengths
    r = rng.uniform(0.001, 0.003, 400)
    i, j, ratio = overlapping_pairs(x, r, (0, 0, 0), lengths, periodic)
    d = x[None, :, :] - x[:, None, :]
    for a in range(3):
        if periodic[a]:
            d[..., a] -= lengths[a] * np.round(d[..., a] / lengths[a])
    depth = r[:, None] + r[None, :] - np.linalg.norm(d, axis=2)
    want = {(a, b) for a, b in zip(*np.nonzero(depth > 0)) if a < b}
    assert want and sorted(zip(i.tolist(), j.tolist())) == sorted(want)
    assert np.allclose(ratio, depth[i, j] / np.minimum(r[i], r[j]))


def test_only_pairs_above_the_limit_are_kept():
    x = np.array([[0.0, 0.0, 0.0], [0.0099, 0.0, 0.0], [0.05, 0.0, 0.0], [0.058, 0.0, 0.0]])
    i, j, ratio = overlapping_pairs(x, np.full(4, 0.005), (-0.01, -0.01, -0.01), (0.1, 0.02, 0.02),
                                    (False,) * 3, above=0.05)
    assert (i.tolist(), j.tolist()) == ([2], [3]) and ratio == pytest.approx([0.4])
