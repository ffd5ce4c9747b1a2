"""Gas energy on the staggered grid, and the face fluxes it shares with species transport.

Gas energy (finite volume, particle exchange implicit, so stable for any exchange rate):
  rho c [eps^{n+1} T^{n+1} - eps^n T^n] V / dt + rho c sum_f (eps u)_f A_f T_f
      = HT - H T^{n+1} + H_w (T_w - T^{n+1}) + k_g sum_f eps_f A_f (T_nb - T^n) / h_f,
the last term Fourier conduction through the gas across interior faces (explicit, with
`conduction`; none through walls, inlet or outlet; it needs alpha_g dt sum 1/h^2 within the
limit `tidem.gas.limits.gas_step_checks` enforces),
T_f on interior faces the MUSCL value T_up + phi(r) (T_up - T_far) / 2 with van Leer's limiter
phi(r) = (r + |r|)/(1 + |r|), r = (T_down - T_up)/(T_up - T_far) (van Leer 1979; total
variation diminishing for Courant numbers up to 0.5, the limit the gas step enforces); T_far
is the second cell upwind, the inlet temperature below the first cell, and where there is none
(walls, the outlet) the face takes the upwind value (first order). Inlet faces carry T_in.
with H_w the convection from a heated tube over the tube area A_w the cell borders
(`tube_convection`). "churchill_bernstein": H_w = h_cb eps A_w, h_cb = Nu k_g / D for a cylinder
in cross flow (Churchill & Bernstein 1977),
Nu = 0.3 + 0.62 Re^1/2 Pr^1/3 / [1 + (0.4/Pr)^2/3]^1/4 [1 + (Re/282000)^5/8]^4/5,
Re = rho |u| D / mu at the cell's gas velocity. "martin_nilles": the cell is read as a share
phi = min(1, (1 - eps) / (1 - EPS_PACKED)) of packed emulsion and 1 - phi of free gas,
H_w = [phi h_pb + (1 - phi) h_cb] A_w, h_pb the flow term of a packed bed's wall coefficient,
h_pb d / k_g = 0.19 Re_0^0.75 Pr^1/3, Re_0 = rho U_0 d / mu (Martin & Nilles 1993; d the
grains' Sauter diameter): grains break the gas's boundary layer at the tube every diameter,
which a bare cylinder's correlation (length D) misses. The emulsion's superficial velocity is
the cell's, U_0 = eps |u|, up to the minimum fluidization velocity U_mf: a bubbling bed's
emulsion stays near minimum fluidization and bubbles carry the excess (two-phase theory,
Toomey & Johnstone 1952). The heat each tube gives the gas is
summed into wall_rate [W] and, over time, wall_energy [J].
  (+ Qs / dt, heat handed back by particles that reacted away, with reactions).
"""

import taichi as ti

from .gas_grid import CLOSED, INLET, INTERIOR, serial_loops
from .ordered import in_order

EPS_PACKED = 0.4  # voidage of the packed emulsion in the "martin_nilles" tube convection (Martin & Nilles' beds)


def make_energy_kernels(gg, G, index, rho: float, mu: float, heat: bool, rho_c: float, tube_walls: bool,
                        k_gas: float, prandtl: float, sources: bool, conduction: bool, wall_grain: float = 0.0,
                        wall_umf: float = 0.0) -> dict:
    """Return {"upwind", "interior_diffusion"} (Taichi funcs, also used by `species`) and with
    `heat` the kernel "energy", for gas grid `gg`, fields `G` and the grid's index functions
    `index` (unit, cell_index, face_index, face_eps of `gas_flow.make_flow_kernels`); `wall_grain`
    > 0 (the grains' Sauter diameter [m]) takes the "martin_nilles" tube convection, its emulsion's
    velocity capped at `wall_umf` [m/s]."""
    n = gg.cells
    per = gg.periodic
    h = ti.Vector(list(gg.h))
    vol = gg.volume
    ordered = in_order()
    serial = serial_loops(gg)  # the grid's loops in one thread (small grids on the CPU)
    cells = tuple(n)
    area = ti.Vector([gg.h[1] * gg.h[2], gg.h[0] * gg.h[2], gg.h[0] * gg.h[1]])
    U, K = G.u, G.kind
    unit, cell_index, face_index, face_eps = index.unit, index.cell_index, index.face_index, index.face_eps
    aperture, part, cut_faces = index.aperture, index.part, index.cut_faces

    pr3 = prandtl ** (1.0 / 3.0)
    cb_denominator = (1.0 + (0.4 / prandtl) ** (2.0 / 3.0)) ** 0.25

    @ti.func
    def wall_conductance(I):
        """H_w [W/K] of a cell bordering a heated tube (module docstring)."""
        speed2 = 0.0
        for c in ti.static(range(3)):
            uc = 0.5 * (U[c][face_index(I, c)] + U[c][face_index(I + unit(c), c)])
            speed2 += uc * uc
        speed = ti.sqrt(speed2)
        d = G.wall_D[I]
        re = rho * speed * d / mu
        h_cb = (0.3 + 0.62 * ti.sqrt(re) * pr3 / cb_denominator * (1.0 + (re / 282000.0) ** 0.625) ** 0.8) * k_gas / d
        eps = G.eps[I]
        h = h_cb * eps
        if ti.static(wall_grain > 0.0):
            phi = ti.min(1.0, (1.0 - eps) / (1.0 - EPS_PACKED))
            re0 = rho * ti.min(eps * speed, wall_umf) * wall_grain / mu
            h_pb = 0.19 * re0 ** 0.75 * pr3 * k_gas / wall_grain
            h = phi * h_pb + (1.0 - phi) * h_cb
        return h * G.wall_A[I]

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
        if ti.static(cut_faces):
            if part(cell_index(up)) < 1.0 or part(cell_index(down)) < 1.0:
                slope = 0.0  # a face of a cut cell: first order (`gas_checks.courant`)
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
                    flux = aperture(f, c) * face_eps(f, c) * U[c][f] * area[c]
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
                    out += aperture(f, c) * face_eps(f, c) * area[c] * (F[cell_index(nb)] - F[I]) / h[c]
        return out

    @ti.kernel
    def energy(dt: ti.f64, t_in: ti.f64):
        """Advection of eps T (MUSCL faces) with implicit particle and tube exchange (module docstring);
        with `sources`, plus the heat Qs [J] particles handed to the gas, and the enthalpy that
        entered through the inlet and outlet summed in bsum[0] [J]."""
        if ti.static(tube_walls):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for k in range(G.wall_rate.shape[0]):
                G.wall_rate[k] = 0.0
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
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
                v = vol * part(I)
                G.T_new[I] = (rho_c * (G.eps_old[I] * G.T[I] * v - dt * net) + dt * (G.HT[I] + hw_tw) + extra) \
                    / (rho_c * G.eps[I] * v + dt * (G.H[I] + hw))
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
            G.T[I] = G.T_new[I]
        if ti.static(tube_walls):
            if ti.static(ordered):
                ti.loop_config(serialize=True)  # each tube's heat flow summed in cell order: the same bits every run
            for I in ti.grouped(ti.ndrange(*cells)):
                if G.solid[I] == 0 and G.wall_A[I] > 0.0:
                    flow = wall_conductance(I) * (G.wall_T[I] - G.T[I])
                    G.wall_rate[G.wall_k[I]] += flow
                    G.wall_energy[G.wall_k[I]] += dt * flow

    kernels = dict(upwind=upwind, interior_diffusion=interior_diffusion, part=part)
    if heat:
        kernels["energy"] = energy
    return kernels
