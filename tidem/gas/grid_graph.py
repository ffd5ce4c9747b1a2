"""Connected cells of a grid (plain numpy): components of a graph, the cells joined to seeds through open links
(`tidem.gas.mesh`'s cut of the gas grid, `tidem.gas.apertures`, `tidem.particles.fill_pockets`)."""

from __future__ import annotations

import numpy as np


def components(n: int, ea: np.ndarray, eb: np.ndarray) -> np.ndarray:
    """Connected-component label (the smallest member) of each of n nodes joined by the edges
    (ea, eb): hooking of roots and full pointer jumping, a few numpy passes."""
    label = np.arange(n)
    while True:
        la, lb = label[ea], label[eb]
        lo, hi = np.minimum(la, lb), np.maximum(la, lb)
        join = lo != hi
        if not join.any():
            return label
        np.minimum.at(label, hi[join], lo[join])  # hi is a root: every label is one after jumping
        while True:
            nxt = label[label]
            if np.array_equal(nxt, label):
                break
            label = nxt


def reached(shape, open_links: list[np.ndarray], periodic, seeds: np.ndarray, skip: np.ndarray) -> np.ndarray:
    """Cells of a grid `shape` joined to a seed cell through open links (per axis c, bool over the
    links between consecutive cells: shape[c] - 1 of them, shape[c] on a periodic axis), never
    through a `skip` cell."""
    ids = np.arange(int(np.prod(shape))).reshape(shape)
    ea, eb = [], []
    for c in range(3):
        n = shape[c]
        lo = np.take(ids, range(n if periodic[c] else n - 1), axis=c)
        hi = np.take(ids, [(j + 1) % n for j in range(n if periodic[c] else n - 1)], axis=c)
        ok = open_links[c] & ~skip.flat[lo] & ~skip.flat[hi]
        ea.append(lo[ok])
        eb.append(hi[ok])
    label = components(ids.size, np.concatenate(ea), np.concatenate(eb))
    hit = np.zeros(ids.size, bool)
    hit[np.unique(label[seeds.ravel() & ~skip.ravel()])] = True
    return hit[label].reshape(shape)


def interior_links(links: np.ndarray, c: int, periodic: bool) -> np.ndarray:
    """The links between cells from an array that also holds the two boundary links (open axis)."""
    return links if periodic else np.take(links, range(1, links.shape[c] - 1), axis=c)


def bordering(mask: np.ndarray, c: int, periodic: bool) -> np.ndarray:
    """bool per face normal to c (n_c + 1 of them along an open c, n_c periodic, face j between cells j - 1 and
    j): whether a cell on either side is in `mask`."""
    if periodic:
        return mask | np.roll(mask, 1, axis=c)
    pad = [(0, 0)] * 3
    pad[c] = (1, 0)
    below = np.pad(mask, pad)  # the cell below face j is j - 1 (none below face 0)
    pad[c] = (0, 1)
    above = np.pad(mask, pad)  # the cell above face j is j (none above face n)
    return below | above
