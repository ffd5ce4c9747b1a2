"""Contact laws: normal, tangential and rolling sub-models as small Taichi functions.

All laws share one calling convention, so that particle-particle, particle-wall and
particle-tube contacts use the same code (`make_contact_response`):

* geometry: unit normal `n` pointing from particle i to the other body, overlap `delta` > 0,
  relative velocity of i's contact point against the other's `v_rel`, relative spin `w_rel`,
  effective mass `m_eff`, effective radius `r_eff`, the two diameters (linear laws);
* a parameter vector `p` (indices below) from the material-pair table built by `tidem.particles.contact_params`;
* history: tangential spring `xi` [m], rolling spring moment `mr` [N m], maximum overlap
  `dmax` [m] (hysteresis), each returned updated.

Normal laws (F_n > 0 is repulsive):

* linear spring-dashpot (source 1): F_n = k_n delta + eta_n v_n, k_n = E_i d_i E_j d_j /
  (E_i d_i + E_j d_j) (source 3 eq. 26; a wall has d -> infinity, so k_n = E_i d_i),
  eta_n = 2 gamma sqrt(k_n m_eff), gamma = -ln e / sqrt(ln^2 e + pi^2). The dashpot may pull
  at the end of a contact; this keeps the restitution exactly e.
* Hertz-Mindlin: F_n = 4/3 E* sqrt(R*) delta^1.5 + eta_n v_n, S_n = 2 E* sqrt(R* delta),
  S_t = 8 G* sqrt(R* delta), eta = 2 sqrt(5/6) gamma sqrt(S m_eff) (Tsuji et al. 1992 form,
  as in LIGGGHTS' hertz model).
* linear hysteresis of Walton & Braun (source 3 eq. 26-28): loading with k_l, unloading and
  reloading with k_ul along F = k_ul (delta - delta_0), delta_0 = delta_max (1 - k_l/k_ul);
  no attraction, floor 0.001 k_l delta. Without the floor e = sqrt(k_l/k_ul); `tidem.particles.contact_params`
  picks k_ul so that the restitution *with* the floor is e.

Tangential (source 3 eq. 29; Cundall-Strack spring with history): the spring `xi` is rotated
into the current tangent plane keeping its length, grows by v_t dt, F_t = -k_t xi - eta_t v_t;
when |F_t| > mu_s F_n the contact slides at mu_d F_n and the spring is reset to carry it.
k_t = kappa k_n with the Mindlin ratio kappa = 2(1-nu)/(2-nu) for the linear laws.

Rolling resistance, elastic-plastic spring-dashpot "model C" (source 3 eq. 30-33; Ai et al.
2011): k_r = R*^2 k_n, M_s <- M_s - k_r w_roll dt capped at mu_r R* F_n; while below the cap a
dashpot M_d = -eta_r 2 sqrt(I_r k_r) w_roll acts, I_r the effective rolling inertia.
"""

import taichi as ti

# Indices into a material-pair parameter vector.
ESTAR, GSTAR, GAMMA, KAPPA, MU_S, MU_D, MU_R, ETA_R, UNLOAD_RATIO, E_I, E_J = range(11)
# heat conduction (kernels/heat.py): solid conductivity of the pair, contact-radius correction
# for a softened modulus, gas conductivity, mean free path + roughness (wall contacts), and
# the exchange emissivity of a particle-surface pair (0 without heat.radiation)
K_EFF, A_CORR, LAMBDA_GAS, GAP, EMIS = range(11, 16)
# square roots the laws' dashpots take, computed once per material pair: sqrt(2 E*), sqrt(8 G*), sqrt(kappa)
ROOT_2E, ROOT_8G, ROOT_KAPPA = range(16, 19)
N_PARAMS = 19

LINEAR, HERTZ, HYSTERETIC, NONE = 0, 1, 2, 3
LAW_IDS = {"linear": LINEAR, "hertz_mindlin": HERTZ, "hysteretic": HYSTERETIC, "none": NONE}


@ti.func
def rotate_into_plane(h, n):
    """Project a history vector onto the plane normal to n, keeping its length (scaled by
    sqrt(|h|^2 / |h_projected|^2), |h_projected|^2 = |h|^2 - (h.n)^2 for a unit n: one square root)."""
    hn = h.dot(n)
    out = h - hn * n
    h2 = h.norm_sqr()
    new2 = h2 - hn * hn
    if new2 > 0.0:
        out *= ti.sqrt(h2 / new2)
    return out


def make_contact_response(law: int, rolling: bool):
    """Build the contact function for one normal law, with or without rolling resistance."""

    @ti.func
    def respond(n, delta, v_rel, w_rel, m_eff, r_eff, d_i, d_j, i_roll, p, xi, mr, dmax, dt):
        v_n = v_rel.dot(n)  # approach speed, > 0 when closing
        v_t = v_rel - v_n * n
        f_n = 0.0
        k_ref = 0.0  # stiffness for the tangential and rolling springs
        eta_scale = 0.0
        root = 0.0
        damp = 0.0  # sqrt(k_ref m_eff / p[ROOT_2E]^2) for Hertz: both dashpots take it
        if ti.static(law == HERTZ):
            root = ti.sqrt(r_eff * delta)
            k_ref = 2.0 * p[ESTAR] * root
            damp = ti.sqrt(root * m_eff)
            eta_scale = 2.0 * ti.sqrt(5.0 / 6.0)
            f_n = 4.0 / 3.0 * p[ESTAR] * root * delta + eta_scale * p[GAMMA] * p[ROOT_2E] * damp * v_n
        else:
            k_n = p[E_I] * d_i
            if p[E_J] > 0.0:
                k_n = p[E_I] * d_i * p[E_J] * d_j / (p[E_I] * d_i + p[E_J] * d_j)
            k_ref = k_n
            eta_scale = 2.0
            if ti.static(law == LINEAR):
                damp = ti.sqrt(k_n * m_eff)
                f_n = k_n * delta + 2.0 * p[GAMMA] * damp * v_n
            else:
                k_ul = k_n * p[UNLOAD_RATIO]
                dmax = ti.max(dmax, delta)
                delta0 = dmax * (1.0 - 1.0 / p[UNLOAD_RATIO])
                f_n = ti.min(k_n * delta, k_ul * (delta - delta0))
                f_n = ti.max(f_n, 0.001 * k_n * delta)
        f_pos = ti.max(f_n, 0.0)

        # tangential spring with Coulomb cap
        # the dashpot's sqrt(k_t m_eff) from the normal one's: k_t / k_ref is a constant of the pair
        k_t = k_ref * p[KAPPA]
        eta_t = 0.0
        if ti.static(law == HERTZ):
            k_t = 8.0 * p[GSTAR] * root
            eta_t = eta_scale * p[GAMMA] * p[ROOT_8G] * damp
        elif ti.static(law == LINEAR):
            eta_t = eta_scale * p[GAMMA] * p[ROOT_KAPPA] * damp
        else:
            eta_t = eta_scale * p[GAMMA] * ti.sqrt(k_t * m_eff)
        xi = rotate_into_plane(xi, n) + v_t * dt
        f_t = -k_t * xi - eta_t * v_t
        cap = p[MU_S] * f_pos
        ft2 = f_t.norm_sqr()
        if ft2 > cap * cap:  # sliding (compared squared: a square root only then)
            ft_norm = ti.sqrt(ft2)
            f_t *= p[MU_D] * f_pos / ft_norm
            if k_t > 0.0:
                xi = -(f_t + eta_t * v_t) / k_t

        # rolling resistance (model C)
        m_roll = ti.Vector([0.0, 0.0, 0.0])
        if ti.static(rolling):
            w_roll = w_rel - w_rel.dot(n) * n
            k_r = r_eff * r_eff * k_ref
            mr = rotate_into_plane(mr, n) - k_r * w_roll * dt
            m_lim = p[MU_R] * r_eff * f_pos
            mr2 = mr.norm_sqr()
            if mr2 > m_lim * m_lim:
                mr *= m_lim / ti.sqrt(mr2)
                m_roll = mr
            else:
                m_roll = mr - p[ETA_R] * 2.0 * ti.sqrt(i_roll * k_r) * w_roll
        force = -f_n * n + f_t
        return force, f_t, m_roll, xi, mr, dmax

    return respond


def make_slot_response(S, prefix: str, respond, rolling: bool, hysteretic: bool):
    """The contact of a particle with a surface (a plane, a tube, a mesh triangle) whose history lies in
    a slot of the particle's rows `{prefix}ft` (and `{prefix}mr`, `{prefix}dmax` where the law keeps them)
    of the State S: `touch(i, slot, nrm, delta, u, vi, wi, mi, ri, params, dt)` runs the contact law
    `respond` against a wall of infinite diameter moving at u at the contact point, with the particle's own
    mass and rolling inertia 1.4 m r^2, stores the updated history in the slot and returns the force and
    the torque on the particle."""
    ft = getattr(S, prefix + "ft")
    mr_rows = getattr(S, prefix + "mr") if rolling else None
    dmax_rows = getattr(S, prefix + "dmax") if hysteretic else None
    zero3 = ti.Vector([0.0, 0.0, 0.0])

    @ti.func
    def touch(i, slot, nrm, delta, u, vi, wi, mi, ri, params, dt):
        v_rel = vi - u + (ri * wi).cross(nrm)
        dmax = 0.0
        if ti.static(hysteretic):
            dmax = dmax_rows[i, slot]
        mr = zero3
        if ti.static(rolling):
            mr = mr_rows[i, slot]
        f, f_t, m_roll, xi_new, mr_new, dmax_new = respond(
            nrm, delta, v_rel, wi, mi, ri, 2.0 * ri, 0.0, 1.4 * mi * ri * ri, params, ft[i, slot], mr, dmax, dt)
        ft[i, slot] = xi_new
        if ti.static(rolling):
            mr_rows[i, slot] = mr_new
        if ti.static(hysteretic):
            dmax_rows[i, slot] = dmax_new
        return f, (ri * nrm).cross(f_t) + m_roll

    return touch
