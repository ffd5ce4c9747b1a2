"""Locally averaged incompressible gas on the staggered grid: predictor, pressure projection
by preconditioned conjugate gradients, velocity correction.

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
      for small grids on the CPU, `cg_serial`; else in parallel, its scalars kept on the device,
      one launch per iteration on the CPU and per 8 on a GPU, `cg_iterate`); thin grids on the
      CPU solve it directly instead (banded Cholesky, `kernels/gas_band.py`).
Boundaries: inlet faces at the bottom carry a set superficial velocity (eps_f u_f = U_in);
the top is a pressure outlet (p = 0 on the face); other box sides and faces of solid cells
(cells whose centre lies in a tube) are walls (u_f = 0, zero normal pressure gradient), the side walls
free-slip or, with `no_slip`, holding the gas still (ghost value -u in the viscous term); periodic axes wrap.
Cut faces (meshes in the gas, `tidem.gas.apertures`): a face open over the share a_f of its area
carries the flux a_f eps_f u_f, u_f the gas velocity in its open part, and a cell whose gas part
is the share f of it holds f V of gas, so that the pressure equation reads
    sum_f a_f eps_f A_f (p_nb - p) / h^2 = f d(eps)/dt + sum_f +- a_f eps_f u*_f / h,
symmetric still (each face's coefficient a_f eps_f A_f / h^2 shared by its two cells); the gas
energy and species take the same fluxes and volumes. Without meshes a_f = f = 1.
Gas energy: `kernels/gas_energy.py`.
"""

from types import SimpleNamespace

import taichi as ti

from .gas_band import make_band_solve
from .gas_checks import make_check_kernels
from .gas_energy import make_energy_kernels
from .gas_grid import CLOSED, INLET, OUTLET, make_cic, serial_loops
from .ordered import in_order

SERIAL_CELLS = 50_000  # grids up to this size solve the pressure in one thread (measured faster, deterministic)
# The CG keeps its scalars in G.sums (RZ = r.z, DQ = d.q, RZ_NEW = the next r.z, RR = r.r), so that the
# host launches iterations without reading anything back (`tidem.gas.phase`, _project).
RZ, DQ, RZ_NEW, RR = range(4)
GPU_BATCH = 8  # parallel CG iterations per launch on a GPU (`cg_batch`)


def serial_solve(cells: int) -> bool:
    """Whether a grid of `cells` cells solves the pressure in one thread (`cg_serial`): small grids on
    the CPU; never on a GPU (`kernels/ordered.py`)."""
    return cells <= SERIAL_CELLS and in_order()


def cg_batch() -> int:
    """Iterations of the parallel CG per launch (`cg_iterate`) and per read of its residual: one on
    the CPU, where the solve stops at the first iteration within tolerance; GPU_BATCH on a GPU, where
    each launch and each read from the host waits for the device (the bubbling bed's 130 iterations
    per solve, a launch per stage and two reads per iteration, took 2.9 ms a step on an H100,
    `benchmarks/README.md`): the solve may go up to GPU_BATCH - 1 iterations past its tolerance."""
    return 1 if in_order() else GPU_BATCH


def make_flow_kernels(gg, G, rho: float, mu: float, gravity, heat: bool = False, rho_c: float = 1.0,
                      tube_walls: bool = False, k_gas: float = 0.026, prandtl: float = 0.7, sources: bool = False,
                      conduction: bool = False, wall_grain: float = 0.0,
                      wall_umf: float = 0.0, band: int = 0, open_faces: bool = False, cut_faces: bool = False,
                      no_slip: bool = False):
    """Return a dict of kernels for gas grid `gg` and fields `G` (see `tidem.gas.fields`); `tube_walls`
    adds convection from heated tubes (fields wall_A, wall_T, wall_D, wall_k, wall_rate, wall_energy;
    with `wall_grain` > 0, the grains' diameter, the packed-bed term in the particle-filled share, its
    velocity capped at `wall_umf`),
    `sources` the heat of particles that reacted away (Qs) and the boundary enthalpy sum (bsum),
    `conduction` Fourier conduction through the gas; `band` > 0 (`gas_band.band_width`) adds the direct
    pressure solve band_solve (fields band, band_y). With `open_faces` (tubes or meshes in the gas) a face's drag
    B_f, Bv_f acts over its open volume, G.open_face[c] times the face's volume (`tidem.gas.open_volume`). With
    `cut_faces` (meshes in the gas) each face carries its aperture G.aperture[c] and each cell its gas part's
    share G.part of its volume (`tidem.gas.apertures`): the fluxes a_f S_f (eps u)_f and the volume f V. `no_slip`:
    the box's side walls (x, y; not periodic) hold the gas still (module docstring)."""
    cic, corner, weight, corners = make_cic(gg)
    n = gg.cells
    small = serial_solve(n[0] * n[1] * n[2])
    serial = serial_loops(gg)
    cells = tuple(n)
    faces = [gg.face_shape(c) for c in range(3)]
    batch = cg_batch()
    per = gg.periodic
    h = ti.Vector(list(gg.h))
    lo = ti.Vector(list(gg.lo))
    nu = mu / rho
    g = ti.Vector(list(gravity))
    vol = gg.volume
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
    def aperture(I, c: ti.template()):
        """The open share of face I normal to c (1 without meshes)."""
        a = 1.0
        if ti.static(cut_faces):
            a = G.aperture[c][I]
        return a

    @ti.func
    def part(I):
        """The share of cell I its gas fills (1 without meshes)."""
        f = 1.0
        if ti.static(cut_faces):
            f = G.part[I]
        return f

    @ti.func
    def sample(F: ti.template(), c: ti.template(), x):
        base, frac = cic(x, c)
        out = 0.0
        for o_t in ti.static(corners(c)):
            o = ti.Vector(o_t)
            out += weight(frac, o, c) * F[corner(base, o, c)]
        return out

    @ti.kernel
    def predict(dt: ti.f64):
        for c in ti.static(range(3)):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*faces[c])):
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
                        up, down = U[c][face_index(I + e, c)], U[c][face_index(I - e, c)]
                        if ti.static(no_slip and a < 2 and a != c and not per[a]):  # mirror beyond a no-slip wall
                            up, down = ti.select(I[a] == n[a] - 1, -U[c][I], up), ti.select(I[a] == 0, -U[c][I], down)
                        lap += (up - 2.0 * U[c][I] + down) / (h[a] * h[a])
                    inv_vol = 1.0 / vol
                    if ti.static(open_faces):
                        inv_vol /= G.open_face[c][I]
                    b = G.B[c][I] * inv_vol
                    denom = rho * ef + dt * b
                    US[c][I] = (rho * ef * (u_adv + dt * (nu * lap + g[c])) + dt * G.Bv[c][I] * inv_vol) / denom
                    A[c][I] = dt * ef / denom
                    coef = ef * A[c][I] / (h[c] * h[c])
                    if ti.static(cut_faces):
                        coef *= G.aperture[c][I]
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
        for I in ti.grouped(ti.ndrange(*cells)):
            b = 0.0
            dg = 1.0
            if G.solid[I] == 0:
                dg = 0.0
                div = part(I) * (G.eps[I] - G.eps_old[I]) / dt
                for c in ti.static(range(3)):
                    e = unit(c)
                    fp = face_index(I + e, c)
                    div += (aperture(fp, c) * face_eps(fp, c) * US[c][fp] - aperture(I, c) * face_eps(I, c) * US[c][I]) \
                        / h[c]
                    dg += C[c][I] + C[c][fp]
                b = -div
            G.rhs[I] = b
            G.diag[I] = ti.max(dg, 1e-300)
            bb += b * b
        return bb

    @ti.kernel
    def cg_start():
        """r = b + L p (warm start), z = r / diag, d = z; sums[RZ] = r.z."""
        G.sums[RZ] = 0.0
        for I in ti.grouped(G.p):
            r = G.rhs[I] - apply(G.p, I)
            if G.solid[I] == 1:
                r = 0.0
            G.cg_r[I] = r
            z = r / G.diag[I]
            G.cg_d[I] = z
            G.sums[RZ] += r * z

    @ti.func
    def cg_apply():
        """q = -L d; sums[DQ] = d.q."""
        G.sums[DQ] = 0.0
        for I in ti.grouped(G.p):
            q = apply(G.cg_d, I)
            if G.solid[I] == 1:
                q = 0.0
            G.cg_q[I] = q
            G.sums[DQ] += G.cg_d[I] * q

    @ti.func
    def cg_update():
        """alpha = r.z / d.q (0 once d.q <= 0: the solve has stalled or converged to zero), p += alpha d,
        r -= alpha q; sums[RZ_NEW] = r.z, sums[RR] = r.r with z = r / diag."""
        alpha = 0.0
        if G.sums[DQ] > 0.0:
            alpha = G.sums[RZ] / G.sums[DQ]
        G.sums[RZ_NEW] = 0.0
        G.sums[RR] = 0.0
        for I in ti.grouped(G.p):
            G.p[I] += alpha * G.cg_d[I]
            r = G.cg_r[I] - alpha * G.cg_q[I]
            G.cg_r[I] = r
            G.sums[RZ_NEW] += r * r / G.diag[I]
            G.sums[RR] += r * r

    @ti.func
    def cg_direction():
        """d = z + beta d with beta = r.z (new) / r.z (old); sums[RZ] = the new r.z."""
        beta = 0.0
        if G.sums[RZ] > 0.0:
            beta = G.sums[RZ_NEW] / G.sums[RZ]
        G.sums[RZ] = G.sums[RZ_NEW]
        for I in ti.grouped(G.p):
            G.cg_d[I] = G.cg_r[I] / G.diag[I] + beta * G.cg_d[I]

    @ti.kernel
    def cg_iterate() -> ti.f64:
        """cg_batch() CG iterations in one launch, each loop a parallel stage; returns r.r."""
        for _ in ti.static(range(batch)):
            cg_apply()
            cg_update()
            cg_direction()
        return G.sums[RR]

    @ti.kernel
    def cg_serial(max_iterations: ti.i32, tol_abs: ti.f64) -> ti.i32:
        """The whole CG solve in one thread (small grids: no launch or thread-pool cost per
        iteration); returns the iterations, leaves |r|^2 in sums[RR]."""
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
            G.sums[RR] = rr
            G.sums[RZ] = it
        return ti.cast(G.sums[RZ], ti.i32)

    @ti.kernel
    def correct():
        """Extend p into solid cells, pressure gradient on every face, u = u* - A grad p."""
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
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
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*faces[c])):
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

    kernels = dict(predict=predict, assemble=assemble, cg_start=cg_start, cg_iterate=cg_iterate, cg_serial=cg_serial,
                   correct=correct)
    index = SimpleNamespace(unit=unit, cell_index=cell_index, face_index=face_index, face_eps=face_eps, apply=apply,
                            aperture=aperture, part=part, cut_faces=cut_faces)
    kernels.update(make_check_kernels(gg, G, index, cut_faces))
    if band:
        kernels["band_solve"] = make_band_solve(gg, G, index, band)
    kernels.update(make_energy_kernels(gg, G, index, rho, mu, heat, rho_c, tube_walls, k_gas, prandtl, sources,
                                       conduction, wall_grain, wall_umf))
    return kernels
