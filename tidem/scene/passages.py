"""Passages too narrow for coarse-grained parcels: advice, not errors.

A parcel of diameter k d stands for k^3 grains, but it packs and flows as one particle of its
own size. Where a passage is only a few parcels wide, the parcel's wall effect and arching
replace the grains': in the moving-bed verification (docs/coarse_graining.md) a slab 4.2 parcels
deep packed 9 % looser and discharged 24 % less than its grains, so MIN_PARCELS is a floor,
not a guarantee. `narrow_passages` lists, for each coarse-grained group,
the horizontal extents of the domain, the gaps between parallel tubes and the gaps between a tube
and a domain wall that hold fewer than `MIN_PARCELS` of its largest parcels, with the k that
would fit them.
"""

from __future__ import annotations

import itertools
import math

from tidem.scene.schema import Scene
from tidem.scene.sizes import largest_diameter

MIN_PARCELS = 4.0
AXES = "xyz"


def _horizontal(scene: Scene) -> list[int]:
    """The two axes across gravity (gravity's largest component is 'up')."""
    g = [abs(c) for c in scene.domain.gravity]
    up = g.index(max(g))
    return [a for a in range(3) if a != up]


def _passages(scene: Scene) -> list[tuple[str, float]]:
    """(what, width [m]) of every horizontal extent, tube-tube and tube-wall gap of the scene."""
    dom = scene.domain
    lo, hi = dom.min, dom.max
    out = [(f"the domain's {AXES[a]} extent", hi[a] - lo[a]) for a in _horizontal(scene)]
    walls = set(dom.wall_sides())
    for i, t in enumerate(scene.tubes):
        across = [a for a in range(3) if AXES[a] != t.axis]
        for a in across:
            for side, gap in (("-", t.center[a] - 0.5 * t.diameter - lo[a]), ("+", hi[a] - t.center[a] - 0.5 * t.diameter)):
                if f"{AXES[a]}{side}" in walls:
                    out.append((f"the gap between tubes[{i}] and the {AXES[a]}{side} wall", gap))
    for (i, t), (j, u) in itertools.combinations(enumerate(scene.tubes), 2):
        if t.axis != u.axis:
            continue
        d2 = 0.0
        for a in range(3):
            if AXES[a] == t.axis:
                continue
            d = u.center[a] - t.center[a]
            if AXES[a] in dom.periodic:
                length = hi[a] - lo[a]
                d -= length * round(d / length)
            d2 += d * d
        out.append((f"the gap between tubes[{i}] and tubes[{j}]", math.sqrt(d2) - 0.5 * (t.diameter + u.diameter)))
    return out


def narrow_passages(scene: Scene) -> list[str]:
    """One line per coarse-grained group with a passage narrower than MIN_PARCELS parcels: the
    narrowest, and how many more there are (closed gaps, width <= 0, are the geometry checks')."""
    notes = []
    passages = _passages(scene)
    for g_i, group in enumerate(scene.particles):
        k = group.coarse_grain
        if k <= 1.0:
            continue
        grain = largest_diameter(group.diameter)
        parcel = k * grain
        narrow = sorted((width, what) for what, width in passages if 0.0 < width < MIN_PARCELS * parcel)
        if not narrow:
            continue
        width, what = narrow[0]
        k_fit = max(1.0, math.floor(10.0 * width / (MIN_PARCELS * grain)) / 10.0)
        more = f" (and {len(narrow) - 1} more passages under {MIN_PARCELS:g} parcels)" if len(narrow) > 1 else ""
        notes.append(f"particles[{g_i}].coarse_grain = {k:g}: {what} is {width * 1e3:.3g} mm, {width / parcel:.1f} "
                     f"parcels of {parcel * 1e3:.3g} mm{more}; in passages under {MIN_PARCELS:g} parcels, parcels pack "
                     f"and flow as particles of their own size, not as their grains (docs/coarse_graining.md); use "
                     f"coarse_grain <= {k_fit:g} or widen the passage")
    return notes
