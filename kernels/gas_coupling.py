"""Particle <-> gas exchange: voidage, drag, pressure-gradient force, heat exchange.

At each gas step (every `coupling_interval` DEM steps):
  deposit_volume: eps_c = 1 - sum_p w_pc V_p / (f_c V_cell) (cloud-in-cell, `gas_grid.make_cic`;
                  f_c the open fraction of a cell a mesh cuts, `tidem.gas.mesh`, else 1),
                  clipped below at `min_voidage`. With `layers` = m > 1 the solid volume is also
                  deposited on layers m times thinner than a cell (about one grain high;
                  same cells across), for the voidage a grain sees (below).
  couple:         per particle, eps_p and u_p interpolated with the same weights; the drag
                  coefficient K_p (`drag.make_drag`) and heat conductance H_p = h_p pi d^2
                  (`drag.make_nusselt`) are frozen until the next gas step (the largest
                  H_p / (m_p c_p) of a non-reacting particle is kept in G.heat_rate for the
                  step limit); then (a second loop: the coefficients in parallel, the deposits
                  in particle order on the CPU) K_p w_pf is added
                  to face f's implicit drag coefficient B_f and K_p w_pf v_p to Bv_f, and with
                  heat H_p w_pc to the cell's H_c and H_p w_pc T_p to HT_c.
                  Layered (m > 1, `gas.voidage = "layered"`): eps_p from the layers
                  (`kernels/layered_voidage.py`), u_p = sum_f w_pf eps_f u_f / eps_p (the superficial velocity
                  over the grain's own voidage) and K_p = K(eps_p) s_p, s_p = min(eps_c,p / eps_p, 2)
                  with eps_c,p the cells' voidage at the grain: the gas carries -eps_c grad p, so a
                  grain's whole fluid force is about its drag / eps_c, and s_p makes that its own
                  voidage's, K(eps_p) (u_p - v_p) / eps_p (a settled bed then carries Ergun over its
                  own voidage profile, surface layer included); the face gets K_p w_pf eps_f / eps_p
                  in B_f (and K_p w_pf v_p in Bv_f), which keeps the exchange exactly opposite.
  sample:         after the gas step, u_p (layered: from the superficial velocity over the frozen
                  eps_p), grad p_p and T_g,p (and Y_O2,p) at each particle.
Every DEM step (`add_gas_forces`): f_p += K_p (u_p - v_p) - V_p grad p_p (source 1, Tsuji
form, the gas carrying -eps grad p), and q_p += H_p (T_g,p - T_p).
Below the first cell centre, where gas enters through the distributor, the gas temperature
is interpolated between the inlet face (T_in) and the bottom cell: the lattice point below
the bottom cell c takes the mirror value 2 T_in - T_c (a convex combination for any particle
above the distributor, so no overshoot). That share of the exchange, w H_p (T_p - 2 T_in + T_c),
is charged to the bottom cell (T_c implicit), so the heat exchanged still balances exactly.
With tubes or meshes in the gas every one of these weights is taken over the cells and faces the gas
flows in (`kernels/gas_weights.py`): a grain beside a wall neither puts its volume, drag and heat where
the gas never sees them nor reads the gas there.
Because interpolation and deposition share weights that sum to 1, the drag the gas feels,
sum_f B_f u_f - Bv_f, equals minus the sum of the particle drag forces at the gas step
(momentum exchange balances exactly), and likewise for heat.
"""

import math

import taichi as ti

from .drag import make_drag, make_nusselt
from .exchange_filter import make_exchange_filter
from .gas_grid import make_cic, serial_loops
from .gas_smoothing import Filter, make_filter, make_open_shares
from .gas_weights import make_gas_weights, make_in_gas, plain_weights
from .layered_voidage import make_layered_voidage
from .ordered import in_order

MAX_SCALE = 2.0  # cap of eps_c / eps_p: the margin of the drag-relaxation check (`tidem.gas.limits`)


def make_coupling_kernels(gg, G, S, drag_model: int, rho: float, mu: float, min_voidage: float,
                          heat: bool = False, nusselt_model: int = 0, prandtl: float = 0.7, k_gas: float = 0.026,
                          species: bool = False, tracer_dt: float = 0.0,
                          coarse_grain: bool = False, cut_cells: bool = False, layers: int = 1, rows: int = 1,
                          cell_filter: Filter | None = None, layer_filter: Filter | None = None,
                          exchange_filter: Filter | None = None):
    """Return (deposit_volume(n), couple(n), sample(n), add_gas_forces(n), gas_force(i, t)) for
    particles S and gas G (gas_force: add_gas_forces for one particle, a Taichi func);
    with `species`, `sample` also gives each particle the O2 mass fraction of the gas, gY. With
    `tracer_dt` (the DEM step, scenes with reactions) a reacting particle's drag coefficient is
    capped at m / (2 dt): one that shrank below the drag relaxation limit follows the gas
    (tracer limit) instead of making the explicit drag update unstable. With `heat`, the inlet gas
    temperature G.t_in[0] (set by the host before each gas step, `tidem.gas.phase`) is used below the
    first cell centre. With `coarse_grain`, particle i is a parcel of
    k^3 grains of diameter d_p / k (k = S.cg[i]): drag and heat exchange are those of one grain
    times k^3 (K_p = k^3 K(eps, d_p/k, w), H_p = k^3 h(d_p/k) pi (d_p/k)^2; the per-grain
    closures of MFiX's CGDEM and CFDEM's coarse-grained models), which keeps the grains'
    terminal velocity, drag relaxation time and lumped heating time; the pressure-gradient
    force and the voidage take the parcel's volume, k^3 grains' volume. With `cut_cells` (meshes or
    tubes in the gas) the voidage is taken over each cell's open volume G.open, and the weights over the
    cells and faces the gas flows in (`kernels/gas_weights.py`). With `layers` > 1
    (G.solid_layer allocated) a grain's voidage comes from horizontal layers `layers` times thinner
    than a gas cell (`kernels/layered_voidage.py`; `rows` > 1: a parcel stands in up to `rows` rows of its
    grains). With `cell_filter` / `layer_filter` (`gas.averaging_length`) the solid
    volume deposited on the cells / layers is filtered to that averaging length before the voidage is taken
    (`kernels/gas_smoothing.py`; G.solid_tmp / G.layer_tmp allocated). With `exchange_filter` (`gas.drag_averaging =
    "length"`) the drag deposited on the faces is spread by that filter and the gas velocity the particles read is
    taken through its transpose (`kernels/exchange_filter.py`; G.uf, G.face_tmp, G.face_tmp2 allocated); otherwise
    the drag keeps its CIC weights. Either way the exchange balances exactly; the heat keeps its CIC weights."""
    cic, corner, weight, corners = make_cic(gg)
    layered = layers > 1
    share, gweight, _ = plain_weights(weight)
    if cut_cells:
        in_gas, _ = make_in_gas(gg, G, layers)
        share, gweight, _ = make_gas_weights(corner, weight, corners, in_gas)
    deposit_layers = layered_voidage = None  # used only when layered
    if layered:
        deposit_layers, layered_voidage = make_layered_voidage(
            gg, G, S, layers, rows, cut_cells, min_voidage, cell_filter.own if cell_filter else None,
            layer_filter.own if layer_filter else None)
    drag_coefficient = make_drag(drag_model, rho, mu)
    nusselt = make_nusselt(nusselt_model, rho, mu, prandtl)
    inv_vol = 1.0 / gg.volume
    ordered = in_order()
    serial = serial_loops(gg)  # the grid's own loops in one thread (small grids on the CPU)
    cells = tuple(gg.cells)
    faces = [gg.face_shape(c) for c in range(3)]
    layer_cells = (cells[0], cells[1], cells[2] * layers)
    U = G.u
    B = G.B
    BV = G.Bv
    GP = G.gp

    @ti.func
    def sample_faces(F: ti.template(), x):
        out = ti.Vector([0.0, 0.0, 0.0])
        for c in ti.static(range(3)):
            base, frac = cic(x, c)
            s, m = share(base, frac, c)
            for o_t in ti.static(corners(c)):
                o = ti.Vector(o_t)
                out[c] += gweight(base, frac, o, c, s, m) * F[c][corner(base, o, c)]
        return out

    @ti.func
    def face_voidage(J, c: ti.template()):
        """eps_f of face J normal to axis c: the mean of its two cells (as `gas_flow`)."""
        below = J
        below[c] -= 1
        zero = ti.Vector([0, 0, 0])
        return 0.5 * (G.eps[corner(below, zero, -1)] + G.eps[corner(J, zero, -1)])

    filtered = exchange_filter is not None
    VEL = G.uf if filtered else U  # the gas velocity the particles read (filtered: u~ of eq. (4), layered: eps u)

    @ti.func
    def sample_superficial(x):
        """eps_f u_f interpolated to x, per component (the superficial velocity; filtered: G.uf holds it)."""
        out = ti.Vector([0.0, 0.0, 0.0])
        if ti.static(filtered):
            out = sample_faces(VEL, x)
        else:
            for c in ti.static(range(3)):
                base, frac = cic(x, c)
                s, m = share(base, frac, c)
                for o_t in ti.static(corners(c)):
                    o = ti.Vector(o_t)
                    J = corner(base, o, c)
                    out[c] += gweight(base, frac, o, c, s, m) * face_voidage(J, c) * U[c][J]
        return out

    @ti.func
    def sample_cells(F: ti.template(), x):
        base, frac = cic(x, -1)
        s, m = share(base, frac, -1)
        out = 0.0
        for o_t in ti.static(corners(-1)):
            o = ti.Vector(o_t)
            out += gweight(base, frac, o, -1, s, m) * F[corner(base, o, -1)]
        return out

    @ti.func
    def below_inlet(base, o, J):
        """Corner o lies below the bottom cell, where gas enters (inlet velocity > 0)."""
        return base[2] + o[2] < 0 and G.inlet[J[0], J[1]] > 0.0

    @ti.func
    def sample_temperature(x):
        """T_g at x, with the mirror value 2 T_in - T_c below the bottom cell over the inlet."""
        base, frac = cic(x, -1)
        s, m = share(base, frac, -1)
        out = 0.0
        for o_t in ti.static(corners(-1)):
            o = ti.Vector(o_t)
            J = corner(base, o, -1)
            t = G.T[J]
            if below_inlet(base, o, J):
                t = 2.0 * G.t_in[0] - G.T[J]
            out += gweight(base, frac, o, -1, s, m) * t
        return out

    @ti.func
    def volume(i):
        r = S.radius[i]
        return 4.0 / 3.0 * math.pi * r * r * r

    cell_open, layer_open = make_open_shares(G, cut_cells, layers)
    filters = []
    if cell_filter is not None:
        filters.append(make_filter(cell_filter, cells, gg.periodic, G.solid_vol, G.solid_tmp, cell_open, serial))
    if layer_filter is not None:
        filters.append(make_filter(layer_filter, layer_cells, gg.periodic, G.solid_layer, G.layer_tmp, layer_open,
                                   serial))

    def deposit_volume(n: int):
        """Deposit the particles' volume, filter it to the averaging length where one is set, take the voidage."""
        deposit_solids(n)
        for apply in filters:
            apply()
        set_voidage()

    @ti.kernel
    def deposit_solids(n: ti.i32):
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
            G.solid_vol[I] = 0.0
        if ti.static(layered):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*layer_cells)):
                G.solid_layer[I] = 0.0
        if ti.static(ordered):
            ti.loop_config(serialize=True)  # sums in particle order: bit-identical runs on any thread count
        for i in range(n):
            if S.active[i]:
                base, frac = cic(S.x[i], -1)
                vp = volume(i)
                s, m = share(base, frac, -1)
                for o_t in ti.static(corners(-1)):
                    o = ti.Vector(o_t)
                    G.solid_vol[corner(base, o, -1)] += gweight(base, frac, o, -1, s, m) * vp
                if ti.static(layered):
                    deposit_layers(i, vp)

    @ti.kernel
    def set_voidage():
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
            G.eps_old[I] = G.eps[I]
            open_vol = 1.0
            if ti.static(cut_cells):
                open_vol = G.open[I]
            G.eps[I] = ti.max(1.0 - G.solid_vol[I] * inv_vol / open_vol, min_voidage)

    @ti.func
    def deposit_exchange(i):
        """Add particle i's frozen K_p (and H_p) to the faces' B, Bv (and the cells' H, HT) with its CIC weights."""
        x = S.x[i]
        k = S.gK[i]
        for c in ti.static(range(3)):
            base, frac = cic(x, c)
            s, m = share(base, frac, c)
            for o_t in ti.static(corners(c)):
                o = ti.Vector(o_t)
                wk = gweight(base, frac, o, c, s, m) * k
                J = corner(base, o, c)
                if ti.static(layered and filtered):
                    B[c][J] += wk / S.geps[i]  # times eps_f after the filter (eq. (3) of `kernels/exchange_filter.py`)
                elif ti.static(layered):
                    B[c][J] += wk * face_voidage(J, c) / S.geps[i]
                else:
                    B[c][J] += wk
                BV[c][J] += wk * S.v[i][c]
        if ti.static(heat):
            hp = S.gH[i]
            base, frac = cic(x, -1)
            s, m = share(base, frac, -1)
            for o_t in ti.static(corners(-1)):
                o = ti.Vector(o_t)
                J = corner(base, o, -1)
                wh = gweight(base, frac, o, -1, s, m) * hp
                if below_inlet(base, o, J):
                    G.H[J] -= wh
                    G.HT[J] += wh * (S.T[i] - 2.0 * G.t_in[0])
                else:
                    G.H[J] += wh
                    G.HT[J] += wh * S.T[i]

    @ti.kernel
    def couple(n: ti.i32) -> ti.f64:
        """Freeze K_p (and H_p), each particle in parallel, then deposit them (in particle order on the
        CPU); return max over particles of K_p / m_p [1/s]."""
        for c in ti.static(range(3)):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*faces[c])):
                B[c][I] = 0.0
                BV[c][I] = 0.0
        if ti.static(heat):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*cells)):
                G.H[I] = 0.0
                G.HT[I] = 0.0
        # both largest rates in locals, which Taichi keeps per thread and merges at the loop's end: an
        # atomic max on G.heat_rate from every particle (both threads on one address) took 0.26 ms of
        # the 0.53 ms loop on fluidized_tube (`benchmarks/README.md`)
        rate = 0.0
        heat_rate_max = 0.0
        for i in range(n):
            if S.active[i]:
                x = S.x[i]
                eps = 0.0
                u = ti.Vector([0.0, 0.0, 0.0])
                scale = 1.0  # layered: eps_c / eps_p (the grain's whole fluid force at its own voidage)
                if ti.static(layered):
                    eps = layered_voidage(i, x, volume(i))
                    u = sample_superficial(x)
                    u /= eps
                    scale = ti.min(sample_cells(G.eps, x) / eps, MAX_SCALE)
                else:
                    eps = sample_cells(G.eps, x)
                    u = sample_faces(VEL, x)
                d = 2.0 * S.radius[i]
                grains = 1.0  # grains per parcel
                if ti.static(coarse_grain):
                    d /= S.cg[i]
                    grains = S.cg[i] ** 3
                w = (u - S.v[i]).norm()
                k = grains * drag_coefficient(eps, d, w) * scale
                if ti.static(tracer_dt > 0.0):
                    if S.rx[i] >= 0:
                        k = ti.min(k, 0.5 * S.mass[i] / tracer_dt)
                S.gK[i] = k
                S.geps[i] = eps
                ti.atomic_max(rate, k * S.inv_mass[i])
                if ti.static(heat):
                    h = nusselt(eps, d, w) * k_gas / d
                    hp = grains * h * math.pi * d * d
                    S.gH[i] = hp
                    heat_rate = hp * S.inv_heat_cap[i]
                    if ti.static(tracer_dt > 0.0):
                        if S.rx[i] >= 0:  # reacting: shrinks to nothing; kernels/reactions.py bounds its T
                            heat_rate = 0.0
                    ti.atomic_max(heat_rate_max, heat_rate)
        if ti.static(heat):
            G.heat_rate[0] = heat_rate_max
        if ti.static(ordered):
            ti.loop_config(serialize=True)  # deposits summed in particle order (determinism)
        for i in range(n):
            if S.active[i]:
                deposit_exchange(i)
        return rate

    @ti.kernel
    def sample(n: ti.i32):
        for i in range(n):
            if S.active[i]:
                x = S.x[i]
                if ti.static(layered):
                    S.gu[i] = sample_superficial(x) / S.geps[i]
                else:
                    S.gu[i] = sample_faces(VEL, x)
                S.ggp[i] = sample_faces(GP, x)
                if ti.static(heat):
                    S.gT[i] = sample_temperature(x)
                if ti.static(species):
                    S.gY[i] = sample_cells(G.Y, x)

    @ti.func
    def gas_force(i, t):
        """Drag, pressure-gradient force and gas heat exchange of particle i (t unused). Plain stores: the
        kick may take i from a slab list, where `S.f[i] += ...` would be an atomic (`kernels/contact.py`)."""
        S.f[i] = S.f[i] + S.gK[i] * (S.gu[i] - S.v[i]) - volume(i) * S.ggp[i]
        if ti.static(heat):
            S.q[i] = S.q[i] + S.gH[i] * (S.gT[i] - S.T[i])

    @ti.kernel
    def add_gas_forces(n: ti.i32):
        for i in range(n):
            if S.active[i]:
                gas_force(i, 0.0)

    if filtered:
        read_velocity, spread_drag = make_exchange_filter(exchange_filter, gg, G, layered, cut_cells, serial,
                                                          face_voidage)
        couple_kernel, sample_kernel = couple, sample

        def couple(n: int) -> float:
            """`couple` with the velocity read through the filter and the drag spread by it (eqs. (3)-(4))."""
            read_velocity()
            rate = couple_kernel(n)
            spread_drag()
            return rate

        def sample(n: int):
            read_velocity()
            sample_kernel(n)

    return deposit_volume, couple, sample, add_gas_forces, gas_force
