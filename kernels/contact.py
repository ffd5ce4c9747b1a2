"""Contact forces and torques: particle-particle (from the Verlet list), plane walls and tubes.

Each pair is listed once, in the row of its owner (`kernels/broadphase.py`), and evaluated there:
the contact law (`contact_laws.make_contact_response`) updates the pair's history in the owner's
row and gives the force F and rolling moment M on the owner i; the partner j receives -F and the
torque r_j n x F - M (n the unit normal from i to j: Newton's third law, the contact point r_j n
from j). Particles are swept slab by slab (`kernels/geometry.py`): a pair's partner lies in the
owner's slab or in the next one. The slabs are grouped into blocks of consecutive slabs
(`block_count`: an even number of blocks, at most 16, each of two slabs or more; one block below
four slabs), so (`passes`)
1. pass 1: each block, one thread per block, sweeps its slabs but the last in order, each in index
   order (its pairs, walls and tubes), adding to the sums of that slab and the next, which the last
   kick-drift zeroed (`kernels/integrate.py`; and the contact counts, where the host reads them,
   here); when the step goes on, it integrates (`then`) each slab after the block's first as soon as
   it is swept: its sums are complete (each slab receives only from itself and the one before), and
   no pair left to evaluate reads it;
2. pass 2, once every block is through pass 1: each block's last slab likewise, then it integrates
   that slab and the next block's first one, now complete too;
so a slab's particles are mostly still in cache when they are swept after being added to as
partners, and integrated right after (2-5 % of a step of the peer bed at 10k and 50k against
sweeping even slabs, then odd ones, `benchmarks/README.md`; the blocks also share out better
among threads than eight or nine single slabs). No two threads then write the same particle, and
every sum is taken in the same order whatever the thread count (the blocks depend on the slab count
only): float64 runs are bit-reproducible without atomics. Each particle is read and written
about once per step, which is what the large beds, whose fields do not fit in cache, wait on. With
`atomic` (a GPU, where a slab per thread would leave it idle) every particle of a pass is a thread
of its own and the sums are atomic: the same forces, summed in an order that varies from run to run.
With heat the same pair evaluation adds its conduction (contact spot and gas lens) to both
particles' heat flows.

Quiet partners. A row lists the partners that touched at the last neighbour build first
(`nbr_touch` of them) and the others after; the build zeroed the others' history and noted the
smallest gap between their surfaces, `nbr_gap` (`kernels/broadphase.py`). Since then no two
particles have come closer than twice the largest displacement, 2 sqrt(S.max_disp), so while that
(plus a rounding margin, `quiet_margin`) stays below a row's `nbr_gap`, none of those partners
touches: the pass evaluates the first `nbr_touch` partners only. A pair apart adds nothing and its
history stays zero, so this changes no bit; it saves the distance, the branch and the history store
of each partner apart (a settled bed: 1.3 of 3.7 listed pairs a particle, `benchmarks/README.md`).
With the gas lens (`fluid_layer`) pairs apart conduct, so they are skipped only in steps without
the conduction.

With numerics.precision = 'mixed' the row fields (ft, mr, dmax) are float32: what the loop reads
from them is widened to float64 (`wide`) and what it stores is rounded once; the sums stay float64.

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
from .geometry import make_geometry, make_slabs
from .heat import pfp_conductance, spot_conductance, wall_conductance, wall_radiation
from .ordered import in_order, raise_max
from .sizes import make_sizes

# Loop iterations per worker in the slab loops. Taichi's CPU runtime (1.7) runs a parallel loop of fewer
# than about a thousand iterations on one thread and splits a longer one into one block of consecutive
# iterations per thread: a loop of SPREAD iterations per thread, of which the first of each block does
# the work of one worker, gives each thread one worker. The workers take the slabs of a pass one at a
# time from shared counters (`S.slab_next`): the host thread starts at once while the others are
# still waking up (tens of microseconds here), and a slab of more work holds up no one.
SPREAD = 1024
BLOCKS = 16  # the most blocks of slabs in a pass (`block_count`)


def block_count(n_slabs: int) -> int:
    """Blocks of consecutive slabs that the passes hand out (`passes`): an even number (two threads
    take as many), at most BLOCKS, each of at least two slabs; one below four slabs. Depends on the
    slab count only, never on the thread count (module docstring)."""
    if n_slabs < 4:
        return 1
    b = min(n_slabs // 2, BLOCKS)
    return b - b % 2


def make_force_kernel(grid, law: int, rolling: bool, planes: list[dict], tubes: list[dict], W: int, gravity, S,
                      track_contact_time: bool = False, one_material: tuple | None = None, heat: bool = False,
                      angle_bins: int = 0, fluid_layer: float = 0.0, pairs: bool = True,
                      radiation: bool = False, foil: bool = False, wall_foil: bool = False, cull: int = 0,
                      surface_reach: float = 0.0, grain_scale: float = 1.0, atomic: bool | None = None,
                      uniform: tuple[float, float] | None = None, quiet_margin: float = 0.0):
    """Return a namespace of the kernel `forces(n, t, dt, conduct, diag)` (both passes), `passes(then)`,
    which makes the Taichi func of both passes that calls the Taichi func then(i, t, dt, drift, kick) on
    every particle whose sums are complete (`kernels/integrate.py` fuses the kick with them); `finish(i, t)` (the
    contact times, None without them) and `mark_near(n)` (below). With heat, `conduct` = m > 0 evaluates
    the conduction and books the heat of m steps (q[i] = m x the heat flow: heat.conduction_interval =
    m evaluates it every m-th step, an explicit Euler step of m dt), and `conduct` = 0 skips it (q[i] =
    0; the surfaces' heat flows of the last evaluation hold); S.conduct[None] tells the kick. `diag` = 1
    also fills ovl and ncontact (module docstring).
    `planes` and `tubes` (`tidem.surfaces`) are compiled in as constants. `one_material`: where all particles
    are of one material, its material-pair parameter vector and its material-surface vector for each
    surface, and `uniform`: (radius, mass) where all have the same; the pair loop then takes them as
    constants of the kernel instead of loading them for every pair (12 % of the passes of the peer
    bed, whose products of constants the compiler then folds, `benchmarks/README.md`). `heat` adds conduction
    (kernels/heat.py) to the same loop, adding to q [W] and the heat flow into each surface with a
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
    conducts as those grains do (kernels/heat.py). `atomic`: atomic sums, one thread per particle
    (module docstring); None: on any architecture but the CPU. `quiet_margin` [m] > 0: skip quiet
    partners (module docstring) with that rounding margin; 0: evaluate every listed pair."""
    if atomic is None:
        atomic = not in_order()
    flat = atomic or not pairs  # one loop over the particles, no slabs
    n_slabs, _slab_of, succ, pred = make_slabs(grid)
    n_blocks = block_count(n_slabs)
    workers = max(1, ti.lang.impl.current_cfg().cpu_max_num_threads)
    pfp = heat and fluid_layer > 0.0
    quiet = pairs and quiet_margin > 0.0  # skip the quiet partners (module docstring)
    min_image, _wrap, _cc, _cid = make_geometry(grid)
    respond = make_contact_response(law, rolling)
    hysteretic = law == 2
    g = ti.Vector(list(gravity))
    n_planes = len(planes)
    moving = [any(p["vel"]) for p in planes]
    n_surf = n_planes + len(tubes)
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    cg = float(grain_scale)
    fp = ti.lang.impl.current_cfg().default_fp
    K = S.nbr.shape[1]
    hist = S.ft.dtype  # float32 with numerics.precision = 'mixed' (tidem.state), else fp

    single = one_material is not None
    p_one, s_one = one_material if single else (None, None)
    radius_of, mass_of = make_sizes(S, uniform)

    @ti.func
    def wide(v):
        """A value read from the rows, in the kernels' float type."""
        return ti.cast(v, fp)

    @ti.func
    def lens(p, r_eff, gap, delta_f):
        """The gas-lens conductance; a parcel's is that of its grains' k lenses (k H(R*/k, h/k, delta_f/k)),
        i.e. H(R*, h/k, delta_f/k) since H is proportional to R*."""
        return pfp_conductance(p, r_eff, gap / cg, delta_f / cg)

    @ti.func
    def separation(xi, ri, j, x: ti.template()):
        """Minimum-image separation x_j - x_i (positions `x`), r_j, r_i + r_j and the squared distance."""
        d = min_image(x[j] - xi)
        rj = radius_of(j)
        return d, rj, ri + rj, d.norm_sqr()

    @ti.func
    def unit_normal(d, dist, rsum):
        """Unit normal along d and |d| = dist (z for coincident centres). One division and three products:
        Taichi's fast math does not let the compiler turn d / |d| into that itself."""
        nrm = ti.Vector([0.0, 0.0, 1.0])
        if dist > 1e-12 * rsum:
            nrm = d * (1.0 / dist)
        return nrm, dist

    @ti.func
    def pair_params(mat_i, j):
        """The material-pair parameter vector of i and j (constants where all particles are of one material)."""
        if ti.static(single):
            return ti.Vector(p_one)
        else:
            return S.pp[mat_i, S.mat[j]]

    @ti.func
    def surface_params(mat_i, s: ti.template()):
        """The material-surface parameter vector of i and surface s, as `pair_params`."""
        if ti.static(single):
            return ti.Vector(s_one[s])
        else:
            return S.ps[mat_i, s]

    @ti.func
    def touching_heat(i, j, mat_i, r_eff, delta, ri, rj):
        """Heat flow into i from a touching partner j: contact spot, plus the gas lens."""
        p_pair = pair_params(mat_i, j)
        h_pair = spot_conductance(p_pair, r_eff, delta)
        if ti.static(pfp):
            h_pair += lens(p_pair, r_eff, -delta, fluid_layer * ti.min(ri, rj))
        return h_pair * (S.T[j] - S.T[i])

    @ti.func
    def lens_heat(i, j, mat_i, ri, rj, rsum, dist):
        """Heat flow into i through the gas lens from a partner j at distance `dist` that does not touch it."""
        flow = 0.0
        gap = dist - rsum
        if gap < fluid_layer * ti.min(ri, rj):
            h_gas = lens(pair_params(mat_i, j), ri * rj / rsum, gap, fluid_layer * ti.min(ri, rj))
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
            if ti.static(moving[s]):
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
    def surface_heat(s: ti.template(), b, flow):
        """Book a particle's heat flow from surface s, and from a tube by angle bin b of the contact point."""
        ti.atomic_add(S.surf_rate[s], flow)
        if ti.static(angle_bins > 0 and s >= n_planes):
            ti.atomic_add(S.tube_bin_rate[s - n_planes, b], flow)

    @ti.func
    def add(field: ti.template(), j, value):
        """field[j] += value: a plain load and store where one thread owns j in this pass (slabs; Taichi
        would make `field[j] += value` with an index it cannot prove private an atomic, a
        compare-and-swap loop per float, 20 ns a pair on the peer bed), else atomic."""
        if ti.static(atomic):
            ti.atomic_add(field[j], value)
        else:
            field[j] = field[j] + value

    @ti.func
    def raise_to(field: ti.template(), j, value):
        """field[j] = max(field[j], value), as `add`."""
        if ti.static(atomic):
            ti.atomic_max(field[j], value)
        else:
            field[j] = ti.max(field[j], value)

    @ti.func
    def clear(i):
        """Zero particle i's contact count and largest overlap before a force evaluation that fills
        them (the kick-drift zeroes the force, torque and heat flow)."""
        S.ovl[i] = 0.0
        S.ncontact[i] = 0

    @ti.func
    def visit(i, t, dt, conduct, diag, reach):
        """Particle i's pairs (adding the reactions to the partners), walls and tubes, and gravity; its
        quiet partners only where their gap at the build is within `reach` (`quiet_reach`)."""
        xi = S.x[i]
        ri = radius_of(i)
        mi = mass_of(i)
        wi = S.w[i]
        vi = S.v[i]
        mat_i = S.mat[i]
        force = mi * g
        torque = zero3
        worst = 0.0
        touching = 0
        heat_in = 0.0
        if ti.static(pairs):  # contact.model = 'none' compiles no pair loop
            # software pipelining: the next listed partner's distance (its loads and square root) is taken
            # while this pair's contact law runs, instead of after it (10-14 % of the pass on the peer bed;
            # past the row's end the "next partner" is i itself, never used)
            count = S.nbr_n[i]
            if ti.static(quiet):  # (a select, not a branch: in a flowing bed it goes either way)
                skip = S.nbr_gap[i] > reach
                if ti.static(pfp):  # the gas lens conducts between partners apart, when the conduction is on
                    skip &= conduct == 0
                count = ti.select(skip, S.nbr_touch[i], count)
            j_next = ti.select(count > 0, S.nbr[i, 0], i)
            d_next, rj_next, rsum_next, dist2_next = separation(xi, ri, j_next, S.x)
            dist_next = ti.sqrt(dist2_next)
            for k in range(count):
                j, d, rj, rsum, dist2, dist_k = j_next, d_next, rj_next, rsum_next, dist2_next, dist_next
                j_next = ti.select(k + 1 < count, S.nbr[i, ti.min(k + 1, K - 1)], i)
                d_next, rj_next, rsum_next, dist2_next = separation(xi, ri, j_next, S.x)
                dist_next = ti.sqrt(dist2_next)
                if dist2 < rsum * rsum:
                    nrm, dist = unit_normal(d, dist_k, rsum)
                    delta = rsum - dist
                    wj = S.w[j]
                    v_rel = vi - S.v[j] + (ri * wi + rj * wj).cross(nrm)
                    mj = mass_of(j)
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
                        nrm, delta, v_rel, wi - wj, m_eff, r_eff, 2.0 * ri, 2.0 * rj, i_roll,
                        pair_params(mat_i, j), wide(S.ft[i, k]), mr, dmax, dt)
                    force += f
                    torque += (ri * nrm).cross(f_t) + m_roll
                    add(S.f, j, -f)
                    add(S.tq, j, (rj * nrm).cross(f_t) - m_roll)
                    S.ft[i, k] = ti.cast(xi_new, hist)
                    if ti.static(rolling):
                        S.mr[i, k] = ti.cast(mr_new, hist)
                    if ti.static(hysteretic):
                        S.dmax[i, k] = ti.cast(dmax_new, hist)
                    if ti.static(heat):
                        if conduct:
                            flow = touching_heat(i, j, mat_i, r_eff, delta, ri, rj)
                            heat_in += flow
                            add(S.q, j, -conduct * flow)
                    if diag:
                        share_ovl = delta / ti.min(ri, rj)
                        worst = ti.max(worst, share_ovl)
                        touching += 1
                        raise_to(S.ovl, j, share_ovl)
                        add(S.ncontact, j, 1)
                else:
                    if ti.static(pfp):
                        if conduct:
                            flow = lens_heat(i, j, mat_i, ri, rj, rsum, dist_k)
                            heat_in += flow
                            add(S.q, j, -conduct * flow)
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
                            surface_params(mat_i, s), S.wft[i, slot], mr, dmax, dt)
                        force += f
                        torque += (ri * nrm).cross(f_t) + m_roll
                        S.wft[i, slot] = xi_new
                        if ti.static(heat):
                            if conduct and S.surf_T[s] > 0.0:
                                b = tube_bin(s, nrm)
                                t_wall = wall_temperature(s, b)
                                flow = wall_conductance(surface_params(mat_i, s), ri, delta, cg) * (t_wall - S.T[i])
                                if ti.static(radiation):
                                    flow += wall_radiation(surface_params(mat_i, s), ri, t_wall, S.T[i])
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
                            flow = cg * lens(surface_params(mat_i, s), ri, -delta, fluid_layer * ri) * (
                                wall_temperature(s, b) - S.T[i])
                            heat_in += flow
                            surface_heat(s, b, flow)
        S.wmask[i] = held
        add(S.f, i, force)
        add(S.tq, i, torque)
        if ti.static(heat):
            add(S.q, i, conduct * heat_in)  # the heat of `conduct` steps, and none between evaluations
        if diag:
            raise_to(S.ovl, i, worst)
            add(S.ncontact, i, touching)

    @ti.func
    def quiet_reach():
        """How far apart two particles listed at the last neighbour build may now have come closer:
        twice the largest displacement since then (S.max_disp holds it squared, from the last
        kick-drift; larger after a build), plus `quiet_margin` for rounding. A partner whose gap
        was wider cannot touch yet."""
        return 2.0 * ti.sqrt(S.max_disp[None]) + quiet_margin

    @ti.func
    def block_start(b):
        """The first slab of block b (block n_blocks: n_slabs)."""
        return b * n_slabs // n_blocks

    @ti.func
    def clear_slab(s):
        for p in range(S.slab_start[s], S.slab_start[s + 1]):
            clear(S.slab_list[p])

    @ti.func
    def sweep_slab(s, t, dt, conduct, diag, reach):
        for p in range(S.slab_start[s], S.slab_start[s + 1]):
            visit(S.slab_list[p], t, dt, conduct, diag, reach)

    @ti.func
    def start_pass(conduct):
        """Before the passes: the conduction of this step for the kick, and with it the surfaces' heat
        flows zeroed (else those of the last evaluation hold)."""
        if ti.static(heat):
            S.conduct[None] = conduct
            if conduct:
                ti.loop_config(serialize=True)  # a few items: no thread-pool round trip
                for s in range(n_surf):
                    S.surf_rate[s] = 0.0
                if ti.static(angle_bins > 0):
                    ti.loop_config(serialize=True)
                    for k, b in ti.ndrange(*S.tube_bin_rate.shape):
                        S.tube_bin_rate[k, b] = 0.0

    def passes(then=None):
        """Both passes (module docstring) as a Taichi func passes(n, t, dt, conduct, diag, drift, kick)
        that calls the Taichi func then(i, t, dt, drift, kick) on every particle once its sums are
        complete and keeps the largest value it returns in S.max_disp[None] (the squared displacements
        of the kick-drifts): one atomic per worker, not one per particle. One parallel loop: each
        worker takes blocks from a shared counter (S.slab_next[0]) while any are left, waits until
        every block is through pass 1 (S.slab_next[1] counts them), then takes blocks' last slabs
        (S.slab_next[2]). A worker waits only for blocks that another one took and is sweeping, so the
        loop finishes on any number of threads, one included; it saves the start of a second parallel
        loop (about 50 us on two threads, `benchmarks/README.md`). With `flat`: two loops over the
        particles."""
        kicks = then is not None

        @ti.func
        def integrate_slab(s, t, dt, drift, kick):
            largest = 0.0
            for p in range(S.slab_start[s], S.slab_start[s + 1]):
                largest = ti.max(largest, then(S.slab_list[p], t, dt, drift, kick))
            return largest

        @ti.func
        def both(n, t, dt, conduct, diag, drift, kick):
            if ti.static(track_contact_time):
                diag = 1  # the contact times need the count in every pass
            reach = quiet_reach()
            if ti.static(kicks):
                S.max_disp[None] = 0.0  # the kick-drifts' displacements follow
            start_pass(conduct)
            if ti.static(flat):
                if diag:
                    for i in range(n):
                        if S.active[i]:
                            clear(i)
                for i in range(n):
                    if S.active[i]:
                        visit(i, t, dt, conduct, diag, reach)
                if ti.static(kicks):
                    for i in range(n):
                        if S.active[i]:
                            raise_max(S.max_disp, then(i, t, dt, drift, kick))
            else:
                for c in ti.static(range(3)):
                    S.slab_next[c] = 0
                for e in range(workers * SPREAD):
                    if e % SPREAD == 0:
                        largest = 0.0
                        while True:  # pass 1
                            b = ti.atomic_add(S.slab_next[0], 1)
                            if b >= n_blocks:
                                break
                            lo, hi = block_start(b), block_start(b + 1)
                            if diag:
                                for s in range(lo, hi):
                                    clear_slab(s)
                            for s in range(lo, hi - 1):
                                sweep_slab(s, t, dt, conduct, diag, reach)
                                if ti.static(kicks):
                                    if s > lo or pred(s) < 0:  # complete: its predecessor is swept
                                        largest = ti.max(largest, integrate_slab(s, t, dt, drift, kick))
                            ti.atomic_add(S.slab_next[1], 1)
                        while ti.atomic_add(S.slab_next[1], 0) < n_blocks:  # pass 2 adds to the blocks' first slabs
                            pass
                        while True:  # pass 2
                            b = ti.atomic_add(S.slab_next[2], 1)
                            if b >= n_blocks:
                                break
                            last = block_start(b + 1) - 1
                            sweep_slab(last, t, dt, conduct, diag, reach)
                            if ti.static(kicks):
                                largest = ti.max(largest, integrate_slab(last, t, dt, drift, kick))
                                after = succ(last)  # the next block's first slab
                                if after >= 0 and after != last:
                                    largest = ti.max(largest, integrate_slab(after, t, dt, drift, kick))
                        if ti.static(kicks):
                            ti.atomic_max(S.max_disp[None], largest)

        return both

    forces_only = passes()

    @ti.kernel
    def forces(n: ti.i32, t: float, dt: float, conduct: ti.i32, diag: ti.i32):
        forces_only(n, t, dt, conduct, diag, 0, 0)

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
    def finish(i, t):
        """The contact times of particle i, from its complete contact count."""
        note_contact_time(i, S.ncontact[i], t)

    return SimpleNamespace(forces=forces, passes=passes,
                           finish=finish if track_contact_time else None, mark_near=mark_near_surfaces if cull else None)
