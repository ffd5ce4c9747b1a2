"""Initial particle sizes and positions: size distributions, lattice fill of a region, pour sites,
the groups of a scene placed (`place_groups`), and the cell-order sort key of the broad phase.

Sizes are drawn from the group's distribution with its seed (cut-offs by redrawing, not by
clipping, so no spike at the bounds). A filled region is a simple cubic lattice of spacing
1.02 d_max (no initial overlap), its sites jittered by up to 1 % of the spacing, filled bottom-up; sites
that would overlap a tube, a wall or a mesh wall are skipped, and so are those inside a body drawn as a
mesh (`inside_bodies`: a tube or block the region surrounds), and with `skip_pockets` those a grain
could not reach from the domain's top (`tidem.particles.fill_pockets`). Given positions that overlap a mesh
wall by more than numerics.max_overlap are refused with a message naming the particle.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tidem.particles.fill_pockets import joined_to_top
from tidem.particles.overlaps import min_image
from tidem.scene.sizes import largest_parcel, parcel_count
from tidem.walls.mesh_geometry import inside_mesh, point_mesh_distance

POCKETS = (" and out of the pockets a grain could not reach from the domain's top (skip_pockets; a closed "
           "vessel, such as a drum, is all pocket: fill it with 'inside_mesh')")
MAX_MESH_MESSAGES = 6  # given positions inside a mesh reported one by one, per group


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


def clear_of_obstacles(sites: np.ndarray, radius: float, planes, tubes, lengths, periodic,
                       meshes=()) -> np.ndarray:
    """Mask of sites whose sphere of `radius` touches no plane, no tube and no mesh; `meshes`
    holds (vertices, triangles) pairs (exact point-triangle distances, no periodic images)."""
    ok = np.ones(len(sites), dtype=bool)
    for vertices, triangles in meshes:
        todo = np.flatnonzero(ok)
        ok[todo] = point_mesh_distance(sites[todo], vertices, triangles, within=radius) > radius * (1 - 1e-9)
    for p0, n in planes:
        ok &= (sites - np.asarray(p0)) @ np.asarray(n) > radius * (1 - 1e-9)
    for centre, axis_mask, r_tube in tubes:
        d = min_image(sites - np.asarray(centre), lengths, periodic) * np.asarray(axis_mask)
        ok &= np.linalg.norm(d, axis=1) > (r_tube + radius) * (1 - 1e-9)
    return ok


@dataclass
class Placed:
    """The particles of all groups at the start, in scene order; arrays of shape [capacity]."""

    radius: np.ndarray
    material: np.ndarray  # index into the scene's materials
    group: np.ndarray  # index into the scene's particle groups
    fixed: np.ndarray
    x0: np.ndarray  # [capacity, 3]; zeros for particles still to be poured
    v0: np.ndarray  # [capacity, 3]
    active0: np.ndarray  # False for particles still to be poured
    temperature0: np.ndarray | None  # None without [heat]
    pours: list[dict]  # one per poured group, for `tidem.particles.pour.Pourer`
    pocket_sites: dict[int, int] = field(default_factory=dict)  # group -> lattice sites skip_pockets left empty


def mesh_position_overlaps(scene, key: str, pos: np.ndarray, radius: np.ndarray, meshes) -> list[str]:
    """Messages for given positions whose sphere enters a mesh wall by more than
    numerics.max_overlap of its radius (the ratio (r - distance) / r of tidem.particles.overlaps)."""
    limit = scene.numerics.max_overlap
    out: list[str] = []
    for mesh in meshes:
        dist = point_mesh_distance(pos, mesh.vertices, mesh.triangles, within=float(radius.max()))
        ratio = (radius - dist) / radius
        bad = np.flatnonzero(ratio > limit)
        for i in bad[:MAX_MESH_MESSAGES]:
            out.append(f"{key}.positions[{i}]: overlaps {mesh.name} by {100 * ratio[i]:.0f} % of its radius at "
                       f"{np.round(pos[i], 6).tolist()} (limit numerics.max_overlap = {100 * limit:g} %); move it "
                       f"clear of the mesh (centre at least {radius[i]:.3g} m from it)"
                       + (f" ({len(bad)} particles of this group overlap it in all)" if len(bad) > 1 and i == bad[0]
                          else ""))
    return out


def inside_bodies(points: np.ndarray, mesh_geo: list, vessel: int | None, room: float) -> np.ndarray:
    """Mask of the points inside a body drawn as a mesh: a mesh with an inside (closed, or a tube open only
    at its two ends along an axis: `mesh_geometry.inside_mesh`, strict) whose bounding box is less than half
    the `room` [m^3] the points are placed in (a region's box, or the domain for given positions: a tube or
    block in the bed; a larger one is the vessel they were drawn in); `vessel`: the group's `inside_mesh`,
    never a body."""
    out = np.zeros(len(points), bool)
    for k, (vertices, triangles) in enumerate(mesh_geo):
        if k == vessel or not len(points) or np.prod(np.ptp(vertices, axis=0)) >= 0.5 * room:
            continue
        inside = inside_mesh(points, vertices, triangles, strict=True)
        if inside is not None:
            out |= inside
    return out


def _box_volume(lo, hi) -> float:
    return float(np.prod(np.asarray(hi, float) - np.asarray(lo, float)))


def place_groups(scene, planes: list[dict], tubes: list[dict], lengths, periodic,
                 meshes=()) -> tuple[Placed | None, list[str]]:
    """Sizes, positions and velocities of every particle group (given positions, a region filled
    bottom-up, or a pour), or None and the messages of the groups that cannot be placed.
    `meshes` (tidem.walls.mesh_walls.MeshWall, at t = 0): lattice sites that overlap one are skipped,
    given positions that overlap one by more than numerics.max_overlap are refused."""
    mesh_geo = [(m.vertices, m.triangles) for m in meshes]
    dom = scene.domain
    mat_names = list(scene.materials)
    radius, material, group, x0, v0, active0, pours = [], [], [], [], [], [], []
    fixed, temp0 = [], []
    pocket_sites: dict[int, int] = {}
    errors: list[str] = []
    offset = 0
    for gi, g in enumerate(scene.particles):
        rng = np.random.default_rng(g.seed)
        key = f"particles[{gi}]"
        count = parcel_count(g)  # None: fill every free lattice site of the region
        if g.region is not None:
            spacing = 1.02 * largest_parcel(g)
            sites = lattice_sites(g.region.min, g.region.max, spacing, g.lattice)
            plane_geo = [(p["p0"], p["n"]) for p in planes]
            tube_geo = [(t["c"], t["mask"], t["r"]) for t in tubes]
            sites = sites[clear_of_obstacles(sites, 0.5 * spacing, plane_geo, tube_geo, lengths, periodic, mesh_geo)]
            if g.inside_mesh is not None:
                inside = inside_mesh(sites, *mesh_geo[g.inside_mesh])
                if inside is None:
                    errors.append(f"{key}.inside_mesh: {meshes[g.inside_mesh].name} has no inside (it is neither "
                                  "closed nor open only at its two ends along an axis, like a drum); drop "
                                  "'inside_mesh' and fit 'region' inside it")
                    continue
                sites = sites[inside]
            sites = sites[~inside_bodies(sites, mesh_geo, g.inside_mesh, _box_volume(g.region.min, g.region.max))]
            if g.skip_pockets and meshes and len(sites):
                joined = joined_to_top(dom.min, lengths, periodic, spacing, meshes, sites)
                pocket_sites[gi] = int((~joined).sum())
                sites = sites[joined]
            fill_all = count is None
            if fill_all:
                count = len(sites)
            if len(sites) == 0 or len(sites) < count:
                asked = f"{count}" if g.coarse_grain == 1.0 else f"{count} parcels ({g.count} grains / k^3)"
                errors.append(
                    f"{key}: the region holds at most {len(sites)} particles of diameter {spacing / 1.02:g} m clear of "
                    f"walls, tubes and meshes{POCKETS if g.skip_pockets else ''}"
                    + ("; enlarge 'region'" if fill_all else f", but {asked} were asked for; enlarge 'region' or "
                                                             "lower 'count'")
                )
                continue
        try:
            d = g.coarse_grain * sample_diameters(g.diameter, count, rng)  # parcels of k^3 grains
        except PlacementError as exc:
            errors.append(f"{key}.diameter: {exc}")
            continue
        if g.positions is not None:
            pos = np.asarray(g.positions, float)
            vel = np.asarray(g.velocities, float) if g.velocities is not None else np.tile(g.velocity, (count, 1))
            act = np.ones(count, bool)
            found = mesh_position_overlaps(scene, key, pos, 0.5 * d, meshes)
            trapped = np.flatnonzero(inside_bodies(pos, mesh_geo, None, _box_volume(dom.min, dom.max)))
            many = f" ({len(trapped)} particles of this group lie inside one)" if len(trapped) > 1 else ""
            found += [f"{key}.positions[{i}]: {np.round(pos[i], 6).tolist()} lies inside a body drawn as a mesh (a "
                      "closed mesh, or a tube open at its ends, around it); move it out" + (many if i == trapped[0] else "")
                      for i in trapped[:MAX_MESH_MESSAGES]]
            if found:
                errors += found
                continue
        elif g.region is not None:
            # fill bottom-up; random order within each layer
            layer = np.unique(np.round(sites[:, 2], 9), return_inverse=True)[1]
            order = np.lexsort((rng.random(len(sites)), layer))[:count]
            order = order[np.argsort(spatial_key(sites[order], dom.min, 1.1 * spacing), kind="stable")]
            pos = sites[order] + rng.uniform(-0.01, 0.01, (count, 3)) * spacing
            vel = np.tile(g.velocity, (count, 1))
            act = np.ones(count, bool)
        else:
            pos = np.zeros((count, 3))
            vel = np.tile(g.velocity, (count, 1))
            act = np.zeros(count, bool)
            pours.append(dict(first=offset, count=count, region=g.pour.region, rate=g.pour.rate / g.coarse_grain**3,
                              start=g.pour.start,
                              seed=g.seed, inserted=0, key=key))
        radius.append(0.5 * d)
        material.append(np.full(count, mat_names.index(g.material), np.int32))
        group.append(np.full(count, gi, np.int32))
        fixed.append(np.full(count, g.fixed))
        if scene.heat is not None:
            temp0.append(np.full(count, g.temperature or scene.heat.initial_temperature))
        x0.append(pos)
        v0.append(vel)
        active0.append(act)
        offset += count
    if errors:
        return None, errors
    return Placed(radius=np.concatenate(radius), material=np.concatenate(material), group=np.concatenate(group),
                  fixed=np.concatenate(fixed), x0=np.concatenate(x0), v0=np.concatenate(v0),
                  active0=np.concatenate(active0), temperature0=np.concatenate(temp0) if scene.heat is not None else None,
                  pours=pours, pocket_sites=pocket_sites), []


def spatial_key(x: np.ndarray, lo, cell: float) -> np.ndarray:
    """Sort key that stores particles cell by cell in the broad phase's cell order (x, then y,
    then z): partners of a particle then sit close in memory, which makes the force loop about
    1.5x faster than a random order."""
    c = np.floor((x - np.asarray(lo)) / cell).astype(np.int64)
    c -= c.min(axis=0)
    n = c.max(axis=0) + 1
    return (c[:, 0] * n[1] + c[:, 1]) * n[2] + c[:, 2]
