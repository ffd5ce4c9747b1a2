"""Particle-particle contacts from the Verlet list: each pair is evaluated in the row of its owner
(`kernels/broadphase.py`). The contact law (`contact_laws.make_contact_response`) updates the pair's
history in the owner's row and gives the force F and rolling moment M on the owner i; the partner j
receives -F and the torque r_j n x F - M (n the unit normal from i to j: Newton's third law, the
contact point r_j n from j). With heat the same evaluation adds the conduction (contact spot and gas
lens, `kernels/heat.py`) to both particles' heat flows.

Quiet partners. A row lists the partners that touched at the last neighbour build first
(`nbr_touch` of them), then the others in QUIET_GROUPS groups by the gap between their surfaces then
(up to half the skin, up to the skin, beyond: listed for the gas lens), with each group's end and
smallest gap (`nbr_end`, `nbr_gap`; the build zeroed their history, `kernels/broadphase.py`). Since
then no two particles have come closer than twice the largest displacement, 2 sqrt(S.max_disp), so
while that (plus a rounding margin, `quiet_margin`: the `reach`) stays below a group's smallest gap,
none of its partners touches: the pass evaluates the row up to the end of the last group whose
smallest gap is within reach. A pair apart adds nothing and its history stays zero, so skipping it
changes no bit; it saves the distance, the branch and the history store of each partner apart (a settled
bed: 1.3 of 3.7 listed pairs a particle; a bubbling bed: 3.39 of 4.12 quiet partners evaluated with
one group, 1.96 with three, `benchmarks/README.md`). With the gas lens (`fluid_layer`) pairs apart
conduct, so in the steps with conduction every partner is evaluated.

With numerics.precision = 'mixed' the row fields (ft, mr, dmax) are float32: what the loop reads
from them is widened to float64 (`wide`) and what it stores is rounded once; the sums stay float64.
"""

from types import SimpleNamespace

import taichi as ti

from .broadphase import QUIET_GROUPS
from .heat import pfp_conductance, spot_conductance


def make_pair_contacts(S, respond, hysteretic: bool, rolling: bool, p_one, heat: bool, fluid_layer: float,
                       quiet: bool, grain_scale: float, min_image, radius_of, mass_of, add, raise_to):
    """Return a namespace with the Taichi func `visit(i, xi, vi, wi, ri, mi, mat_i, dt, conduct, diag, reach,
    force, torque, heat_in, worst, touching)`, which adds particle i's pairs to the sums handed in (and
    the reactions to its partners, by `add` and `raise_to`: `kernels/ordered.py`) and returns them.
    `p_one`: the material-pair parameter vector where all particles are of one material (constants
    of the kernel), else None (S.pp); `quiet`: skip the quiet partners (module docstring)."""
    pfp = heat and fluid_layer > 0.0
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    cg = float(grain_scale)
    fp = ti.lang.impl.current_cfg().default_fp
    K = S.nbr.shape[1]
    hist = S.ft.dtype  # float32 with numerics.precision = 'mixed' (tidem.sim.state), else fp
    single = p_one is not None

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
    def visit(i, xi, vi, wi, ri, mi, mat_i, dt, conduct, diag, reach, force, torque, heat_in, worst, touching):
        """Particle i's pairs, added to the sums handed in; its quiet partners only where their gap at the
        build is within `reach` (module docstring)."""
        # software pipelining: the next listed partner's distance (its loads and square root) is taken
        # while this pair's contact law runs, instead of after it (10-14 % of the pass on the peer bed;
        # past the row's end the "next partner" is i itself, never used)
        count = S.nbr_n[i]
        if ti.static(quiet):  # (selects, not branches: in a flowing bed each goes either way)
            within = S.nbr_touch[i]
            for g in ti.static(range(QUIET_GROUPS)):  # up to the last group whose nearest may touch
                end = count
                if ti.static(g < QUIET_GROUPS - 1):
                    end = S.nbr_end[i, g]
                within = ti.select(S.nbr_gap[i, g] <= reach, end, within)
            if ti.static(pfp):  # the gas lens conducts between partners apart, when the conduction is on
                within = ti.select(conduct != 0, count, within)
            count = within
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
        return force, torque, heat_in, worst, touching

    return SimpleNamespace(visit=visit)
