"""Geometry of triangle meshes in plain numpy: welding coincident vertices, triangle areas, the
facet sag, flat patches, the exact point-to-mesh distance and inside tests (ray parity).

Used when a scene's `[[meshes]]` are read (`tidem.walls.mesh_load`) and when particles are placed
(`tidem.particles.placement`: lattice and pour sites that overlap a mesh are skipped). Every function
works on `vertices` [V, 3] float64 and `triangles` [T, 3] integer indices; the pairwise ones
(points x triangles) run in chunks of at most `PAIRS` pairs, so memory stays bounded whatever
the sizes.
"""

from __future__ import annotations

import itertools

import numpy as np

PAIRS = 1 << 18  # points x triangles evaluated at once (a few MB per temporary array)
FEATURE_ANGLE = 45.0  # deg: edges that turn more are corners of the part, not facets of a curve
FLAT_TURN, FLAT_SPREAD = 1e-4, 1e-3  # rad: how flat an edge and a patch must be to count as one plane (`flat_patches`)


def triangle_areas(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area of each triangle, |(b - a) x (c - a)| / 2 [m^2]."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def weld(vertices: np.ndarray, triangles: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray, int]:
    """Merge vertices closer than about `tol` [m] and drop vertices no triangle uses.

    Vertices are binned on a grid of cell `tol`, and again on the 7 grids shifted by half a cell
    along one, two or three axes; vertices sharing a cell in any of the 8 grids are joined
    (labels propagated to the smallest index until nothing changes). Two vertices within tol/2
    of each other along every axis share a cell in at least one grid, so a pair straddling a
    cell boundary is not missed (exact copies are merged before, by their bits). Returns
    (vertices, triangles, merged), merged = the number of used vertices before minus after; a
    merged vertex sits at one of its group.
    """
    used = np.unique(triangles)
    v = np.ascontiguousarray(vertices[used], dtype=np.float64)
    tri = np.searchsorted(used, triangles)
    _, first, exact = np.unique(_row_groups(v.view(np.int64)), return_index=True, return_inverse=True)
    u = v[first]  # exact copies (most of an STL's) merged first: the grids below see each point once
    labels = np.arange(len(u))
    if len(u) and tol > 0:
        q = (u - u.min(axis=0)) / tol
        for _ in range(50):
            before = labels.copy()
            for shift in itertools.product((0.0, 0.5), repeat=3):
                cell = _row_groups(np.floor(q + np.asarray(shift)).astype(np.int64))
                low = np.full(cell.max() + 1, len(u))
                np.minimum.at(low, cell, labels)
                labels = low[cell]
            if np.array_equal(labels, before):
                break
    keep, index = np.unique(labels, return_inverse=True)
    return u[keep], index[exact.ravel()][tri].astype(np.int32), len(v) - len(keep)


def _row_groups(keys: np.ndarray) -> np.ndarray:
    """Group number of each row of integer keys [N, 3] (equal rows, equal numbers)."""
    order = np.lexsort(keys.T[::-1])
    k = keys[order]
    new = np.r_[True, np.any(k[1:] != k[:-1], axis=1)]
    out = np.empty(len(keys), np.int64)
    out[order] = np.cumsum(new) - 1
    return out


def _shared_edges(t: np.ndarray):
    """The edges shared by exactly two triangles of `t` [T, 3]: (f1, f2) the two triangles, (e1, e2) their
    rows among the directed edges (tail -> head: (t0 t1), (t1 t2), (t2 t0) of each triangle), and the
    directed edges' `tail`, `head` and `face` arrays."""
    tail = t.ravel()
    head = t[:, [1, 2, 0]].ravel()
    face = np.repeat(np.arange(len(t)), 3)
    key = np.minimum(tail, head).astype(np.int64) * (int(t.max()) + 1) + np.maximum(tail, head)
    order = np.argsort(key, kind="stable")
    key = key[order]
    first = np.r_[True, key[1:] != key[:-1]]
    starts = np.flatnonzero(first)
    counts = np.diff(np.r_[starts, len(key)])
    pairs = starts[counts == 2]
    e1, e2 = order[pairs], order[pairs + 1]
    return face[e1], face[e2], e1, e2, tail, head, face


def _unit_normals(vertices: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals [T, 3] (right-hand rule over t0 t1 t2; zero for a zero-area triangle) and twice the areas."""
    a, b, c = (vertices[t[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    twice_area = np.linalg.norm(n, axis=1)
    return n / np.where(twice_area > 0, twice_area, 1.0)[:, None], twice_area


def facet_sag(vertices: np.ndarray, triangles: np.ndarray, feature_angle: float = FEATURE_ANGLE) -> float:
    """The largest facet sag [m]: how far the flat facets may lie from the curved surface they
    approximate, estimated at every edge shared by exactly two triangles.

    At an edge where the normals turn by theta, with w = min(w1, w2) the smaller height of the
    two triangles over that edge (the facet width across it), the facets are chords of a circle
    of radius R = (w/2) / sin(theta/2), whose sag is R (1 - cos(theta/2)) = (w/2) tan(theta/4).
    For a regular N-gon cylinder of radius R (theta = 2 pi/N, w = 2 R sin(pi/N)) this is exactly
    R (1 - cos(pi/N)). Edges turning by more than `feature_angle` degrees are corners of the
    part (a box's edges, a cylinder's rim), not facets of a curve, and are left out. Normals are
    taken with a consistent winding (one is flipped where the two triangles run along the edge
    in the same direction), so meshes with mixed orientation give the same answer.
    """
    t = np.asarray(triangles)
    if len(t) < 2:
        return 0.0
    n, twice_area = _unit_normals(vertices, t)
    f1, f2, e1, e2, tail, head, face = _shared_edges(t)
    if not len(f1):
        return 0.0
    length = np.linalg.norm(vertices[head] - vertices[tail], axis=1)
    width = twice_area[face] / np.where(length > 0, length, np.inf)
    same_way = tail[e1] == tail[e2]  # consistent winding runs a shared edge in opposite directions
    cos = np.einsum("ij,ij->i", n[f1], n[f2]) * np.where(same_way, -1.0, 1.0)
    theta = np.arccos(np.clip(cos, -1.0, 1.0))
    ok = (theta <= np.radians(feature_angle)) & (twice_area[f1] > 0) & (twice_area[f2] > 0)
    if not ok.any():
        return 0.0
    sag = 0.5 * np.minimum(width[e1], width[e2]) * np.tan(0.25 * theta)
    return float(sag[ok].max())


def flat_patches(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Patch number [T] of each triangle: the smallest index among the triangles joined to it through
    shared edges across which the surface stays flat (the normals turn by less than FLAT_TURN rad and
    the far vertex of the second triangle lies within FLAT_TURN of its distance from the first's plane;
    a float32 STL rounds a plane's triangles to about 1e-5 rad). A patch whose normals spread by more
    than FLAT_SPREAD rad from its first triangle's (a surface curving very gently over many facets) is
    split back into single triangles. A floor or a box face drawn as many triangles is one patch, a
    faceted cylinder a patch per facet (`kernels/mesh_contact.py` treats a particle whose listed
    triangles all lie in one patch as touching a plane)."""
    t = np.asarray(triangles)
    labels = np.arange(len(t))
    if len(t) < 2:
        return labels
    n, _ = _unit_normals(vertices, t)
    f1, f2, e1, _e2, tail, head, _face = _shared_edges(t)
    far = vertices[t[f2].sum(axis=1) - tail[e1] - head[e1]] - vertices[tail[e1]]  # f2's vertex off the edge
    flat = (np.abs(np.einsum("ij,ij->i", n[f1], n[f2])) >= np.cos(FLAT_TURN)) & (
        np.abs(np.einsum("ij,ij->i", far, n[f1])) <= FLAT_TURN * np.linalg.norm(far, axis=1))
    f1, f2 = f1[flat], f2[flat]
    while True:  # spread the smallest label over each join, then let labels point to their labels' labels
        low = np.minimum(labels[f1], labels[f2])
        new = labels.copy()
        np.minimum.at(new, f1, low)
        np.minimum.at(new, f2, low)
        new = new[new]
        if np.array_equal(new, labels):
            break
        labels = new
    bent = np.abs(np.einsum("ij,ij->i", n, n[labels])) < np.cos(FLAT_SPREAD)
    split = np.isin(labels, labels[bent])
    labels[split] = np.flatnonzero(split)
    return labels


def _chunks(n_points: int, n_triangles: int):
    """Slices of the points such that each covers at most PAIRS point-triangle pairs."""
    step = max(1, PAIRS // max(1, n_triangles))
    for s in range(0, n_points, step):
        yield slice(s, min(n_points, s + step))


def _segment_distance2(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distance of points p [n, 1, 3] to segments a-b [1, t, 3] -> [n, t]."""
    ab = b - a
    ap = p - a
    den = np.einsum("...k,...k->...", ab, ab)
    s = np.clip(np.einsum("...k,...k->...", ap, ab) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    d = ap - s[..., None] * ab
    return np.einsum("...k,...k->...", d, d)


def _distances(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Exact distance of each point p [n, 3] to each triangle abc ([t, 3] each) -> [n, t].

    The closest point of a triangle lies in its interior (then the distance is the one to the
    plane, |n . (p - a)| / |n|) or on one of its three edges; the interior case holds where the
    projection of p falls on the inner side of all three edges. A zero-area triangle has no
    interior and counts by its edges."""
    p = p[:, None, :]
    a, b, c = a[None], b[None], c[None]
    n = np.cross(b - a, c - a)
    nn = np.einsum("...k,...k->...", n, n)
    inside = np.broadcast_to(nn > 0, (p.shape[0], n.shape[1])).copy()
    for u, w in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("...k,...k->...", np.cross(w - u, p - u), n) >= 0
    plane = np.einsum("...k,...k->...", p - a, n) ** 2 / np.where(nn > 0, nn, 1.0)
    edge = np.minimum(np.minimum(_segment_distance2(p, a, b), _segment_distance2(p, b, c)), _segment_distance2(p, c, a))
    return np.sqrt(np.where(inside, np.minimum(plane, edge), edge))


class _BoxIndex:
    """Bounding boxes of the triangles, sorted by their lower end along one axis (default: the
    mesh's longest), to find the triangles whose box meets a query box without testing all."""

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray, axis: int | None = None):
        self.lo = np.minimum(np.minimum(a, b), c)
        self.hi = np.maximum(np.maximum(a, b), c)
        if axis is None:
            axis = int(np.argmax(self.hi.max(axis=0) - self.lo.min(axis=0))) if len(a) else 0
        self.axis = axis
        self.order = np.argsort(self.lo[:, self.axis], kind="stable")
        self.keys = self.lo[self.order, self.axis]
        self.extent = float((self.hi - self.lo)[:, self.axis].max()) if len(a) else 0.0

    def meeting(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Indices of the triangles whose box meets [lo, hi]."""
        k = self.axis
        span = self.order[np.searchsorted(self.keys, lo[k] - self.extent, "left"):
                          np.searchsorted(self.keys, hi[k], "right")]
        return span[np.all((self.hi[span] >= lo) & (self.lo[span] <= hi), axis=1)]


def _cells(x: np.ndarray, cell: float) -> np.ndarray:
    """Integer cell coordinates [N, 3] of the points on a grid of `cell` from their lower corner."""
    return np.clip(np.floor((x - x.min(axis=0)) / max(cell, 1e-300)), 0, (1 << 21) - 1).astype(np.uint64)


def _spread(n: np.ndarray) -> np.ndarray:
    """The 21 low bits of n spread to every third bit (for the Morton code)."""
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                        (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
        n = (n | (n << np.uint64(shift))) & np.uint64(mask)
    return n


def _morton_order(x: np.ndarray, cell: float) -> np.ndarray:
    """An order of the points [N, 3] along the Z-order curve of their cells, so that any run of
    consecutive points lies in a compact box."""
    q = _cells(x, cell)
    return np.argsort(_spread(q[:, 0]) | (_spread(q[:, 1]) << np.uint64(1)) | (_spread(q[:, 2]) << np.uint64(2)),
                      kind="stable")


def point_mesh_distance(points, vertices, triangles, within: float | None = None) -> np.ndarray:
    """Distance of each point [N, 3] to the nearest triangle of the mesh [m] -> [N].

    Exact point-triangle distances (see `_distances`), the minimum over all triangles, in
    chunks of at most PAIRS pairs. With `within` (a clearance test), only distances below it
    are exact: points are taken in the Z-order of their cells, and each chunk of them sees only
    the triangles whose bounding box comes within `within` of the chunk's box; a point farther
    than `within` from the mesh gets a value >= within (inf where no triangle is that near).
    """
    x = np.asarray(points, float).reshape(-1, 3)
    out = np.full(len(x), np.inf)
    t = np.asarray(triangles)
    if not len(x) or not len(t):
        return out
    a, b, c = (np.asarray(vertices, float)[t[:, k]] for k in range(3))
    if within is None:
        for s in _chunks(len(x), len(t)):
            out[s] = _distances(x[s], a, b, c).min(axis=1)
        return out
    index = _BoxIndex(a, b, c)
    order = _morton_order(x, max(float(within), 1e-12))
    for s in _chunks(len(x), min(len(t), PAIRS // 16)):  # 16 points a chunk: their box stays small
        idx = order[s]
        p = x[idx]
        sel = index.meeting(p.min(axis=0) - within, p.max(axis=0) + within)
        best = np.full(len(idx), np.inf)
        for u in _chunks(len(sel), len(idx)):  # len(idx) x len(u) <= PAIRS
            best = np.minimum(best, _distances(p, a[sel[u]], b[sel[u]], c[sel[u]]).min(axis=1))
        out[idx] = best
    return out


def _ray_parity(points, vertices, triangles, directions) -> np.ndarray:
    """Inside by ray parity: for each of the given ray directions, whether the ray from each
    point crosses the mesh an odd number of times (Moeller-Trumbore ray-triangle test); the
    majority of the directions decides, so a ray that grazes an edge or vertex (counted twice
    or not at all) does not. The orientation of the triangles does not matter.

    A ray leaves the mesh's bounding box within a travel T along its main axis k (the largest
    component of d), drifting at most T |d_j / d_k| across it; a chunk of points close together
    tests only the triangles whose box meets the chunk's box grown by that drift (and reaching
    ahead along k), so near-axis directions test few triangles."""
    x = np.asarray(points, float).reshape(-1, 3)
    t = np.asarray(triangles)
    votes = np.zeros(len(x), int)
    if not len(x) or not len(t):
        return votes > 0
    a, b, c = (np.asarray(vertices, float)[t[:, k]] for k in range(3))
    e1, e2 = b - a, c - a
    mesh_lo = np.minimum(np.minimum(a, b), c).min(axis=0)
    mesh_hi = np.maximum(np.maximum(a, b), c).max(axis=0)
    size = float(np.linalg.norm(mesh_hi - mesh_lo))
    for d in directions:
        d = np.asarray(d, float) / np.linalg.norm(d)
        k = int(np.argmax(np.abs(d)))
        across = [j for j in range(3) if j != k]
        slope = np.abs(d) / abs(d[k])
        index = _BoxIndex(a, b, c, axis=across[1])
        q = _cells(x, size / 32.0)
        order = np.lexsort((x[:, k], q[:, across[0]], q[:, across[1]]))  # columns along the ray's axis
        odd = np.zeros(len(x), bool)
        for s in _chunks(len(x), min(len(t), 4096)):
            idx = order[s]
            p = x[idx]
            lo, hi = p.min(axis=0), p.max(axis=0)
            travel = (mesh_hi[k] - lo[k]) if d[k] > 0 else (hi[k] - mesh_lo[k])
            grow = slope * max(travel, 0.0)
            grow[k] = 0.0
            lo, hi = lo - grow, hi + grow
            if d[k] > 0:
                hi[k] = np.inf
            else:
                lo[k] = -np.inf
            sel = index.meeting(lo, hi)
            hits = np.zeros(len(idx), int)
            for u in _chunks(len(sel), len(idx)):
                tri = sel[u]
                h = np.cross(d, e2[tri])
                det = np.einsum("ij,ij->i", e1[tri], h)
                ok = np.abs(det) > 1e-300
                inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
                sv = p[:, None, :] - a[tri][None]
                bu = np.einsum("ntk,tk->nt", sv, h) * inv
                q = np.cross(sv, e1[tri][None])
                bv = (q @ d) * inv
                dist = np.einsum("ntk,tk->nt", q, e2[tri]) * inv
                hits += (ok & (bu >= 0) & (bv >= 0) & (bu + bv <= 1) & (dist > 0)).sum(axis=1)
            odd[idx] = hits % 2 == 1
        votes += odd
    return votes * 2 > len(directions)


# near-axis directions (fast, see _ray_parity), tilted by odd small angles so that a ray from a
# lattice site seldom runs exactly through an edge of a part drawn at round coordinates
_NEAR_AXES = np.array([[1.0, 0.0123, 0.0171], [0.0147, 1.0, -0.0113], [-0.0131, 0.0159, 1.0]])


def inside_closed_mesh(points, vertices, triangles) -> np.ndarray:
    """Whether each point [N, 3] lies inside a closed (watertight) mesh -> bool [N]: ray parity
    along three directions, majority vote (see `_ray_parity`)."""
    return _ray_parity(points, vertices, triangles, _NEAR_AXES)


def inside_periodic_mesh(points, vertices, triangles, axis) -> np.ndarray:
    """Whether each point [N, 3] lies inside a mesh that is open along `axis` ("x", "y", "z" or
    a vector), e.g. a drum's cylinder without end caps spanning a periodic axis -> bool [N].

    The rays run perpendicular to the axis (three directions in the cross-section, majority
    vote), so they cross only the mantle: once from inside, an even number of times from
    outside. A point beyond the mesh's ends along the axis counts as outside."""
    if isinstance(axis, str):
        axis = np.eye(3)["xyz".index(axis)]
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.eye(3)[int(np.argmin(np.abs(k)))]
    e1 = np.cross(helper, k)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(k, e1)
    dirs = [np.cos(w) * e1 + np.sin(w) * e2 for w in (0.0123, 0.5 * np.pi + 0.0147, np.pi + 0.0109)]
    return _ray_parity(points, vertices, triangles, dirs)


def open_axis(vertices, triangles, strict: bool = False) -> int | None:
    """None for a closed mesh (every edge shared by two triangles); for an open one, the axis (0, 1,
    2) along which every boundary vertex lies at one of the mesh's two ends, e.g. a drum's cylinder
    without end caps (lifter sheets along it included); -1 if no axis does (an open mesh has no
    inside). `strict`: every boundary edge, both its vertices at the same end (a tube open at its ends;
    not a sheet along the axis, whose rim runs from one end to the other)."""
    t = np.asarray(triangles)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(edges, axis=0, return_counts=True)
    rim = uniq[count == 1]
    if not len(rim):
        return None
    v = np.asarray(vertices, float)
    lo, hi = v.min(axis=0), v.max(axis=0)
    tol = 1e-9 * float(np.linalg.norm(hi - lo))
    for a in range(3):
        ends = v[rim, a]  # [edges, 2]
        at_lo, at_hi = np.abs(ends - lo[a]) <= tol, np.abs(ends - hi[a]) <= tol
        at_end = (at_lo.all(axis=1) | at_hi.all(axis=1)) if strict else (at_lo | at_hi).all(axis=1)
        if hi[a] - lo[a] > 1e3 * tol and at_end.all():  # a flat sheet has both its ends at one place
            return a
    return -1


def inside_mesh(points, vertices, triangles, strict: bool = False) -> np.ndarray | None:
    """Whether each point lies inside a closed mesh or inside an axis-open one (`open_axis`, `strict`
    as there); None if the mesh has no inside."""
    axis = open_axis(vertices, triangles, strict)
    if axis is None:
        return inside_closed_mesh(points, vertices, triangles)
    if axis < 0:
        return None
    return inside_periodic_mesh(points, vertices, triangles, "xyz"[axis])
