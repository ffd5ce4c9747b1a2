"""Initial overlaps: particles placed into each other, or into a wall or tube, found before the
first step, so that `tidem check` names the particles and the key to change instead of a run
stopping at t = 0 with "the contacts are too soft".

The overlap ratio is the runtime's (`kernels/contact.py`, `Solver.check`): the overlap depth
over the smaller radius of a pair, or over the particle's radius at a wall or tube, compared
with numerics.max_overlap. Pairs are found on a cell grid of twice the largest radius (a
particle meets only the 27 cells around its own), with the periodic axes wrapped.
"""

from __future__ import annotations

import itertools

import numpy as np

MAX_MESSAGES = 6  # overlapping group pairs and particles at walls reported one by one


def overlapping_pairs(x: np.ndarray, radius: np.ndarray, lo, lengths, periodic,
                      above: float = 0.0) -> tuple[np.ndarray, ...]:
    """(i, j, ratio) of every pair i < j whose spheres overlap by a ratio = depth / min(r_i, r_j)
    greater than `above`."""
    n = len(x)
    none = np.zeros(0, np.int64)
    if n < 2:
        return none, none, np.zeros(0)
    lengths = np.asarray(lengths, float)
    counts = np.clip(np.floor(lengths / (2.0 * radius.max())), 1, 2**20).astype(np.int64)
    cell = np.clip(np.floor((x - np.asarray(lo)) / (lengths / counts)).astype(np.int64), 0, counts - 1)

    def key(c):
        return (c[:, 0] * counts[1] + c[:, 1]) * counts[2] + c[:, 2]

    order = np.argsort(key(cell), kind="stable")
    keys = key(cell)[order]
    found = []
    half = [o for o in itertools.product((-1, 0, 1), repeat=3) if o >= (0, 0, 0)]  # o and -o meet the same pairs
    for offset in half:  # kept per offset: only the pairs overlapping more than `above`
        near = cell + np.asarray(offset)
        ok = np.ones(n, bool)
        for a in range(3):
            if periodic[a]:
                near[:, a] %= counts[a]
            else:
                ok &= (near[:, a] >= 0) & (near[:, a] < counts[a])
        k = key(near)
        start = np.searchsorted(keys, k, "left")
        many = np.where(ok, np.searchsorted(keys, k, "right") - start, 0)
        i = np.repeat(np.arange(n), many)
        j = order[np.repeat(start - np.cumsum(many) + many, many) + np.arange(many.sum())]
        keep = i < j if offset == (0, 0, 0) else i != j  # a periodic axis of one cell wraps onto itself
        i, j = i[keep], j[keep]
        hit = _depth(x, radius, i, j, lengths, periodic) > above * np.minimum(radius[i], radius[j])
        found.append(np.minimum(i[hit], j[hit]) * n + np.maximum(i[hit], j[hit]))
    pair = np.unique(np.concatenate(found))  # a pair met through two offsets (few periodic cells) counts once
    i, j = pair // n, pair % n
    return i, j, _depth(x, radius, i, j, lengths, periodic) / np.minimum(radius[i], radius[j])


def min_image(d: np.ndarray, lengths, periodic) -> np.ndarray:
    """Separations d [n, 3] with each periodic component wrapped to the nearest image (in place)."""
    for a in range(3):
        if periodic[a]:
            d[:, a] -= lengths[a] * np.round(d[:, a] / lengths[a])
    return d


def _depth(x, radius, i, j, lengths, periodic) -> np.ndarray:
    """Overlap depth r_i + r_j - |x_j - x_i| of pairs (minimum image on periodic axes) [m]."""
    return radius[i] + radius[j] - np.linalg.norm(min_image(x[j] - x[i], lengths, periodic), axis=1)


def surface_overlaps(x: np.ndarray, radius: np.ndarray, planes: list[dict], tubes: list[dict], lengths,
                     periodic) -> tuple[np.ndarray, list[str]]:
    """Per particle, the largest overlap ratio depth / r with a plane or tube, and its name."""
    worst = np.zeros(len(x))
    which = np.full(len(x), -1)
    names = [p["name"] for p in planes] + [t["name"] for t in tubes]
    gaps = [(x - np.asarray(p["p0"])) @ np.asarray(p["n"]) for p in planes]
    for t in tubes:
        d = min_image(x - np.asarray(t["c"]), lengths, periodic)
        gaps.append(np.linalg.norm(d * np.asarray(t["mask"]), axis=1) - t["r"])
    for s, gap in enumerate(gaps):
        ratio = (radius - gap) / radius
        deeper = ratio > worst
        worst[deeper], which[deeper] = ratio[deeper], s
    return worst, [names[s] if s >= 0 else "" for s in which]


def fills_apart(scene) -> bool:
    """True when every group placed at the start fills a region and no two regions (grown by
    the largest diameter) meet: the lattice of a fill has no overlaps, so no pair need be checked."""
    from tidem.scene.sizes import max_diameter

    placed = [g for g in scene.particles if g.pour is None]
    if any(g.region is None for g in placed):
        return False
    grow = max_diameter(scene)
    return not any(all(a.region.min[k] - grow < b.region.max[k] and b.region.min[k] - grow < a.region.max[k]
                       for k in range(3)) for n, a in enumerate(placed) for b in placed[n + 1:])


def _where(scene, group: int, k: int) -> str:
    """The key of a particle: 'particles[0].positions[3]' or 'particle 12 of particles[0].region'."""
    if scene.particles[group].positions is not None:
        return f"particles[{group}].positions[{k}]"
    return f"particle {k} of the fill of particles[{group}].region"


def initial_overlaps(scene, x, radius, active, group, planes, tubes, lengths, periodic) -> list[str]:
    """Messages for placed particles that overlap each other, a wall or a tube by more than
    numerics.max_overlap, each naming the particles, their group's key and the fix."""
    limit = scene.numerics.max_overlap
    idx = np.flatnonzero(active)
    first = {g: int(np.argmax(group == g)) for g in np.unique(group)}
    xs, rs = x[idx], radius[idx]
    none = np.zeros(0, np.int64)
    i, j, ratio = ((none, none, np.zeros(0)) if fills_apart(scene) else
                   overlapping_pairs(xs, rs, scene.domain.min, lengths, periodic, above=limit))
    out: list[str] = []
    seen: dict[tuple[int, int], int] = {}
    for a, b, r in sorted(zip(idx[i], idx[j], ratio), key=lambda t: -t[2]):
        ga, gb = int(group[a]), int(group[b])
        pair = (min(ga, gb), max(ga, gb))
        seen[pair] = seen.get(pair, 0) + 1
        if seen[pair] > 1 or len(out) >= MAX_MESSAGES:
            continue
        names = (_where(scene, ga, int(a - first[ga])), _where(scene, gb, int(b - first[gb])))
        fill = any(scene.particles[g].positions is None for g in pair)
        fix = ("make the regions and positions of these groups disjoint" if fill else
               f"place their centres at least {radius[a] + radius[b]:.3g} m apart (the sum of their radii), "
               "or remove one")
        out.append(f"{names[0]} and {names[1]} overlap by {100 * r:.0f} % of the smaller radius at "
                   f"{np.round(x[a], 6).tolist()} (limit numerics.max_overlap = {100 * limit:g} %); {fix}")
    for k, pair in enumerate(seen):
        if seen[pair] > 1 and k < len(out):
            out[k] += f" ({seen[pair]} overlapping pairs between these groups in all)"
    worst, surface = surface_overlaps(xs, rs, planes, tubes, lengths, periodic)
    for p in np.flatnonzero(worst > limit)[:max(0, MAX_MESSAGES - len(out))]:
        a = idx[p]
        g = int(group[a])
        out.append(f"{_where(scene, g, int(a - first[g]))} at {np.round(x[a], 6).tolist()} overlaps {surface[p]} by "
                   f"{100 * worst[p]:.0f} % of its radius (limit numerics.max_overlap = {100 * limit:g} %); move it "
                   f"clear of the surface (centre at least {radius[a]:.3g} m from it, on the particles' side)")
    return out
