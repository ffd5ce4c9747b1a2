"""Sphere-triangle contacts with mesh walls: detection with feature suppression, per-contact
history, and the same contact law and wall heat transfer as planes and tubes.

Triangles live in fields (`tri_v` [T, 3] vertices now, `tri_mesh` [T] the mesh each belongs to);
a mesh that crosses a periodic boundary also holds shifted copies of the triangles near it, so
that a surface continues seamlessly across the boundary (`tidem.walls.mesh_bins`).

Broad phase. At each neighbour build every particle lists the triangles within r_i + `reach`
(skin plus the gas lens' reach) of its centre, `mc_tri[i, :mc_n[i]]`, from the triangles binned
into the neighbour grid's cells (`mbin_start`, `mbin_tri`; binned on the host, `tidem.walls.mesh_bins`).
Until the next build no particle moves more than half the skin and (`tidem.sim.solver`) no mesh more
than half the skin, so no unlisted triangle can touch. More than `M` triangles in reach count in
overflow[3] (an error for the run).

Narrow phase. The closest point of triangle (a, b, c) to the centre x is found by the region test
of Ericson (Real-Time Collision Detection, 2005, sec. 5.1.5): in a vertex region the point is that
vertex, in an edge region the projection onto that edge, else the projection onto the face. The
contact of a triangle within reach is dropped when its closest point p lies on (within `on_tol`
of) another listed triangle: that one is then at least as close, and the closer one stays (of two
as close, the face before the edge before the vertex, then the one listed first). On a flat or
convex surface made of many triangles a sphere then feels one contact, from the face under it,
and nothing changes where it crosses an edge or passes a vertex (the edge and vertex contacts of
the triangles around lie on a nearer one); at a concave edge each face's closest point lies on
its own face only, so both act. A face contact's normal is the face normal (exact for a plane
made of triangles: the same bits as the analytic plane), an edge or vertex contact's the line
from x to p. Flat patches: where every triangle a particle lists lies in one plane patch (joined
by flat shared edges, `tidem.walls.mesh_geometry.flat_patches`) and x lies over the face of one of them,
that face is the nearest point of the patch and every other listed triangle's contact would be
suppressed, so the particle touches that face alone without testing the others; it tries first
the triangle whose face it was over last (a floor of fine triangles costs about one nearest-point
test a step, `benchmarks/README.md`).

History. Each particle has `WM` slots (mh_id: mesh index or -1, mh_n: the contact normal,
mh_ft / mh_mr / mh_dmax: tangential spring, rolling spring, largest overlap). A contact takes the
free-this-step slot of the same mesh whose normal is closest to its own (cosine above MATCH),
else a new slot: the spring follows the contact, not the triangle, as it slides onto the next
triangle of a smooth surface, and the contact law projects it onto the new tangent plane
(`contact_laws.rotate_into_plane`). Slots no contact used this step are freed.

Wall velocity at the contact point p: u = v_m + Omega_m x (p - c_m(t)) + the surface velocity's
part in the tangent plane (`mesh_motion`: translation v, angular velocity Omega, centre at t = 0
c0, surface velocity; c_m(t) = c0 + v t).

Heat (a mesh with a fixed temperature, surf_T[n_surf + m] > 0): a touching contact conducts by
the wall contact laws of `kernels/heat.py` (spot and Schluender gas gap, radiation), one within
the gas lens (`fluid_layer` r_i) that does not touch by the gas lens, exactly as a plane wall
(`kernels/contact.py`); the heat flow is booked in surf_rate[n_surf + m].
"""

from types import SimpleNamespace

import taichi as ti

from .contact_laws import make_contact_response, make_slot_response
from .heat import pfp_conductance, wall_conductance, wall_radiation

FACE, EDGE, VERTEX = 0, 1, 2
MATCH = 0.7  # cosine between a contact's normal and a slot's above which the slot carries on (45 deg)


@ti.func
def closest_on_triangle(x, a, b, c):
    """Closest point of triangle (a, b, c) to x and its feature (FACE, EDGE, VERTEX); Ericson's region
    test (module docstring). Degenerate triangles are refused when a mesh is read."""
    ab = b - a
    ac = c - a
    ap = x - a
    d1 = ab.dot(ap)
    d2 = ac.dot(ap)
    p = a
    feature = VERTEX
    done = False
    if d1 <= 0.0 and d2 <= 0.0:
        done = True
    bp = x - b
    d3 = ab.dot(bp)
    d4 = ac.dot(bp)
    if not done and d3 >= 0.0 and d4 <= d3:
        p, done = b, True
    vc = d1 * d4 - d3 * d2
    if not done and vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        p, feature, done = a + d1 / (d1 - d3) * ab, EDGE, True
    cp = x - c
    d5 = ab.dot(cp)
    d6 = ac.dot(cp)
    if not done and d6 >= 0.0 and d5 <= d6:
        p, done = c, True
    vb = d5 * d2 - d1 * d6
    if not done and vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        p, feature, done = a + d2 / (d2 - d6) * ac, EDGE, True
    va = d3 * d6 - d5 * d4
    if not done and va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        p, feature, done = b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b), EDGE, True
    if not done:
        inv = 1.0 / (va + vb + vc)
        p, feature = a + (vb * inv) * ab + (vc * inv) * ac, FACE
    return p, feature


def make_mesh_contacts(S, law: int, rolling: bool, n_surf: int, M: int, WM: int, reach: float, on_tol: float,
                       heat: bool, fluid_layer: float, radiation: bool, grain_scale: float, grid_funcs, radius_of,
                       blocks: bool = False):
    """Return a namespace of Taichi funcs: `visit(i, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, force,
    torque, heat_in, worst, touching, blk)`, which adds particle i's contacts with every mesh to the sums
    handed in (force, torque, heat flow into i [W], largest overlap / r_i, contacts) and returns them, the
    heat flow into a heated mesh booked in block blk's row with `blocks` (surf_rate_block, added up in
    block order: `kernels/surface_contact.py`), else atomically in surf_rate;
    `list_candidates(i)` (the broad phase, run on each particle by the neighbour build). `n_surf`: planes
    and tubes before the meshes in the surface tables (S.ps, surf_T, surf_rate); `M`, `WM`: candidates and
    contact slots per particle; `reach`: how far beyond its radius a particle lists triangles (skin
    and gas lens); `on_tol`: the distance within which a point lies on a triangle; `grid_funcs`:
    (cell_coord, cell_id) of the neighbour grid; `radius_of`: `kernels/sizes.py`."""
    hysteretic = law == 2
    slot_touch = make_slot_response(S, "mh_", make_contact_response(law, rolling), rolling, hysteretic)
    pfp = heat and fluid_layer > 0.0
    cell_coord, cell_id = grid_funcs
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    cg = float(grain_scale)
    tol2 = on_tol * on_tol

    @ti.func
    def book(s, flow, blk):
        """Heat flow [W] into heated mesh s (its index among the surfaces)."""
        if ti.static(blocks):
            S.surf_rate_block[blk, s] += flow
        else:
            ti.atomic_add(S.surf_rate[s], flow)

    @ti.func
    def triangle(k):
        """The vertices of triangle k now."""
        return S.tri_v[k, 0], S.tri_v[k, 1], S.tri_v[k, 2]

    @ti.func
    def nearest(x, k):
        """Closest point of listed triangle k to x, its feature and the squared distance."""
        a, b, c = triangle(k)
        p, feature = closest_on_triangle(x, a, b, c)
        return p, feature, (p - x).norm_sqr()

    @ti.func
    def suppressed(i, q, p, feature, d2, cnt, r, d2s, features):
        """Whether contact q of particle i (closest point p, `feature`, squared distance d2) repeats another:
        p lies on another listed triangle, which is then at least as close; the closer one stays, and of
        two as close (within 2 on_tol r of d2: two triangles may round one point differently) the one of
        the smaller feature number, then the one listed first (module docstring). `d2s`, `features`: the
        listed triangles' squared distances and features, from `visit`."""
        drop = False
        tie = 2.0 * on_tol * r
        for o in range(cnt):
            if not drop and o != q:
                d2_o, f_o = d2s[o], features[o]
                if d2_o < d2 - tie or (d2_o <= d2 + tie and (f_o < feature or (f_o == feature and o < q))):
                    _pp, _f, e2 = nearest(p, S.mc_tri[i, o])
                    drop = e2 < tol2
        return drop

    @ti.func
    def wall_velocity(m, p, nrm, t):
        """Velocity of mesh m at point p: rigid motion plus the tangential part of its surface velocity."""
        vel = S.mesh_motion[m, 0]
        omega = S.mesh_motion[m, 1]
        centre = S.mesh_motion[m, 2] + vel * t
        belt = S.mesh_motion[m, 3]
        return vel + omega.cross(p - centre) + belt - belt.dot(nrm) * nrm

    @ti.func
    def slot_for(i, m, nrm, used):
        """The history slot of contact (mesh m, normal nrm): the slot of mesh m not yet used this step
        whose normal is closest (cosine above MATCH), else a free one, else one that no contact has
        used this step (a contact of the last step that has ended, or that this step has yet to
        reach), with zeroed history; -1 if every slot holds a contact of this step."""
        best = -1
        best_cos = MATCH
        for q in range(WM):
            if not (used >> q) & 1 and S.mh_id[i, q] == m:
                cos = S.mh_n[i, q].dot(nrm)
                if cos > best_cos:
                    best, best_cos = q, cos
        if best < 0:
            for q in range(WM):
                if best < 0 and not (used >> q) & 1 and S.mh_id[i, q] < 0:
                    best = q
            for q in range(WM):
                if best < 0 and not (used >> q) & 1:
                    best = q
            if best >= 0:
                S.mh_id[i, best] = m
                S.mh_ft[i, best] = zero3
                if ti.static(rolling):
                    S.mh_mr[i, best] = zero3
                if ti.static(hysteretic):
                    S.mh_dmax[i, best] = 0.0
        return best

    @ti.func
    def touch(i, k, p, feature, d2, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, used, force, torque, heat_in, worst,
              touching, blk):
        """Contact of particle i with listed triangle k (closest point p, `feature`, squared distance d2 within
        reach): the contact law and its history slot if it touches, else the gas lens' conduction; added to
        the sums, `used` (bit q: slot q holds a contact of this step) updated."""
        m = S.tri_mesh[k]
        nrm = zero3
        dist = 0.0
        if feature == FACE:
            a, b, c = triangle(k)
            face = (b - a).cross(c - a).normalized()
            side = (xi - a).dot(face)
            dist = ti.abs(side)
            nrm = -face
            if side < 0.0:
                nrm = face
        else:
            dist = ti.sqrt(d2)
            nrm = (p - xi) / dist
        delta = ri - dist
        s = n_surf + m
        params = S.ps[mat_i, s]
        if delta > 0.0:
            slot = slot_for(i, m, nrm, used)
            if slot < 0:
                ti.atomic_add(S.overflow[1], 1)
            else:
                used |= 1 << slot
                S.mh_n[i, slot] = nrm
                u = wall_velocity(m, xi + dist * nrm, nrm, t)
                f, t_i = slot_touch(i, slot, nrm, delta, u, vi, wi, mi, ri, params, dt)
                force += f
                torque += t_i
                if ti.static(heat):
                    if conduct and S.surf_T[s] > 0.0:
                        flow = wall_conductance(params, ri, delta, cg) * (S.surf_T[s] - S.T[i])
                        if ti.static(radiation):
                            flow += wall_radiation(params, ri, S.surf_T[s], S.T[i])
                        heat_in += flow
                        book(s, flow, blk)
                if diag:
                    worst = ti.max(worst, delta / ri)
                    touching += 1
        else:
            if ti.static(pfp):
                if conduct and S.surf_T[s] > 0.0:
                    flow = cg * pfp_conductance(params, ri, -delta / cg, fluid_layer * ri / cg) * (
                        S.surf_T[s] - S.T[i])
                    heat_in += flow
                    book(s, flow, blk)
        return used, force, torque, heat_in, worst, touching

    @ti.func
    def visit(i, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, force, torque, heat_in, worst, touching, blk):
        """Particle i's mesh contacts (and gas-lens conduction to heated meshes), added to the sums. A particle
        whose listed triangles all lie in one flat patch (S.mc_flat[i] >= 0, `list_candidates`) and whose
        centre lies over the face of one of them touches that face only (module docstring: the others'
        contacts would all be suppressed); it tries first the triangle S.mc_flat[i] it was over last."""
        used = 0  # bit q: slot q holds a contact of this step
        cnt = S.mc_n[i]
        if cnt > 0:  # (a particle with no triangle in reach holds no slot: `list_candidates`)
            near = ri
            if ti.static(pfp):
                near = ri * (1.0 + fluid_layer)
            near2 = near * near
            found = False
            k = S.mc_flat[i]
            if k >= 0:
                for q in range(-1, cnt):  # the triangle of the last step first, then the listed ones
                    if q >= 0:
                        k = S.mc_tri[i, q]
                    p, feature, d2 = nearest(xi, k)
                    if feature == FACE:
                        found = True
                        S.mc_flat[i] = k
                        if d2 < near2:
                            used, force, torque, heat_in, worst, touching = touch(
                                i, k, p, feature, d2, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, used, force,
                                torque, heat_in, worst, touching, blk)
                        break
            if not found:
                d2s = ti.Vector([0.0] * M)  # each listed triangle's squared distance and feature, for `suppressed`
                features = ti.Vector([0] * M)
                hits = 0
                for o in range(cnt):
                    _p, f_o, d2_o = nearest(xi, S.mc_tri[i, o])
                    features[o] = f_o
                    d2s[o] = d2_o
                    if d2_o < near2:
                        hits += 1
                for o in range(cnt):
                    if d2s[o] < near2:
                        k = S.mc_tri[i, o]
                        p, feature, d2 = nearest(xi, k)
                        if hits == 1 or not suppressed(i, o, p, feature, d2, cnt, ri, d2s, features):
                            used, force, torque, heat_in, worst, touching = touch(
                                i, k, p, feature, d2, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, used, force,
                                torque, heat_in, worst, touching, blk)
            for slot in range(WM):
                if not (used >> slot) & 1:
                    S.mh_id[i, slot] = -1
        return force, torque, heat_in, worst, touching

    @ti.func
    def list_candidates(i):
        """mc_tri / mc_n: the triangles within r_i + reach of particle i, if active (the broad phase, run on
        each particle by the neighbour build); mc_flat: the first of them where they all lie in one flat
        patch (tri_patch), else -1."""
        if S.active[i]:
            x = S.x[i]
            r = radius_of(i) + reach
            c = cell_id(cell_coord(x))
            cnt = 0
            patch = -1
            flat = -1  # a listed triangle where all lie in one flat patch (the first one's), else -1
            for e in range(S.mbin_start[c], S.mbin_start[c + 1]):
                k = S.mbin_tri[e]
                _p, _f, d2 = nearest(x, k)
                if d2 < r * r:
                    if cnt < M:
                        S.mc_tri[i, cnt] = k
                    own = S.tri_patch[k]
                    if cnt == 0:
                        patch, flat = own, k
                    if own != patch or own < 0:
                        patch = -2
                    cnt += 1
            if cnt > M:
                ti.atomic_max(S.overflow[3], cnt)
            S.mc_n[i] = ti.min(cnt, M)
            S.mc_flat[i] = ti.select(patch >= 0, flat, -1)
            if cnt == 0:  # out of every mesh's reach until the next build: no contact holds a slot
                for q in range(WM):
                    S.mh_id[i, q] = -1

    return SimpleNamespace(visit=visit, list_candidates=list_candidates)


def make_mesh_mover(S, motions: list[tuple]):
    """A kernel move(t) that puts every triangle of a moving mesh where it is at time t:
    x = c0 + s + R(theta) (x0 - c0) + shift (Rodrigues' rotation about the unit axis; `shift`:
    the periodic image's offset), theta = omega t and s = v t for a constant motion, compiled in;
    for a mesh whose motion follows a schedule theta and s are the host's (S.mesh_pose[m] = (theta,
    s), the schedules' integrals, `tidem.sim.conditions`). `motions`: per mesh (moving, c0, axis,
    omega, v, scheduled), constants."""
    moving = [mo[0] for mo in motions]
    scheduled = [mo[5] for mo in motions]

    @ti.func
    def place(k, t, m: ti.template()):
        _moving, c0, axis, omega, vel, _scheduled = motions[m]
        c = ti.Vector(c0)
        a = ti.Vector(axis)
        th = omega * t
        offset = ti.Vector(vel) * t
        if ti.static(scheduled[m]):
            pose = S.mesh_pose[m]
            th = pose[0]
            offset = ti.Vector([pose[1], pose[2], pose[3]])
        cs, sn = ti.cos(th), ti.sin(th)
        for j in ti.static(range(3)):
            r = S.tri_rest[k, j] - c
            rot = r * cs + a.cross(r) * sn + a * a.dot(r) * (1.0 - cs)
            S.tri_v[k, j] = c + offset + rot + S.tri_shift[k]

    @ti.kernel
    def move(t: float):
        for k in range(S.tri_mesh.shape[0]):
            m = S.tri_mesh[k]
            for mm in ti.static(range(len(motions))):
                if ti.static(moving[mm]):
                    if m == mm:
                        place(k, t, mm)

    return move
