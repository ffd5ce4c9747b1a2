"""Initial overlaps (`tidem.overlaps`): the cell search finds the same pairs as brute force,
periodic axes included."""

import numpy as np
import pytest

from tidem.overlaps import overlapping_pairs


@pytest.mark.parametrize("periodic", [(False, False, False), (True, False, True)])
def test_cell_search_finds_every_overlapping_pair(periodic):
    rng = np.random.default_rng(3)
    lengths = np.array([0.05, 0.03, 0.04])
    x = rng.uniform(0, 1, (400, 3)) * lengths
    r = rng.uniform(0.001, 0.003, 400)
    i, j, ratio = overlapping_pairs(x, r, (0, 0, 0), lengths, periodic)
    d = x[None, :, :] - x[:, None, :]
    for a in range(3):
        if periodic[a]:
            d[..., a] -= lengths[a] * np.round(d[..., a] / lengths[a])
    depth = r[:, None] + r[None, :] - np.linalg.norm(d, axis=2)
    want = {(a, b) for a, b in zip(*np.nonzero(depth > 0)) if a < b}
    assert want and set(zip(i.tolist(), j.tolist())) == want
    assert np.allclose(ratio, depth[i, j] / np.minimum(r[i], r[j]))
