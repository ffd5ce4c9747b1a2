"""Reacting particles: char combustion, polymerization heat and sublimation (one kernel, run
every DEM step after the forces and the gas exchange, before the kick that advances T; where no
reaction can remove a particle, as in polymerization, the kick runs the same code itself).

Char combustion (source 1: R_p = k exp(-E/(R T_p)) ... with the sign fixed; kinetics of
Field 1969, Combust. Flame 13, 237: k_s = 8710 exp(-17967 K / T_p) g/(cm^2 s atm) =
0.8596 exp(-E/(R T_p)) kg C/(m^2 s Pa), E = 149.4 kJ/mol), in series with the gas film
(Baum & Street 1971 form):
    carbon rate  m_dot = pi d^2 p_O2 / (1/k_s + 1/k_d),    p_O2 = Y M_gas / M_O2 P,
    film         k_d = (M_C / nu) Sh D / (d R T_f),  T_f = (T_p + T_g)/2,
                 Sh = 2 + 0.6 Re^1/2 Sc^1/3 (Ranz-Marshall analogy), Re = rho_g |u - v| d / mu,
                 Sc = mu / (rho_g D); nu = 1 - phi/2 mol O2 per mol C (phi = co_fraction).
  Y is the cloud-in-cell mean of the fluid cells c around the particle, Y = sum w_c Y_c / sum w_c,
  read every step. The particle loses dm = min(m_dot dt, m); the cells lose nu M_O2/M_C dm of O2,
  each the share w_c Y_c / sum w_c Y_c (`o2_sink`, taken at the next gas step): m_dot is linear in
  Y, so each cell gives what its own O2 drives and a cell without O2 gives none. The particle gets
  dm h_c (h_c the heat per kg C of tidem.heat.reactions). `shrink` keeps the density (d ~ m^1/3),
  `density` keeps the diameter. A particle whose carbon is gone is removed.
Polymerization (source 1, Kaneko et al. 1999): q = k_p p_M exp(-E/R (1/T - 1/T_ref)) m dH_p [W],
  first order in the monomer partial pressure p_M. With `growth` the polymer made stays on the
  particle, dm = q dt / dH_p, at constant density (d ~ m^1/3; the mass grows as exp(k_p p_M t)
  at constant T); the monomer brings its sensible heat c T dm (booked as negative ENTHALPY_OUT),
  and a particle that reaches `max_diameter` stops reacting (the neighbour grid is sized for it).
Sublimation (source 2 eq. 6): a particle at T_s turns the heat it receives into vapour,
  dm = q dt / L_u (equivalently dR/dt = -q / (rho_s L_u 4 pi R^2)), with q its whole heat rate
  (gas exchange with Nu = 2 in the Stokes regime, from `gas_coupling`); below T_s it warms, and
  a step that crosses T_s puts the excess into vapour. The heat comes from the gas through the
  implicit exchange of `gas_energy.energy` (two-way: a loaded plasma cools). A particle past
  `exit` (z) leaves the domain unsublimated.

Coarse-grained parcels (rc["cg"] = k: a parcel of k d_g holds k^3 grains; docs/design/
coarse_graining.md): every rate is one grain's, evaluated with the grain diameter d_g = d / k
(char film and surface, growth cap), times k^3; polymerization heat (proportional to mass) and
sublimation (driven by the gas heat, already per grain in `gas_coupling`) scale by themselves.
Since the parcel's mass and heat capacity carry k^3 too, each grain's history (T, d_g, m_g) is
kept. Counts of particles burnt out or escaped are counts of grains (k^3 per parcel).

Energy bookkeeping (what makes the balances close to rounding): the kick advances
T += dt q / (m c) with the new mass, so reaction heat lands exactly in the particle; the
sensible heat c T dm of the mass that reacted is counted in rsum[ENTHALPY_OUT]; a removed
particle hands the heat of its last step, and the gas exchange the gas already charged for the
rest of the gas step (`steps_left` DEM steps), back to its gas cells (`Qs`, added at the next
gas step). What particles give their gas cells (the O2 a char particle takes, a removed particle's
heat) is booked per particle (`gas_book`) in the parallel loop and added to the cells after it, in
particle order: the same sums, bit for bit, on any thread count; so are the totals of S.rsum on the
CPU (each particle's share booked in its row of `rbook`, added up in particle order after the loop).
Per-step stability (share of the mass used in one step) is refused at set-up (tidem.heat.reactions); the
last step of a particle's life is clamped to what it has left.
"""

import math
from types import SimpleNamespace

import taichi as ti

from .gas_grid import make_cic
from .ordered import in_order

CHAR, POLY, SUBL = 0, 1, 2
REACTED, O2_USED, HEAT_RELEASED, LATENT, ENTHALPY_OUT, REFUND, GONE, ESCAPED, MASS_ESCAPED = range(9)
# the totals (S.rsum slots) that each kind of reaction books
BOOKED = {CHAR: (REACTED, O2_USED, HEAT_RELEASED, ENTHALPY_OUT, GONE, REFUND),
          POLY: (REACTED, HEAT_RELEASED, ENTHALPY_OUT),
          SUBL: (REACTED, LATENT, ENTHALPY_OUT, GONE, REFUND, ESCAPED, MASS_ESCAPED)}


def booked_slots(kinds) -> list[int]:
    """The S.rsum slots that reactions of these kinds book (the columns of S.rbook)."""
    return sorted(set().union(*(BOOKED[k] for k in kinds)))


def make_reaction_kernel(reactions: list[dict], S, gg=None, G=None, rho_g: float = 1.0, mu: float = 1.0,
                         W: int = 1):
    """Return `react(n, t, dt, steps_left)` for the reactions of `tidem.heat.reactions.reaction_constants`
    (a kernel), and `in_kick` where no reaction removes a particle (polymerization): the Taichi funcs
    particle(i, t, dt, steps_left), which the kick calls on each reacting particle after its forces are
    complete, and hand_over(n), which the kick's kernel calls after its particle loop, so that the
    step needs neither a launch nor a pass of its own for the reactions (`kernels/integrate.py`)."""
    gas = G is not None
    ordered = in_order()
    timing = any(r["kind"] == SUBL for r in reactions)
    burning = any(r["kind"] == CHAR for r in reactions)
    removes = any(r["kind"] in (CHAR, SUBL) for r in reactions)  # (burnt out, sublimated or escaped)
    deposits = gas and removes  # only these book anything for the gas cells (`gas_book`)
    slots = booked_slots(r["kind"] for r in reactions)
    if gas:
        cic, corner, weight, corners = make_cic(gg)

    @ti.func
    def book(i, slot: ti.template(), amount):
        """Add `amount` to the total S.rsum[slot]: on the CPU in particle i's own row of S.rbook, which the
        kernel adds up in particle order after its loop (the same sums on any thread count, and no atomic
        add to one address from every thread: those took four fifths of a polymerizing bed's reaction
        step); on a GPU to the total itself."""
        ti.static_assert(slot in slots, "a reaction books a total that BOOKED does not list for its kind")
        if ti.static(ordered):
            S.rbook[i][ti.static(slots.index(slot))] += amount
        else:
            ti.atomic_add(S.rsum[slot], amount)

    @ti.func
    def deposit(F: ti.template(), x, amount):
        if ti.static(gas):
            base, frac = cic(x, -1)
            for o_t in ti.static(corners(-1)):
                o = ti.Vector(o_t)
                ti.atomic_add(F[corner(base, o, -1)], weight(frac, o, -1) * amount)

    @ti.func
    def o2_weights(x):
        """The O2 the gas cells around x offer: sum of w_c Y_c and of w_c over the fluid cells c of x's
        cloud-in-cell cube (a solid cell, inside a tube, holds no gas)."""
        base, frac = cic(x, -1)
        wy = 0.0
        wf = 0.0
        for o_t in ti.static(corners(-1)):
            o = ti.Vector(o_t)
            J = corner(base, o, -1)
            if G.solid[J] == 0:
                w = weight(frac, o, -1)
                wy += w * ti.max(G.Y[J], 0.0)
                wf += w
        return wy, wf

    @ti.func
    def take_o2(x, amount):
        """Charge `amount` [kg] of O2 to the cells around x, each in proportion to w_c Y_c, the O2 it
        gave the particle: the take from a cell is linear in its own Y, so a cell without O2 gives none."""
        base, frac = cic(x, -1)
        wy, wf = o2_weights(x)
        for o_t in ti.static(corners(-1)):
            o = ti.Vector(o_t)
            J = corner(base, o, -1)
            if G.solid[J] == 0:
                ti.atomic_add(G.o2_sink[J], weight(frac, o, -1) * ti.max(G.Y[J], 0.0) / wy * amount)

    @ti.func
    def cube_root_of_ratio(m_new, m):
        """(m_new / m)^(1/3). For a change x = m_new / m - 1 below 1e-5, the series 1 + x/3 - x^2/9
        + 5 x^3/81, whose next term 10 x^4/243 lies below the result's rounding: a growing or burning
        particle changes by far less in a step, and pow took a third of a polymerizing bed's reaction
        step (olefin_polymerization)."""
        x = (m_new - m) / m
        g = 0.0
        if ti.abs(x) < 1e-5:
            g = 1.0 + x * (1.0 / 3.0 - x * (1.0 / 9.0 - x * (5.0 / 81.0)))
        else:
            g = (m_new / m) ** (1.0 / 3.0)
        return g

    @ti.func
    def set_mass(i, m_new, shrink: ti.template()):
        """New mass (and radius when shrinking at constant density); inverse mass, inertia and
        heat capacity follow."""
        m = S.mass[i]
        if ti.static(shrink):
            S.radius[i] *= cube_root_of_ratio(m_new, m)
        S.inv_heat_cap[i] *= m / m_new
        S.mass[i] = m_new
        if S.inv_mass[i] > 0.0:
            S.inv_mass[i] = 1.0 / m_new
            S.inv_inertia[i] = 1.0 / (0.4 * m_new * S.radius[i] ** 2)

    @ti.func
    def remove(i, t, dt, steps_left, heat_left):
        """Take particle i out; `heat_left` [J] of this step and the gas exchange already
        charged to the gas for the rest of the gas step go back to the gas."""
        refund = heat_left
        if ti.static(gas):
            refund += S.gH[i] * (S.gT[i] - S.T[i]) * dt * steps_left
            S.gas_book[i][1] = refund
        book(i, REFUND, refund)
        S.active[i] = 0
        S.v[i] = ti.Vector([0.0, 0.0, 0.0])
        S.w[i] = ti.Vector([0.0, 0.0, 0.0])
        S.q[i] = 0.0
        for q in range(W):
            S.wid[i, q] = -1
        S.wmask[i] = 0
        if ti.static(timing):
            S.rt1[i] = t

    def make_char(rc):
        shrink = rc["shrink"]

        @ti.func
        def char(i, t, dt, steps_left, T, m, c):
            gone = 0
            d = 2.0 * S.radius[i] / rc["cg"]  # the grain's diameter
            wy, wf = o2_weights(S.x[i])
            y = 0.0
            if wf > 0.0:
                y = wy / wf
            S.gY[i] = y
            p_o2 = y * rc["x_per_y"] * rc["pressure"]
            k_s = rc["A"] * ti.exp(-rc["E_R"] / T)
            w = (S.gu[i] - S.v[i]).norm()
            sh = 2.0 + 0.6 * ti.sqrt(rho_g * w * d / mu) * rc["sc"] ** (1.0 / 3.0)
            k_d = rc["film"] * sh * rc["D"] / (d * 0.5 * (T + S.gT[i]))
            rate = rc["cg"] ** 3 * math.pi * d * d * p_o2 / (1.0 / k_s + 1.0 / k_d)
            dm = ti.min(rate * dt, m)
            if dm > 0.0:
                o2 = dm * rc["o2_per_c"]
                S.gas_book[i][0] = o2
                book(i, REACTED, dm)
                book(i, O2_USED, o2)
                book(i, HEAT_RELEASED, dm * rc["heat_per_c"])
                book(i, ENTHALPY_OUT, c * T * dm)
                heat = S.q[i] + dm * rc["heat_per_c"] / dt
                if dm >= m:
                    book(i, GONE, rc["cg"] ** 3)
                    remove(i, t, dt, steps_left, heat * dt)
                    gone = 1
                else:
                    S.q[i] = heat
                    set_mass(i, m - dm, shrink)
            return gone

        return char

    def make_poly(rc):
        grow = rc["grow"]

        @ti.func
        def poly(i, t, dt, steps_left, T, m, c):
            active = True
            if ti.static(grow):
                active = 2.0 * S.radius[i] / rc["cg"] < rc["d_max"]
            if active:
                q = rc["k"] * ti.exp(-rc["E_R"] * (1.0 / T - 1.0 / rc["T_ref"])) * m * rc["enthalpy"]
                S.q[i] += q
                book(i, HEAT_RELEASED, q * dt)
                if ti.static(grow):
                    dm = q * dt / rc["enthalpy"]
                    book(i, REACTED, dm)
                    book(i, ENTHALPY_OUT, -(c * T * dm))
                    set_mass(i, m + dm, True)
            return 0

        return poly

    def make_subl(rc):
        @ti.func
        def subl(i, t, dt, steps_left, T, m, c):
            gone = 0
            if S.x[i][2] > rc["exit"]:
                book(i, ESCAPED, rc["cg"] ** 3)
                book(i, MASS_ESCAPED, m)
                book(i, ENTHALPY_OUT, c * T * m)
                remove(i, -t, dt, steps_left, S.q[i] * dt)
                gone = 1
            else:
                T_s = rc["T_s"]
                excess = (T + dt * S.q[i] / (m * c) - T_s) * m * c  # heat beyond T_s [J]
                if excess > 0.0:
                    dm = ti.min(excess / rc["L"], m)
                    book(i, REACTED, dm)
                    book(i, LATENT, dm * rc["L"])
                    book(i, ENTHALPY_OUT, c * T_s * dm)
                    if dm >= m:
                        book(i, GONE, rc["cg"] ** 3)
                        remove(i, t, dt, steps_left, S.q[i] * dt - dm * rc["L"] - c * (T_s - T) * m)
                        gone = 1
                    else:
                        set_mass(i, m - dm, True)
                        S.q[i] = (T_s - T) * (m - dm) * c / dt
            return gone

        return subl

    makers = {CHAR: make_char, POLY: make_poly, SUBL: make_subl}
    steps = [makers[rc["kind"]](rc) for rc in reactions]

    @ti.func
    def react_particle(i, t, dt, steps_left):
        """Advance reacting particle i by dt; returns 1 if it was removed."""
        removed = 0
        if ti.static(timing):
            if S.rt0[i] < 0.0:
                S.rt0[i] = t
        T = S.T[i]
        m = S.mass[i]
        c = 1.0 / (S.inv_heat_cap[i] * m)  # specific heat [J/(kg K)]
        for k in ti.static(range(len(steps))):
            if S.rx[i] == k:
                removed += steps[k](i, t, dt, steps_left, T, m, c)
        return removed

    @ti.func
    def hand_over(n):
        """After every particle has reacted: on the CPU the ledger rows added up in particle order (the
        same totals whatever the thread count), and what the particles booked for their gas cells."""
        if ti.static(deposits or ordered):
            if ti.static(ordered):
                ti.loop_config(serialize=True)  # particle order, whatever the thread count
            for i in range(n):
                if ti.static(ordered):
                    if S.rx[i] >= 0:  # (an inert particle's row stays zero)
                        for k in ti.static(range(len(slots))):
                            S.rsum[slots[k]] += S.rbook[i][k]
                            S.rbook[i][k] = 0.0
                if ti.static(deposits):
                    booked = S.gas_book[i]
                    if booked[0] != 0.0 or booked[1] != 0.0:
                        if ti.static(burning):
                            take_o2(S.x[i], booked[0])
                        deposit(G.Qs, S.x[i], booked[1])
                        S.gas_book[i] = ti.Vector([0.0, 0.0])

    @ti.kernel
    def react(n: ti.i32, t: ti.f64, dt: ti.f64, steps_left: ti.i32) -> ti.i32:
        """Advance every reacting particle by dt; returns the number of particles removed."""
        removed = 0
        for i in range(n):
            if S.active[i] and S.rx[i] >= 0:
                removed += react_particle(i, t, dt, steps_left)
        hand_over(n)
        return removed

    in_kick = None
    if not removes:
        in_kick = SimpleNamespace(particle=react_particle, hand_over=hand_over)
    return SimpleNamespace(react=react, in_kick=in_kick)
