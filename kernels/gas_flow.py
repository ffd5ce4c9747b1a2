"""Locally averaged incompressible gas on the staggered grid: predictor, pressure projection
by preconditioned conjugate gradients, velocity correction, and gas energy.

Equations (source 1, Tsuji/Kawaguchi form; gas density rho and viscosity mu constant):
    d(eps)/dt + div(eps u) = 0
    rho eps Du/Dt = -eps grad p - f + eps rho g + mu lap u,   f = sum_p K_p (u - v_p) / V
(the conservative form rho [d(eps u)/dt + div(eps u u)] reduces to this by continuity).
One gas step of length dt on face f (eps_f the mean of the two cells, B_f and Bv_f the
deposited drag coefficients of `gas_coupling`, per cell volume V):
  predictor, drag implicit:  u*_f = [rho eps_f (u_adv + dt (nu lap u + g)) + dt Bv_f / V]
                                    / (rho eps_f + dt B_f / V),
      u_adv the semi-Lagrangian value u^n(x_f - dt u^n(x_f)) (stable for any step);
  correction:                u_f = u*_f - A_f grad p_f,   A_f = dt eps_f / (rho eps_f + dt B_f / V);
  pressure:                  div(eps A grad p) = div(eps u*) + (eps^{n+1} - eps^n) / dt,
      a symmetric positive definite system for -p, solved by Jacobi-preconditioned CG to a
      relative residual `tolerance`, warm-started from the last pressure (in one thread
      for small grids, `cg_serial`; else one parallel launch per CG stage).
Boundaries: inlet faces at the bottom carry a set superficial velocity (eps_f u_f = U_in);
the top is a pressure outlet (p = 0 on the face); other box sides and faces of solid cells
(cells whose centre lies in a tube) are walls (u_f = 0, zero normal pressure gradient);
periodic axes wrap.
Gas energy (finite volume, particle exchange implicit, so stable for any exchange rate):
  rho c [eps^{n+1} T^{n+1} - eps^n T^n] V / dt + rho c sum_f (eps u)_f A_f T_f
      = HT - H T^{n+1} + H_w (T_w - T^{n+1}) + k_g sum_f eps_f A_f (T_nb - T^n) / h_f,
the last term Fourier conduction through the gas across interior faces (explicit, with
`conduction`; none through walls, inlet or outlet; it needs alpha_g dt sum 1/h^2 within the
limit `tidem.gas_limits.gas_step_checks` enforces),
T_f on interior faces the MUSCL value T_up + phi(r) (T_up - T_far) / 2 with van Leer's limiter
phi(r) = (r + |r|)/(1 + |r|), r = (T_down - T_up)/(T_up - T_far) (van Leer 1979; total
variation diminishing for Courant numbers up to 0.5, the limit the gas step enforces); T_far
is the second cell upwind, the inlet temperature below the first cell, and where there is none
(walls, the outlet) the face takes the upwind value (first order). Inlet faces carry T_in.
with H_w = h_w eps A_w the convection from a heated tube over the tube area A_w the cell
borders (`tube_convection`): h_w = Nu k_g / D, Churchill & Bernstein (1977) for a cylinder in
cross flow, Nu = 0.3 + 0.62 Re^1/2 Pr^1/3 / [1 + (0.4/Pr)^2/3]^1/4 [1 + (Re/282000)^5/8]^4/5,
Re = rho |u| D / mu at the cell's gas velocity. The heat each tube gives the gas is summed
into wall_rate [W] and, over time, wall_energy [J].
  (+ Qs / dt, heat handed back by particles that reacted away, with reactions).
"""

import taichi as ti

from .gas_grid import make_cic

CLOSED, INTERIOR, INLET, OUTLET = 0, 1, 2, 3
SERIAL_CELLS = 50_000  # grids up to this size solve the pressure in one thread (measured faster, deterministic)


def make_flow_kernels(gg, G, rho: float, mu: float, gravity, heat: bool = False, rho_c: float = 1.0,
                      tube_walls: bool = False, k_gas: float = 0.026, prandtl: float = 0.7, sources: bool = False,
                      conduction: bool = False):
    """Return a dict of kernels for gas grid `gg` and fields `G` (see `tidem.gas_fields`); `tube_walls`
    adds convection from heated tubes (fields wall_A, wall_T, wall_D, wall_k, wall_rate, wall_energy),
    `sources` the heat of particles that reacted away (Qs) and the boundary enthalpy sum (bsum),
    `conduction` Fourier conduction through the gas."""
    cic, corner, weight = make_cic(gg)
    n = gg.cells
    small = n[0] * n[1] * n[2] <= SERIAL_CELLS
    per = gg.periodic
    h = ti.Vector(list(gg.h))
    lo = ti.Vector(list(gg.lo))
    nu = mu / rho
    g = ti.Vector(list(gravity))
    vol = gg.volume
    area = ti.Vector([gg.h[1] * gg.h[2], gg.h[0] * gg.h[2], gg.h[0] * gg.h[1]])
    U, US, A, C, K, GP = G.u, G.us, G.A, G.C, G.kind, G.gp

    @ti.func
    def unit(c: ti.template()):
        e = ti.Vector([0, 0, 0])
        e[c] = 1
        return e

    @ti.func
    def cell_index(I):
        """Wrap periodic axes, clamp open ones."""
        for a in ti.static(range(3)):
            if ti.static(per[a]):
                I[a] = I[a] % n[a]
            else:
                I[a] = ti.min(ti.max(I[a], 0), n[a] - 1)
        return I

    @ti.func
    def face_index(I, c: ti.template()):
        for a in ti.static(range(3)):
            if ti.static(per[a]):
                I[a] = I[a] % n[a]
            else:
                top = n[a] - 1
                if ti.static(a == c):
                    top = n[a]
                I[a] = ti.min(ti.max(I[a], 0), top)
        return I

    @ti.func
    def face_eps(I, c: ti.template()):
        return 0.5 * (G.eps[cell_index(I - unit(c))] + G.eps[cell_index(I)])

    @ti.func
    def sample(F: ti.template(), c: ti.template(), x):
        base, frac = cic(x, c)
        out = 0.0
        for o in ti.static(ti.grouped(ti.ndrange(2, 2, 2))):
            out += weight(frac, o) * F[corner(base, o, c)]
        return out

    @ti.kernel
    def predict(dt: ti.f64):
        for c in ti.static(range(3)):
            for I in ti.grouped(U[c]):
                kind = K[c][I]
                ef = face_eps(I, c)
                if kind == INLET:
                    US[c][I] = G.inlet[I[0], I[1]] / ef
                    A[c][I] = 0.0
                elif kind == CLOSED:
                    US[c][I] = 0.0
                    A[c][I] = 0.0
                else:
                    xf = lo + (I + 0.5) * h
                    xf[c] -= 0.5 * h[c]
                    vel = ti.Vector([sample(U[0], 0, xf), sample(U[1], 1, xf), sample(U[2], 2, xf)])
                    u_adv = sample(U[c], c, xf - dt * vel)
                    lap = 0.0
                    for a in ti.static(range(3)):
                        e = unit(a)
                        lap += (U[c][face_index(I + e, c)] - 2.0 * U[c][I] + U[c][face_index(I - e, c)]) / (h[a] * h[a])
                    b = G.B[c][I] / vol
                    denom = rho * ef + dt * b
                    US[c][I] = (rho * ef * (u_adv + dt * (nu * lap + g[c])) + dt * G.Bv[c][I] / vol) / denom
                    A[c][I] = dt * ef / denom
                    coef = ef * A[c][I] / (h[c] * h[c])
                    if kind == OUTLET:
                        coef *= 2.0
                    C[c][I] = coef
                if kind == CLOSED or kind == INLET:
                    C[c][I] = 0.0

    @ti.func
    def apply(x: ti.template(), I):
        """(-L x)_I: sum over faces of C_f (x_I - x_neighbour); identity on solid cells."""
        out = x[I]
        if G.solid[I] == 0:
            out = 0.0
            for c in ti.static(range(3)):
                e = unit(c)
                fm = I
                fp = face_index(I + e, c)
                cm = C[c][fm]
                cp = C[c][fp]
                if K[c][fm] == OUTLET:
                    out += cm * x[I]
                elif cm > 0.0:
                    out += cm * (x[I] - x[cell_index(I - e)])
                if K[c][fp] == OUTLET:
                    out += cp * x[I]
                elif cp > 0.0:
                    out += cp * (x[I] - x[cell_index(I + e)])
        return out

    @ti.kernel
    def assemble(dt: ti.f64) -> ti.f64:
        """rhs b = -(div(eps u*) + d eps/dt), Jacobi diagonal; return |b|^2."""
        bb = 0.0
        if ti.static(small):
            ti.loop_config(serialize=True)  # |b|^2 in cell order, so the CG stops at the same iteration every run
        for I in ti.grouped(G.p):
            b = 0.0
            dg = 1.0
            if G.solid[I] == 0:
                dg = 0.0
                div = (G.eps[I] - G.eps_old[I]) / dt
                for c in ti.static(range(3)):
                    e = unit(c)
                    fp = face_index(I + e, c)
                    div += (face_eps(fp, c) * US[c][fp] - face_eps(I, c) * US[c][I]) / h[c]
                    dg += C[c][I] + C[c][fp]
                b = -div
            G.rhs[I] = b
            G.diag[I] = ti.max(dg, 1e-300)
            bb += b * b
        return bb

    @ti.kernel
    def cg_start() -> ti.f64:
        """r = b + L p (warm start), z = r / diag, d = z; return r.z."""
        rz = 0.0
        for I in ti.grouped(G.p):
            r = G.rhs[I] - apply(G.p, I)
            if G.solid[I] == 1:
                r = 0.0
            G.cg_r[I] = r
            z = r / G.diag[I]
            G.cg_d[I] = z
            rz += r * z
        return rz

    @ti.kernel
    def cg_apply() -> ti.f64:
        """q = -L d; return d.q."""
        dq = 0.0
        for I in ti.grouped(G.p):
            q = apply(G.cg_d, I)
            if G.solid[I] == 1:
                q = 0.0
            G.cg_q[I] = q
            dq += G.cg_d[I] * q
        return dq

    @ti.kernel
    def cg_update(alpha: ti.f64):
        """p += alpha d, r -= alpha q; sums[0] = r.z, sums[1] = r.r with z = r / diag."""
        G.sums[0] = 0.0
        G.sums[1] = 0.0
        for I in ti.grouped(G.p):
            G.p[I] += alpha * G.cg_d[I]
            r = G.cg_r[I] - alpha * G.cg_q[I]
            G.cg_r[I] = r
            G.sums[0] += r * r / G.diag[I]
            G.sums[1] += r * r

    @ti.kernel
    def cg_direction(beta: ti.f64):
        for I in ti.grouped(G.p):
            G.cg_d[I] = G.cg_r[I] / G.diag[I] + beta * G.cg_d[I]

    @ti.kernel
    def cg_serial(max_iterations: ti.i32, tol_abs: ti.f64) -> ti.i32:
        """The whole CG solve in one thread (small grids: no launch or thread-pool cost per
        iteration); returns the iterations, leaves |r|^2 in sums[1]."""
        ti.loop_config(serialize=True)
        for _ in range(1):
            rz = 0.0
            for i, j, k in ti.ndrange(n[0], n[1], n[2]):
                I = ti.Vector([i, j, k])
                r = 0.0
                if G.solid[I] == 0:
                    r = G.rhs[I] - apply(G.p, I)
                G.cg_r[I] = r
                G.cg_d[I] = r / G.diag[I]
                rz += r * r / G.diag[I]
            it = 0
            rr = rz
            while it < max_iterations:
                dq = 0.0
                for i, j, k in ti.ndrange(n[0], n[1], n[2]):
                    I = ti.Vector([i, j, k])
                    q = 0.0
                    if G.solid[I] == 0:
                        q = apply(G.cg_d, I)
                    G.cg_q[I] = q
                    dq += G.cg_d[I] * q
                it += 1
                if dq <= 0.0:
                    break
                alpha = rz / dq
                rz_new = 0.0
                rr = 0.0
                for i, j, k in ti.ndrange(n[0], n[1], n[2]):
                    I = ti.Vector([i, j, k])
                    G.p[I] += alpha * G.cg_d[I]
                    r = G.cg_r[I] - alpha * G.cg_q[I]
                    G.cg_r[I] = r
                    rz_new += r * r / G.diag[I]
                    rr += r * r
                if ti.sqrt(rr) <= tol_abs:
                    break
                beta = rz_new / rz
                rz = rz_new
                for i, j, k in ti.ndrange(n[0], n[1], n[2]):
                    I = ti.Vector([i, j, k])
                    G.cg_d[I] = G.cg_r[I] / G.diag[I] + beta * G.cg_d[I]
            G.sums[1] = rr
            G.sums[0] = it
        return ti.cast(G.sums[0], ti.i32)

    @ti.kernel
    def correct():
        """Extend p into solid cells, pressure gradient on every face, u = u* - A grad p."""
        for I in ti.grouped(G.p):
            if G.solid[I] == 1:
                s = 0.0
                m = 0
                for c in ti.static(range(3)):
                    for sgn in ti.static((-1, 1)):
                        J = cell_index(I + sgn * unit(c))
                        if G.solid[J] == 0:
                            s += G.p[J]
                            m += 1
                G.p[I] = s / ti.max(m, 1)
        for c in ti.static(range(3)):
            for I in ti.grouped(U[c]):
                e = unit(c)
                grad = 0.0
                inside = 1
                if ti.static(not per[c]):
                    inside = 0
                    if I[c] > 0 and I[c] < n[c]:
                        inside = 1
                if K[c][I] == OUTLET:
                    grad = -G.p[cell_index(I - e)] / (0.5 * h[c])
                elif inside == 1:
                    grad = (G.p[cell_index(I)] - G.p[cell_index(I - e)]) / h[c]
                elif ti.static(n[c] > 1):
                    J = I
                    if I[c] == 0:
                        J[c] = 1
                    else:
                        J[c] = n[c] - 1
                    grad = (G.p[cell_index(J)] - G.p[cell_index(J - e)]) / h[c]
                GP[c][I] = grad
                U[c][I] = US[c][I] - A[c][I] * grad

    @ti.kernel
    def divergence(dt: ti.f64) -> ti.f64:
        """max over fluid cells of |d eps/dt + div(eps u)| [1/s] after the correction."""
        worst = 0.0
        for I in ti.grouped(G.p):
            if G.solid[I] == 0:
                div = (G.eps[I] - G.eps_old[I]) / dt
                for c in ti.static(range(3)):
                    fp = face_index(I + unit(c), c)
                    div += (face_eps(fp, c) * U[c][fp] - face_eps(I, c) * U[c][I]) / h[c]
                ti.atomic_max(worst, ti.abs(div))
        return worst

    @ti.kernel
    def courant(dt: ti.f64) -> ti.f64:
        """Largest face Courant number |u| dt / h."""
        worst = 0.0
        for c in ti.static(range(3)):
            for I in ti.grouped(U[c]):
                ti.atomic_max(worst, ti.abs(U[c][I]) * dt / h[c])
        return worst

    pr3 = prandtl ** (1.0 / 3.0)
    cb_denominator = (1.0 + (0.4 / prandtl) ** (2.0 / 3.0)) ** 0.25

    @ti.func
    def wall_conductance(I):
        """H_w = h_w eps A_w [W/K] of a cell bordering a heated tube (Churchill-Bernstein)."""
        speed2 = 0.0
        for c in ti.static(range(3)):
            uc = 0.5 * (U[c][face_index(I, c)] + U[c][face_index(I + unit(c), c)])
            speed2 += uc * uc
        d = G.wall_D[I]
        re = rho * ti.sqrt(speed2) * d / mu
        nu_w = 0.3 + 0.62 * ti.sqrt(re) * pr3 / cb_denominator * (1.0 + (re / 282000.0) ** 0.625) ** 0.8
        return nu_w * k_gas / d * G.eps[I] * G.wall_A[I]

    @ti.func
    def muscl_face(F: ti.template(), f, c: ti.template(), f_in):
        """MUSCL value of F on interior face f of axis c, van Leer-limited (module docstring)."""
        e = unit(c)
        up = f - e
        down = f
        far = f - 2 * e
        if U[c][f] < 0.0:
            up = f
            down = f - e
            far = f + e
        f_up = F[cell_index(up)]
        f_far = f_up  # no second upwind cell: first order
        if ti.static(per[c]):
            f_far = F[cell_index(far)]
        else:
            if far[c] >= 0 and far[c] < n[c]:
                f_far = F[far]
            if ti.static(c == 2):
                if far[c] < 0 and K[2][up] == INLET:
                    f_far = f_in
        if G.solid[cell_index(far)] == 1:
            f_far = f_up
        d1 = f_up - f_far
        d2 = F[cell_index(down)] - f_up
        slope = 0.0
        if d1 * d2 > 0.0:
            slope = 2.0 * d1 * d2 / (d1 + d2)  # phi(r) d1 of van Leer
        return f_up + 0.5 * slope

    @ti.func
    def upwind(F: ti.template(), I, f_in, muscl: ti.template()):
        """Sum over the faces of cell I of (eps u)_f A_f F_f (outward positive) [unit of F m^3/s],
        and the part of it through the inlet and outlet faces; F_f is the upwind cell's value (or
        with `muscl` the limited MUSCL value, `muscl_face`) on interior faces, f_in on inlet faces
        and the cell's own value on outflow (or backflow) at the outlet."""
        net = 0.0
        boundary = 0.0
        for c in ti.static(range(3)):
            e = unit(c)
            for side in ti.static((0, 1)):
                f = I
                if ti.static(side == 1):
                    f = face_index(I + e, c)
                kind = K[c][f]
                if kind != CLOSED:
                    flux = face_eps(f, c) * U[c][f] * area[c]
                    if ti.static(side == 0):
                        flux = -flux
                    f_face = F[I]
                    if kind == INLET:
                        f_face = f_in
                    elif kind == INTERIOR:
                        if ti.static(muscl):
                            f_face = muscl_face(F, f, c, f_in)
                        elif flux < 0.0:
                            nb = I - e
                            if ti.static(side == 1):
                                nb = I + e
                            f_face = F[cell_index(nb)]
                    net += flux * f_face
                    if kind != INTERIOR:
                        boundary += flux * f_face
        return net, boundary

    @ti.func
    def interior_diffusion(F: ti.template(), I):
        """Sum over the interior faces of cell I of eps_f A_f (F_nb - F_I) / h [unit of F m]: the
        diffusive exchange of gas conduction (here) and of species transport (`species`)."""
        out = 0.0
        for c in ti.static(range(3)):
            e = unit(c)
            for side in ti.static((0, 1)):
                f = I
                nb = I - e
                if ti.static(side == 1):
                    f = face_index(I + e, c)
                    nb = I + e
                if K[c][f] == INTERIOR:
                    out += face_eps(f, c) * area[c] * (F[cell_index(nb)] - F[I]) / h[c]
        return out

    @ti.kernel
    def energy(dt: ti.f64, t_in: ti.f64):
        """Advection of eps T (MUSCL faces) with implicit particle and tube exchange (module docstring);
        with `sources`, plus the heat Qs [J] particles handed to the gas, and the enthalpy that
        entered through the inlet and outlet summed in bsum[0] [J]."""
        if ti.static(tube_walls):
            for k in G.wall_rate:
                G.wall_rate[k] = 0.0
        for I in ti.grouped(G.T):
            G.T_new[I] = G.T[I]
            if G.solid[I] == 0:
                net, boundary = upwind(G.T, I, t_in, True)
                extra = 0.0
                if ti.static(sources):
                    extra = G.Qs[I]
                    G.Qs[I] = 0.0
                    G.bsum[0] += -dt * rho_c * boundary
                if ti.static(conduction):
                    extra += dt * k_gas * interior_diffusion(G.T, I)
                hw = 0.0  # tube convection conductance [W/K] and its heat source hw T_w [W]
                hw_tw = 0.0
                if ti.static(tube_walls):
                    if G.wall_A[I] > 0.0:
                        hw = wall_conductance(I)
                        hw_tw = hw * G.wall_T[I]
                G.T_new[I] = (rho_c * (G.eps_old[I] * G.T[I] * vol - dt * net) + dt * (G.HT[I] + hw_tw) + extra) \
                    / (rho_c * G.eps[I] * vol + dt * (G.H[I] + hw))
                if ti.static(tube_walls):
                    if hw > 0.0:
                        flow = hw * (G.wall_T[I] - G.T_new[I])
                        ti.atomic_add(G.wall_rate[G.wall_k[I]], flow)
                        ti.atomic_add(G.wall_energy[G.wall_k[I]], dt * flow)
        for I in ti.grouped(G.T):
            G.T[I] = G.T_new[I]

    kernels = dict(predict=predict, assemble=assemble, cg_start=cg_start, cg_apply=cg_apply, cg_update=cg_update,
                   cg_direction=cg_direction, cg_serial=cg_serial, correct=correct, divergence=divergence, courant=courant)
    if heat:
        kernels["energy"] = energy
    kernels["upwind"] = upwind
    kernels["interior_diffusion"] = interior_diffusion
    return kernels
