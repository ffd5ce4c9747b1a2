"""Contacts with the analytic surfaces: plane walls (box sides, `[[walls]]`, the outlet plate) and
tubes (infinite cylinders along x or y), with the same contact laws and wall heat transfer as every
surface (`kernels/contact_laws.py`, `kernels/heat.py`).

Walls are planes p(t) = p0 + u (t - t0) clipped to [t0, t1] (a moving bottom plate is a plane with a
velocity); tubes are infinite cylinders along x or y (`tube_mask` zeroes the axis component). Their
geometry is constant (`tidem.walls.surfaces`), compiled into the kernel: an axis-aligned wall costs one
subtraction, a tube no product along its axis. Wall and tube contacts keep their history in a few
slots per particle keyed by the surface index (`wmask` has bit s set while surface s holds a slot,
so particles away from every wall skip the search); a particle that touches more surfaces than it
has slots is counted in `overflow[1]` (an error for the run). With `cull`, a particle skips the
static surfaces that were out of reach at the last neighbour build (`mark_near`).

With heat, a surface with a temperature conducts to a touching particle by the wall contact laws
(`kernels/heat.py`, Schluender's gas gap, radiation), and to one within the gas lens that does not
touch it by the lens; the heat flow is booked per surface in surf_rate and, around a tube, per angle
bin of the contact point (omega = atan2(side, up), 0 = top, 180 deg = bottom) in tube_bin_rate, and the
shares of a tube's flow through the solid contact spots and through the gas lens in tube_route_rate; a
heated foil's own temperature (per angle bin of a tube, one per wall) takes the place of a fixed one.
With `blocks` (the CPU's slab passes, `kernels/contact.py`) each block of slabs books its particles'
flows in rows of its own (surf_rate_block, tube_bin_block: one thread a block, each in the block's
particle order; the mesh pass books the meshes' flows likewise by blocks of particles) and the pass
adds the blocks up in block order (`sum_blocks`): the same sums on any thread count, so a heated foil,
whose temperature follows them, keeps float64 runs bit-reproducible. Without (a GPU), the flows are
atomic adds to surf_rate and tube_bin_rate.
"""

from types import SimpleNamespace

import taichi as ti

from .contact_laws import make_slot_response
from .heat import pfp_conductance, wall_gap_conductance, wall_radiation, wall_spot_conductance


def make_surface_contacts(S, planes: list[dict], tubes: list[dict], W: int, respond, hysteretic: bool, rolling: bool,
                          s_one, heat: bool, fluid_layer: float, angle_bins: int, radiation: bool, foil: bool,
                          wall_foil: bool, cull: int, surface_reach: float, grain_scale: float, min_image, radius_of,
                          blocks: int = 0):
    """Return a namespace of Taichi funcs: `visit(i, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, force,
    torque, heat_in, worst, touching, blk)`, which adds particle i's contacts with every plane and tube to
    the sums it is handed and returns them, booking its heat flows in block blk's rows where `blocks` (the
    number of rows) is given; `clear_flows()` and `sum_blocks()`, which zero the flows (those rows) before a pass
    and add the rows up into surf_rate and tube_bin_rate after it; `mark_near(i)` (None without `cull`).
    `respond`: the contact law (`contact_laws.make_contact_response`); `s_one`: each surface's material-surface parameter
    vector where all particles are of one material (constants of the kernel), else None (S.ps);
    `min_image`, `radius_of`: `kernels/geometry.py`, `kernels/sizes.py`."""
    n_planes = len(planes)
    scheduled = [p.get("speed_schedule") is not None for p in planes]  # the host sets plane_shift, plane_u
    moving = [any(p["vel"]) or sched for p, sched in zip(planes, scheduled)]
    n_tubes = len(tubes)  # (a Python int: Taichi's AST transformer warns of len() inside a func)
    n_surf = n_planes + n_tubes
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    cg = float(grain_scale)
    pfp = heat and fluid_layer > 0.0
    single = s_one is not None
    slot_touch = make_slot_response(S, "w", respond, rolling, hysteretic)

    @ti.func
    def lens(p, r_eff, gap, delta_f):
        """The gas-lens conductance of a parcel's k grains (`kernels/contact.py`)."""
        return pfp_conductance(p, r_eff, gap / cg, delta_f / cg)

    @ti.func
    def surface_params(mat_i, s: ti.template()):
        """The material-surface parameter vector of i and surface s, as `pair_params`."""
        if ti.static(single):
            return ti.Vector(s_one[s])
        else:
            return S.ps[mat_i, s]

    @ti.func
    def along(v, w: ti.template()):
        """v . w for a constant w, with the products by its zero components left out (the compiler may
        not drop them itself: 0 x NaN is NaN)."""
        out = 0.0
        for a in ti.static(range(3)):
            if ti.static(w[a] != 0.0):
                out += v[a] * w[a]
        return out

    @ti.func
    def surface_contact(i, s: ti.template(), t):
        """Overlap, unit normal (particle -> surface) and surface velocity for surface s. The surfaces'
        geometry is constant (`planes`, `tubes`), compiled into the kernel: an axis-aligned wall costs
        one subtraction, a tube no product along its axis."""
        xi = S.x[i]
        r = radius_of(i)
        delta = -1.0
        n = ti.Vector([0.0, 0.0, 1.0])
        u = zero3
        if ti.static(s < n_planes):
            t0, t1 = planes[s]["t"]
            p = ti.Vector(planes[s]["p0"])
            if ti.static(scheduled[s]):
                p += S.plane_shift[s]
                u = S.plane_u[s]
            elif ti.static(moving[s]):
                tc = ti.min(ti.max(t, t0), t1)
                p += ti.Vector(planes[s]["vel"]) * (tc - t0)
                if t > t0 and t < t1:
                    u = ti.Vector(planes[s]["vel"])
            dist = along(xi - p, planes[s]["n"])
            if dist > -r:
                delta = r - dist
                n = -ti.Vector(planes[s]["n"])
        else:
            d = min_image(xi - ti.Vector(tubes[s - n_planes]["c"]))
            for a in ti.static(range(3)):
                if ti.static(tubes[s - n_planes]["mask"][a] == 0.0):
                    d[a] = 0.0
            dist = d.norm()
            if dist > 0.0:
                delta = r + tubes[s - n_planes]["r"] - dist
                n = -d / dist
        return delta, n, u

    @ti.func
    def tube_bin(s: ti.template(), nrm):
        """Angle bin of the contact point on tube s (0 for planes and without angle bins)."""
        b = 0
        if ti.static(angle_bins > 0 and s >= n_planes):
            off = -nrm
            omega = ti.atan2(off.dot(S.tube_side[s - n_planes]), off[2])
            if omega < 0.0:
                omega += 2.0 * 3.141592653589793
            b = ti.min(ti.cast(omega / (2.0 * 3.141592653589793) * angle_bins, ti.i32), angle_bins - 1)
        return b

    @ti.func
    def wall_temperature(s: ti.template(), b):
        """The surface's fixed temperature, or a heated foil's temperature in angle bin b."""
        t_wall = S.surf_T[s]
        if ti.static(foil and s >= n_planes):
            if S.tube_foil[s - n_planes][0] > 0.0:
                t_wall = S.tube_bin_T[s - n_planes, b]
        if ti.static(wall_foil and s < n_planes):
            if S.plane_foil[s][0] > 0.0:
                t_wall = S.plane_foil_T[s]
        return t_wall

    @ti.func
    def surface_heat(s: ti.template(), b, flow, blk):
        """Book a particle's heat flow from surface s, and from a tube by angle bin b of the contact point:
        in block blk's rows with `blocks` (a plain add: one thread a block), else atomically."""
        if ti.static(blocks):
            S.surf_rate_block[blk, s] += flow
            if ti.static(angle_bins > 0 and s >= n_planes):
                S.tube_bin_block[blk, (s - n_planes) * angle_bins + b] += flow
        else:
            ti.atomic_add(S.surf_rate[s], flow)
            if ti.static(angle_bins > 0 and s >= n_planes):
                ti.atomic_add(S.tube_bin_rate[s - n_planes, b], flow)

    @ti.func
    def route_heat(s: ti.template(), route: ti.template(), flow, blk):
        """Book the share of a particle's heat flow from tube s that went by `route` (0 the solid contact
        spot, 1 the gas lens of a particle that does not touch), as `surface_heat` books the whole."""
        if ti.static(angle_bins > 0 and s >= n_planes):
            if ti.static(blocks):
                S.tube_route_block[blk, (s - n_planes) * 2 + route] += flow
            else:
                ti.atomic_add(S.tube_route_rate[s - n_planes, route], flow)

    @ti.func
    def clear_flows():
        """Zero the surfaces' heat flows before a pass that conducts (serial: a few hundred items at most):
        with `blocks` the blocks' rows, the meshes' columns (`kernels/mesh_contact.py`) included, which
        `sum_blocks` adds up into surf_rate and tube_bin_rate after the pass; else those themselves."""
        if ti.static(heat and blocks):
            ti.loop_config(serialize=True)
            for blk, s in ti.ndrange(blocks, S.surf_rate_block.shape[1]):
                S.surf_rate_block[blk, s] = 0.0
            if ti.static(angle_bins > 0):
                ti.loop_config(serialize=True)
                for blk, kb in ti.ndrange(blocks, n_tubes * angle_bins):
                    S.tube_bin_block[blk, kb] = 0.0
                ti.loop_config(serialize=True)
                for blk, kr in ti.ndrange(blocks, n_tubes * 2):
                    S.tube_route_block[blk, kr] = 0.0
        elif ti.static(heat):
            ti.loop_config(serialize=True)
            for s in range(S.surf_rate.shape[0]):
                S.surf_rate[s] = 0.0
            if ti.static(angle_bins > 0):
                ti.loop_config(serialize=True)
                for k, b in ti.ndrange(n_tubes, angle_bins):
                    S.tube_bin_rate[k, b] = 0.0
                ti.loop_config(serialize=True)
                for k, r in ti.ndrange(n_tubes, 2):
                    S.tube_route_rate[k, r] = 0.0

    @ti.func
    def sum_blocks():
        """surf_rate and tube_bin_rate of the planes, tubes and meshes: the blocks' rows added up in block order."""
        if ti.static(heat and blocks):
            ti.loop_config(serialize=True)
            for s in range(S.surf_rate_block.shape[1]):
                total = 0.0
                for blk in range(blocks):
                    total += S.surf_rate_block[blk, s]
                S.surf_rate[s] = total
            if ti.static(angle_bins > 0):
                ti.loop_config(serialize=True)
                for k, b in ti.ndrange(n_tubes, angle_bins):
                    total = 0.0
                    for blk in range(blocks):
                        total += S.tube_bin_block[blk, k * angle_bins + b]
                    S.tube_bin_rate[k, b] = total
                ti.loop_config(serialize=True)
                for k, r in ti.ndrange(n_tubes, 2):
                    total = 0.0
                    for blk in range(blocks):
                        total += S.tube_route_block[blk, k * 2 + r]
                    S.tube_route_rate[k, r] = total

    @ti.func
    def visit(i, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag, force, torque, heat_in, worst, touching, blk):
        """Particle i's contacts with the planes and tubes, added to the sums handed in (module docstring)."""
        held = S.wmask[i]  # bit s set: surface s has a history slot
        nearby = S.near[i] if ti.static(cull) else 0
        for s in ti.static(range(n_surf)):
            near = 1
            if ti.static(cull >> s & 1):
                near = (nearby >> s) & 1  # surfaces out of reach at the last neighbour build
            if near:
                delta, nrm, u = surface_contact(i, s, t)
                slot = -1
                if (held >> s) & 1:
                    for q in range(W):
                        if S.wid[i, q] == s:
                            slot = q
                if delta > 0.0:
                    if slot < 0:
                        for q in range(W):
                            if slot < 0 and S.wid[i, q] < 0:
                                slot = q
                                S.wid[i, q] = s
                                held |= 1 << s
                                S.wft[i, q] = zero3
                                if ti.static(rolling):
                                    S.wmr[i, q] = zero3
                                if ti.static(hysteretic):
                                    S.wdmax[i, q] = 0.0
                    if slot < 0:
                        ti.atomic_add(S.overflow[1], 1)
                    else:
                        f, t_i = slot_touch(i, slot, nrm, delta, u, vi, wi, mi, ri, surface_params(mat_i, s), dt)
                        force += f
                        torque += t_i
                        if ti.static(heat):
                            if conduct and S.surf_T[s] > 0.0:
                                b = tube_bin(s, nrm)
                                t_wall = wall_temperature(s, b)
                                params = surface_params(mat_i, s)
                                spot = wall_spot_conductance(params, ri, delta, cg)
                                flow = (spot + wall_gap_conductance(params, ri, cg)) * (t_wall - S.T[i])
                                if ti.static(radiation):
                                    flow += wall_radiation(params, ri, t_wall, S.T[i])
                                heat_in += flow
                                surface_heat(s, b, flow, blk)
                                route_heat(s, 0, spot * (t_wall - S.T[i]), blk)
                        if diag:
                            worst = ti.max(worst, delta / ri)
                            touching += 1
                else:
                    if slot >= 0:
                        S.wid[i, slot] = -1
                        held &= ~(1 << s)
                    if ti.static(pfp):
                        if conduct and -delta < fluid_layer * ri and S.surf_T[s] > 0.0:
                            b = tube_bin(s, nrm)
                            flow = cg * lens(surface_params(mat_i, s), ri, -delta, fluid_layer * ri) * (
                                wall_temperature(s, b) - S.T[i])
                            heat_in += flow
                            surface_heat(s, b, flow, blk)
                            route_heat(s, 1, flow, blk)
        S.wmask[i] = held
        return force, torque, heat_in, worst, touching

    @ti.func
    def mark_near_surfaces(i):
        """near[i] bit s: static surface s is within reach of particle i (run on each particle by the
        neighbour build, in its kernel; until the next one no particle moves more than half the skin)."""
        if S.active[i]:
            bits = 0
            for s in ti.static(range(n_surf)):
                if ti.static(cull >> s & 1):
                    delta, _n, _u = surface_contact(i, s, 0.0)
                    if -delta < surface_reach:
                        bits |= 1 << s
            S.near[i] = bits

    return SimpleNamespace(visit=visit, mark_near=mark_near_surfaces if cull else None, n_surf=n_surf,
                           clear_flows=clear_flows, sum_blocks=sum_blocks)
