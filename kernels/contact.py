"""Contact forces and torques: particle-particle (from the Verlet list), plane walls and tubes.

Each contact is evaluated once, by its lower-index particle, in two kernels with one thread
per particle and no atomic sums (so runs are bit-reproducible whatever the thread count):
1. `own_forces`: for each listed partner j > i inside contact range, the contact law
   (`contact_laws.make_contact_response`) updates the pair's history in i's row and gives
   the force F on i and the rolling moment M on i; both are also written into j's slot for i
   (the mirror slot `src[i, k]`, found at the neighbour build), whose history arrays the
   pair does not otherwise use. A partner j > i out of range has its history cleared. Walls
   and tubes are done here too.
   For a touching pair own_forces also stamps j's `src` slot for i (-1 from the neighbour build
   on, unused there) with its step number `stamp`.
2. `partner_forces`: for each listed partner j < i whose slot carries this step's stamp, i reads
   its own slot: force -F, torque -r_i n x F - M (n the unit normal from i to j; Newton's third
   law for the force, and the contact point r_i n on i's side). It takes the positions from
   `xf`, where own_forces copied them, so the kick can run it while other particles already
   move on (`kernels/integrate.py`), and it computes no geometry for pairs apart.
With heat, own_forces also evaluates each pair's conduction (contact spot and gas lens) once
and writes minus the heat flow into i to `qpair[j, mirror]`, which partner_forces adds for
every partner j < i. The overlap check and the contact count are computed in both passes,
each for its own side of the row. Against the full list evaluated twice (one law per listed pair
and side) this makes the force step 1.3x faster on the peer benchmark bed.

With numerics.precision = 'mixed' the row fields (ft, mr, dmax, qpair) are float32: what the loop
reads from them is widened to float64 (`wide`), and the force, rolling moment and heat flow handed
to the partner are rounded to float32 once (`handed`) and used by both partners (the owner's torque
then takes the handed force), so momentum and heat are still conserved to the float64 sums' rounding.

Walls are planes p(t) = p0 + u (t - t0) clipped to [t0, t1] (a moving bottom plate is
a plane with a velocity); tubes are infinite cylinders along x or y (`tube_mask` zeroes the axis component). Wall and tube contacts
keep their history in a few slots per particle keyed by the surface index (`wmask` has bit s
set while surface s holds a slot, so particles away from every wall skip the search); a particle that
touches more surfaces than it has slots is counted in `overflow[1]` (an error for the run).

Gravity is added here: f_i = m_i g + sum of contact forces. `ovl[i]` receives the largest
overlap of particle i relative to the smaller radius of the pair, `ncontact[i]` its number of
contacts (coordination number), in the force passes that the host will read them after (`diag`
= 1: health checks, time series, snapshots; with contact timing in every pass): the division
per contact and the two stores per particle are 6 % of a step of the peer bed.
"""

from types import SimpleNamespace

import taichi as ti

from .contact_laws import make_contact_response
from .geometry import make_geometry
from .heat import pfp_conductance, spot_conductance, wall_conductance, wall_radiation


def make_force_kernel(grid, law: int, rolling: bool, n_planes: int, n_tubes: int, W: int, gravity, S,
                      track_contact_time: bool = False, single_material: bool = False, heat: bool = False,
                      angle_bins: int = 0, fluid_layer: float = 0.0, pairs: bool = True,
                      radiation: bool = False, foil: bool = False, wall_foil: bool = False, cull: int = 0,
                      surface_reach: float = 0.0, grain_scale: float = 1.0):
    """Return a namespace of the two passes: kernels `own(n, t, dt, stamp, conduct, diag)` and `partner(n, t)`
    (None without pairs); and as Taichi funcs, for kernels that fuse them with the rest of the step
    (`kernels/integrate.py`), `own_pass(n, t, dt, stamp, conduct, diag)`, the body of `own`, and
    `gather(i, t)`, the partner pass for one particle. With heat, `conduct` = m > 0 evaluates the
    conduction and books the heat of m steps (q[i] = m x the heat flow: heat.conduction_interval = m
    evaluates it every m-th step, an explicit Euler step of m dt), and `conduct` = 0 skips it (q[i] =
    0; the surfaces' heat flows of the last evaluation hold); S.conduct[None] tells the partner pass
    and the kick. `diag` = 1 also fills ovl and ncontact (module docstring; S.diag[None] tells the partner pass).
    `single_material` loads the pair parameters once per particle; `heat` adds conduction
    (kernels/heat.py) to the same loop, writing q[i] [W] and the heat flow into each surface with a
    temperature, surf_rate[s] [W] (into the bed > 0), and with `angle_bins` the heat flow from each tube
    by angle omega of the contact point from the top of the tube, tube_bin_rate[k, b] (omega =
    atan2(side, up), 0 = top, 180 deg = bottom). `fluid_layer` > 0 adds particle-fluid-particle
    conduction between neighbours closer than fluid_layer * min(r_i, r_j), touching or not, and between
    a surface with a temperature and a particle within fluid_layer * r_i of it that does not touch it
    (R* = r_i; a touching one conducts by Schluender's coefficient instead). `pairs = False`
    (contact.model = 'none') skips the neighbour list: gravity and walls only. `radiation` adds grey
    radiation from a heated surface to the particles touching it; with `foil`, a tube with
    tube_foil[k][0] > 0 (a heat flux) has the temperature of its foil in the angle bin of the contact
    point, tube_bin_T[k, b]; with `wall_foil`, a plane with plane_foil[s][0] > 0 has its foil's
    temperature plane_foil_T[s]. `cull` (bit s: surface s does not move) lets each particle skip the
    static surfaces farther than `surface_reach` (skin plus the conduction reach) at the last neighbour
    build, as marked in S.near by the Taichi func `mark_near(n)` (None without culling; the neighbour
    build runs it); a particle far from every wall and tube then costs no surface evaluation at all.
    `grain_scale` k > 1: every particle is a parcel of k^3 grains (one k per scene with heat) and
    conducts as those grains do (kernels/heat.py)."""
    pfp = heat and fluid_layer > 0.0
    min_image, _wrap, _cc, _cid = make_geometry(grid)
    respond = make_contact_response(law, rolling)
    hysteretic = law == 2
    g = ti.Vector(list(gravity))
    n_surf = n_planes + n_tubes
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    cg = float(grain_scale)
    fp = ti.lang.impl.current_cfg().default_fp
    hist = S.ft.dtype  # float32 with numerics.precision = 'mixed' (tidem.state), else fp

    @ti.func
    def wide(v):
        """A value read from the rows, in the kernels' float type."""
        return ti.cast(v, fp)

    @ti.func
    def handed(v):
        """v rounded to the rows' float type, as the partner will read it (float32 with
        numerics.precision = 'mixed'): both partners then add the very same force, moment and heat
        flow, so that momentum and heat stay conserved to the float64 sums' rounding."""
        out = v
        if ti.static(hist != fp):
            out = ti.cast(v, hist)
        return out

    @ti.func
    def lens(p, r_eff, gap, delta_f):
        """The gas-lens conductance; a parcel's is that of its grains' k lenses (k H(R*/k, h/k, delta_f/k)),
        i.e. H(R*, h/k, delta_f/k) since H is proportional to R*."""
        return pfp_conductance(p, r_eff, gap / cg, delta_f / cg)

    @ti.func
    def separation(xi, ri, j, x: ti.template()):
        """Minimum-image separation x_j - x_i (positions `x`), r_j, r_i + r_j and the squared distance."""
        d = min_image(x[j] - xi)
        rj = S.radius[j]
        return d, rj, ri + rj, d.norm_sqr()

    @ti.func
    def unit_normal(d, dist2, rsum):
        """Unit normal along d and |d| (z for coincident centres). One division and three products:
        Taichi's fast math does not let the compiler turn d / |d| into that itself."""
        dist = ti.sqrt(dist2)
        nrm = ti.Vector([0.0, 0.0, 1.0])
        if dist > 1e-12 * rsum:
            nrm = d * (1.0 / dist)
        return nrm, dist

    @ti.func
    def pair_params(mat_i, j, p_same):
        """The material-pair parameter vector of i and j (loaded once per particle for one material)."""
        p = p_same
        if ti.static(not single_material):
            p = S.pp[mat_i, S.mat[j]]
        return p

    @ti.func
    def touching_heat(i, j, mat_i, p_same, r_eff, delta, ri, rj):
        """Heat flow into i from a touching partner j: contact spot, plus the gas lens."""
        p_pair = pair_params(mat_i, j, p_same)
        h_pair = spot_conductance(p_pair, r_eff, delta)
        if ti.static(pfp):
            h_pair += lens(p_pair, r_eff, -delta, fluid_layer * ti.min(ri, rj))
        return h_pair * (S.T[j] - S.T[i])

    @ti.func
    def lens_heat(i, j, mat_i, p_same, ri, rj, rsum, dist2):
        """Heat flow into i through the gas lens from a partner j that does not touch it."""
        flow = 0.0
        gap = ti.sqrt(dist2) - rsum
        if gap < fluid_layer * ti.min(ri, rj):
            h_gas = lens(pair_params(mat_i, j, p_same), ri * rj / rsum, gap, fluid_layer * ti.min(ri, rj))
            flow = h_gas * (S.T[j] - S.T[i])
        return flow

    @ti.func
    def note_contact_time(i, touching, t):
        """First time i touches anything and the first time after that it touches nothing."""
        if ti.static(track_contact_time):
            if touching > 0 and S.touch_start[i] < 0.0:
                S.touch_start[i] = t
            if touching == 0 and S.touch_start[i] >= 0.0 and S.touch_end[i] < 0.0:
                S.touch_end[i] = t

    @ti.func
    def surface_contact(i, s, t):
        """Overlap, unit normal (particle -> surface) and surface velocity for surface s."""
        xi = S.x[i]
        r = S.radius[i]
        delta = -1.0
        n = ti.Vector([0.0, 0.0, 1.0])
        u = zero3
        if s < n_planes:
            t0 = S.plane_t[s][0]
            t1 = S.plane_t[s][1]
            tc = ti.min(ti.max(t, t0), t1)
            p = S.plane_p0[s] + S.plane_vel[s] * (tc - t0)
            if t > t0 and t < t1:
                u = S.plane_vel[s]
            dist = (xi - p).dot(S.plane_n[s])
            if dist > -r:
                delta = r - dist
                n = -S.plane_n[s]
        else:
            k = s - n_planes
            d = min_image(xi - S.tube_c[k]) * S.tube_mask[k]
            dist = d.norm()
            if dist > 0.0:
                delta = r + S.tube_r[k] - dist
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
    def surface_heat(s: ti.template(), b, flow):
        """Book a particle's heat flow from surface s, and from a tube by angle bin b of the contact point."""
        ti.atomic_add(S.surf_rate[s], flow)
        if ti.static(angle_bins > 0 and s >= n_planes):
            ti.atomic_add(S.tube_bin_rate[s - n_planes, b], flow)

    @ti.func
    def own_pass(n, t, dt, stamp, conduct, diag):
        """The body of `own_forces`: a Taichi func, so that a kernel can run it and the kick in one launch
        (`kernels/integrate.py`)."""
        if ti.static(track_contact_time):
            diag = 1  # the contact times need the count in every pass
        S.diag[None] = diag  # for the partner pass
        if ti.static(heat):
            S.conduct[None] = conduct  # for the partner pass and the kick
            if conduct:  # else the surfaces' heat flows of the last evaluation hold
                ti.loop_config(serialize=True)  # a few items: no thread-pool round trip
                for s in range(n_surf):
                    S.surf_rate[s] = 0.0
                if ti.static(angle_bins > 0):
                    ti.loop_config(serialize=True)
                    for k, b in ti.ndrange(*S.tube_bin_rate.shape):
                        S.tube_bin_rate[k, b] = 0.0
        S.stamp[None] = stamp  # for the partner pass
        for i in range(n):
            if S.active[i]:
                xi = S.x[i]
                S.xf[i] = xi  # for the partner pass
                ri = S.radius[i]
                mi = S.mass[i]
                wi = S.w[i]
                vi = S.v[i]
                mat_i = S.mat[i]
                force = mi * g
                torque = zero3
                worst = 0.0
                touching = 0
                heat_in = 0.0
                p_same = S.pp[0, 0]
                if ti.static(pairs):  # contact.model = 'none' compiles no pair loop
                    for k in range(S.split[i], S.nbr_n[i]):  # the partners j > i (j < i: partner_forces)
                        j = S.nbr[i, k]
                        mirror = S.src[i, k]  # -1 only in a row cut by overflow, which stops the run
                        d, rj, rsum, dist2 = separation(xi, ri, j, S.x)
                        if dist2 < rsum * rsum:
                            nrm, dist = unit_normal(d, dist2, rsum)
                            delta = rsum - dist
                            v_rel = vi - S.v[j] + (ri * wi + rj * S.w[j]).cross(nrm)
                            mj = S.mass[j]
                            share = 1.0 / ((mi + mj) * rsum)  # one division for m* = mi mj / (mi + mj) and R*
                            m_eff = mi * mj * rsum * share
                            r_eff = ri * rj * (mi + mj) * share
                            i_roll = 0.0
                            if ti.static(rolling):
                                ai = 1.4 * mi * ri * ri
                                aj = 1.4 * mj * rj * rj
                                i_roll = ai * aj / (ai + aj)
                            dmax = 0.0
                            if ti.static(hysteretic):
                                dmax = wide(S.dmax[i, k])
                            mr = zero3
                            if ti.static(rolling):
                                mr = wide(S.mr[i, k])
                            f, f_t, m_roll, xi_new, mr_new, dmax_new = respond(
                                nrm, delta, v_rel, wi - S.w[j], m_eff, r_eff, 2.0 * ri, 2.0 * rj, i_roll,
                                pair_params(mat_i, j, p_same), wide(S.ft[i, k]), mr, dmax, dt)
                            f = handed(f)
                            m_roll = handed(m_roll)
                            force += f
                            if ti.static(hist != fp):  # the force j receives: both spins from one value
                                f_t = f
                            torque += (ri * nrm).cross(f_t) + m_roll
                            S.ft[i, k] = ti.cast(xi_new, hist)
                            if mirror >= 0:  # handed to j: the force on i, and the pair touches now
                                S.ft[j, mirror] = ti.cast(f, hist)
                                S.src[j, mirror] = stamp
                                if ti.static(rolling):
                                    S.mr[j, mirror] = ti.cast(m_roll, hist)
                            if ti.static(heat):
                                if conduct:
                                    flow = handed(touching_heat(i, j, mat_i, p_same, r_eff, delta, ri, rj))
                                    heat_in += flow
                                    if mirror >= 0:
                                        S.qpair[j, mirror] = ti.cast(-flow, hist)
                            if ti.static(rolling):
                                S.mr[i, k] = ti.cast(mr_new, hist)
                            if ti.static(hysteretic):
                                S.dmax[i, k] = ti.cast(dmax_new, hist)
                            if diag:
                                worst = ti.max(worst, delta / ti.min(ri, rj))
                                touching += 1
                        else:
                            if ti.static(heat):
                                if conduct:
                                    flow = 0.0
                                    if ti.static(pfp):
                                        flow = handed(lens_heat(i, j, mat_i, p_same, ri, rj, rsum, dist2))
                                    heat_in += flow
                                    if mirror >= 0:
                                        S.qpair[j, mirror] = ti.cast(-flow, hist)
                            S.ft[i, k] = zero3
                            if ti.static(rolling):
                                S.mr[i, k] = zero3
                            if ti.static(hysteretic):
                                S.dmax[i, k] = 0.0
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
                                v_rel = vi - u + (ri * wi).cross(nrm)
                                dmax = 0.0
                                if ti.static(hysteretic):
                                    dmax = S.wdmax[i, slot]
                                mr = zero3
                                if ti.static(rolling):
                                    mr = S.wmr[i, slot]
                                f, f_t, m_roll, xi_new, mr_new, dmax_new = respond(
                                    nrm, delta, v_rel, wi, mi, ri, 2.0 * ri, 0.0, 1.4 * mi * ri * ri,
                                    S.ps[mat_i, s], S.wft[i, slot], mr, dmax, dt)
                                force += f
                                torque += (ri * nrm).cross(f_t) + m_roll
                                S.wft[i, slot] = xi_new
                                if ti.static(heat):
                                    if conduct and S.surf_T[s] > 0.0:
                                        b = tube_bin(s, nrm)
                                        t_wall = wall_temperature(s, b)
                                        flow = wall_conductance(S.ps[mat_i, s], ri, delta, cg) * (t_wall - S.T[i])
                                        if ti.static(radiation):
                                            flow += wall_radiation(S.ps[mat_i, s], ri, t_wall, S.T[i])
                                        heat_in += flow
                                        surface_heat(s, b, flow)
                                if ti.static(rolling):
                                    S.wmr[i, slot] = mr_new
                                if ti.static(hysteretic):
                                    S.wdmax[i, slot] = dmax_new
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
                                    flow = cg * lens(S.ps[mat_i, s], ri, -delta, fluid_layer * ri) * (
                                        wall_temperature(s, b) - S.T[i])
                                    heat_in += flow
                                    surface_heat(s, b, flow)
                S.wmask[i] = held
                S.f[i] = force
                S.tq[i] = torque
                if ti.static(heat):
                    S.q[i] = conduct * heat_in  # the heat of `conduct` steps, and none between evaluations
                if diag:
                    S.ovl[i] = worst
                    S.ncontact[i] = touching
                if ti.static(not pairs):
                    note_contact_time(i, touching, t)

    @ti.kernel
    def own_forces(n: ti.i32, t: float, dt: float, stamp: ti.i32, conduct: ti.i32, diag: ti.i32):
        own_pass(n, t, dt, stamp, conduct, diag)

    @ti.func
    def mark_near_surfaces(n):
        """near[i] bit s: static surface s is within reach of particle i (run after each neighbour
        build, in its kernel; until the next one no particle moves more than half the skin)."""
        for i in range(n):
            if S.active[i]:
                bits = 0
                for s in ti.static(range(n_surf)):
                    if ti.static(cull >> s & 1):
                        delta, _n, _u = surface_contact(i, s, 0.0)
                        if -delta < surface_reach:
                            bits |= 1 << s
                S.near[i] = bits

    @ti.func
    def gather_partners(i, t):
        """Add to particle i what its partners j < i handed over in own_forces (body of partner_forces),
        at the positions of the force pass (`xf`), so that it may run while particles move on."""
        xi = S.xf[i]
        ri = S.radius[i]
        force = zero3
        torque = zero3
        heat_in = 0.0
        diag = S.diag[None]
        worst = 0.0
        touching = 0
        if diag:
            worst = S.ovl[i]
            touching = S.ncontact[i]
        stamp = S.stamp[None]
        conduct = 0
        if ti.static(heat):
            conduct = S.conduct[None]
        if ti.static(pairs):
            for k in range(S.split[i]):  # the partners j < i (the row is sorted; the rest was done in own_forces)
                j = S.nbr[i, k]
                if ti.static(heat):
                    if conduct:
                        heat_in += S.qpair[i, k]  # written by j in own_forces
                if S.src[i, k] == stamp:  # j found the pair touching in this force pass
                    d, rj, rsum, dist2 = separation(xi, ri, j, S.xf)
                    nrm, dist = unit_normal(d, dist2, rsum)
                    delta = rsum - dist
                    f_j = S.ft[i, k]  # force on j, written by j in own_forces
                    force -= f_j
                    torque -= (ri * nrm).cross(f_j)
                    if ti.static(rolling):
                        torque -= S.mr[i, k]
                    if diag:
                        worst = ti.max(worst, delta / ti.min(ri, rj))
                        touching += 1
            S.f[i] += force
            S.tq[i] += torque
            if ti.static(heat):
                S.q[i] += conduct * heat_in
            if diag:
                S.ovl[i] = worst
                S.ncontact[i] = touching
            note_contact_time(i, touching, t)

    @ti.kernel
    def partner_forces(n: ti.i32, t: float):
        for i in range(n):
            if S.active[i]:
                gather_partners(i, t)

    return SimpleNamespace(own=own_forces, own_pass=own_pass, partner=partner_forces if pairs else None,
                           gather=gather_partners, mark_near=mark_near_surfaces if cull else None)
