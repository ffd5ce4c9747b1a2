"""Initial particle sizes and positions: size distributions, lattice fill of a region, pour sites.

Sizes are drawn from the group's distribution with its seed (cut-offs by redrawing, not by
clipping, so no spike at the bounds). A filled region is a simple cubic lattice of spacing
1.02 d_max (no initial overlap), its sites jittered by up to 1 % of the spacing, filled bottom-up; sites
that would overlap a tube or a wall are skipped.
"""

from __future__ import annotations

import numpy as np


class PlacementError(ValueError):
    """A group cannot be placed as asked; the message names the key."""


def sample_diameters(dist, count: int, rng: np.random.Generator) -> np.ndarray:
    """Diameters [m] for `count` particles from a validated distribution table."""
    kind = dist.distribution
    if kind == "mono":
        return np.full(count, dist.value)
    if kind == "uniform":
        return rng.uniform(dist.min, dist.max, count)
    lo = dist.min if dist.min is not None else 0.0
    hi = dist.max if dist.max is not None else np.inf

    def draw(k: int) -> np.ndarray:
        if kind == "normal":
            return rng.normal(dist.mean, dist.std, k)
        return dist.median * np.exp(dist.sigma * rng.standard_normal(k))

    out = draw(count)
    for _ in range(200):
        bad = (out < max(lo, 1e-12)) | (out > hi)
        if not bad.any():
            return out
        out[bad] = draw(int(bad.sum()))
    raise PlacementError("the cut-offs min/max leave almost nothing of the distribution")


def lattice_sites(lo, hi, spacing: float, kind: str = "cubic") -> np.ndarray:
    """Sites of a lattice with nearest-neighbour distance `spacing` inside the box
    [lo + s/2, hi - s/2] (so that images across a periodic side stay `spacing` apart).

    cubic: simple cubic, solid fraction 0.52 (d/s)^3 for touching spheres of diameter d;
    hexagonal: face-centred cubic (close-packed layers), 0.74 (d/s)^3.
    """
    if kind == "hexagonal":
        a = spacing * np.sqrt(2.0)
        lo_in = np.asarray(lo, float) + 0.5 * spacing
        hi_in = np.asarray(hi, float) - 0.5 * spacing
        n = np.floor((hi_in - lo_in) / a).astype(int) + 2
        grid = np.stack(np.meshgrid(*[np.arange(k) for k in n], indexing="ij"), axis=-1).reshape(-1, 3) * a
        basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]]) * a
        pts = (grid[:, None, :] + basis[None, :, :]).reshape(-1, 3) + lo_in
        pts = pts[np.all((pts >= lo_in - 1e-12) & (pts <= hi_in + 1e-12), axis=1)]
        pts += 0.5 * ((hi_in - pts.max(axis=0)) - (pts.min(axis=0) - lo_in))  # equal margins
        return pts[np.lexsort((pts[:, 0], pts[:, 1], pts[:, 2]))]
    axes = []
    for a in range(3):
        n = int(np.floor((hi[a] - lo[a]) / spacing + 1e-9))
        if n < 1:
            return np.zeros((0, 3))
        start = lo[a] + 0.5 * (hi[a] - lo[a] - (n - 1) * spacing)
        axes.append(start + spacing * np.arange(n))
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


def clear_of_obstacles(sites: np.ndarray, radius: float, planes, tubes, lengths, periodic) -> np.ndarray:
    """Mask of sites whose sphere of `radius` touches no plane and no tube."""
    ok = np.ones(len(sites), dtype=bool)
    for p0, n in planes:
        ok &= (sites - np.asarray(p0)) @ np.asarray(n) > radius * (1 - 1e-9)
    for centre, axis_mask, r_tube in tubes:
        d = sites - np.asarray(centre)
        for a in range(3):
            if periodic[a]:
                d[:, a] -= lengths[a] * np.round(d[:, a] / lengths[a])
        d *= np.asarray(axis_mask)
        ok &= np.linalg.norm(d, axis=1) > (r_tube + radius) * (1 - 1e-9)
    return ok
