"""Time integration: velocity Verlet for translation, the same kick-drift-kick for spin.

Step n -> n+1 (as in LAMMPS' fix nve/sphere):
  kick_drift:  v += dt/2 f/m,  w += dt/2 T/I,  x += dt v   (then periodic wrap)
  (forces at the new positions, with the half-step velocities in the dashpots)
  kick:        v += dt/2 f/m,  w += dt/2 T/I
`kick_drift` also finds the largest displacement since the last neighbour build, squared (kept in
`max_disp[None]`: no square root per particle); the run loop rebuilds the Verlet list when it
exceeds half the skin. When the host needs nothing between two steps, `kick(..., drift=1)` goes
on with the next step's kick-drift for each particle in the same loop, which saves a kernel
launch and a pass over the particles; the operations are those of the two kernels, in the same order, and the result is
bit-identical (a slab's particles move on only when no pair left to evaluate reads them,
`kernels/contact.py`). With
growing particles the radius gained since the build counts as displacement (a pair's gap
closes by both moves and both growths, so max(move + growth) <= skin / 2 keeps the list valid).
"""

import taichi as ti

from .geometry import make_geometry
from .ordered import raise_max


def make_integrators(grid, S, heat: bool = False, n_surf: int = 0, angle_bins: int = 0, foil: bool = False,
                     growth: bool = False, wall_foil: bool = False, n_planes: int = 0, before_kick=(), forces=None,
                     react=None):
    """Return the kernels (kick_drift(n, dt), kick(n, t, dt, drift), forces_and_kick(n, t, dt, conduct,
    diag, drift, kick)). Each leaves in S.max_disp[None] the largest squared displacement since the last neighbour build
    (for `kick` and `forces_and_kick` that after the next step's kick-drift when drift = 1, else 0;
    drift: 0 or 1; a kernel's return value would cost the host more than reading the field).
    With heat, `kick` also advances temperatures explicitly, T += dt q / (m c), and the heat
    delivered by each surface, E_s += dt q_s.
    `before_kick`: Taichi funcs f(i, t) that finish particle i's force, torque and heat flow
    (the gas forces, the contact times); `kick` calls them on each particle first, which saves a
    kernel launch and a pass over the particles per step.
    `react`: the reactions that run in the kick (`in_kick` of `kernels/reactions.make_reaction_kernel`,
    polymerization): each reacting particle reacts after `before_kick`, just before its kick, as the
    separate reaction kernel would between the forces and the kick, and the kernel hands the reactions'
    totals over after its particle loop.
    `forces`: the contact passes of `kernels/contact.make_force_kernel`; `forces_and_kick` runs
    them and kicks each particle as soon as its sums are complete, in the second pass, so that a
    step is two passes over the particles in one kernel launch (None without `forces`); with kick
    = 0 it only evaluates the forces (the run's first evaluation, so that no other kernel compiles
    them). The surfaces' heat and foils advance after the particles (they only read the flows).

    With `foil`, each heated-foil tube k (tube_foil[k] = (q_el, C_A, A_bin, G / ds^2), q_el > 0)
    advances its foil temperature per angle bin b with the same flows the particles received:
        C_A dT_b/dt = q_el - Q_b / A_bin + (G / ds^2) (T_b-1 - 2 T_b + T_b+1),
    q_el the electric heating per area, Q_b the heat into the bed from bin b, G the foil's
    conductance along the circumference (k times thickness) and ds the bin's arc length; the
    inner side is adiabatic (source 3's foil on a polyethylene tube). Heat is conserved
    exactly: q_el A t = bed heat + foil heat. tube_bin_Tsum integrates T_b over time. With
    `wall_foil` a heated-foil plane s (plane_foil[s] = (q_el, C_A, A)) has one foil temperature,
    C_A dT/dt = q_el - Q_s / A, Q_s its heat into the bed. With heat.conduction_interval m the flows are
    evaluated every m-th step (`kernels/contact.py`): the particles then receive m steps of heat at
    once, the surfaces' delivered heat E_s grows by m dt q_s, and the foils take the held Q each step,
    so the energies agree after every m steps."""
    min_image, wrap, _cc, _cid = make_geometry(grid)
    reacts = react is not None

    fp = ti.lang.impl.current_cfg().default_fp
    bits = ti.i64 if fp == ti.f64 else ti.i32

    @ti.func
    def opaque(u, zero):
        """u, bit for bit, through an integer xor with a run-time zero. Under fast math the compiler
        would merge a step's closing kick and the next step's half-kick in one loop (v + a + a ->
        v + 2 a, or one product dt f / (2 m) shared by both and so left out of a fused
        multiply-add), rounding otherwise; it cannot see through this, so a fused kick gives the
        bits of two kernels."""
        out = u
        for c in ti.static(range(3)):
            out[c] = ti.bit_cast(ti.bit_cast(u[c], bits) ^ ti.cast(zero, bits), fp)
        return out

    @ti.func
    def drift_particle(i, dt, zero):
        """The kick-drift of particle i (`zero`: 0, see opaque); returns its displacement since the
        last neighbour build (plus the radius it gained), squared. Then the force, torque and heat
        flow are spent, and zeroed for the next force evaluation to add to (`kernels/contact.py`)."""
        S.v[i] = opaque(S.v[i], zero) + 0.5 * dt * opaque(S.f[i], zero) * S.inv_mass[i]
        S.w[i] = opaque(S.w[i], zero) + 0.5 * dt * opaque(S.tq[i], zero) * S.inv_inertia[i]
        S.f[i] = ti.Vector([0.0, 0.0, 0.0])
        S.tq[i] = ti.Vector([0.0, 0.0, 0.0])
        if ti.static(heat):
            S.q[i] = 0.0
        x = wrap(S.x[i] + dt * S.v[i])
        S.x[i] = x
        moved2 = min_image(x - S.x_build[i]).norm_sqr()
        if ti.static(growth):
            moved2 = ti.max(ti.sqrt(moved2) + S.radius[i] - S.r_build[i], 0.0) ** 2
        return moved2

    @ti.kernel
    def kick_drift(n: ti.i32, dt: float):
        S.max_disp[None] = 0.0
        for i in range(n):
            if S.active[i]:
                raise_max(S.max_disp, drift_particle(i, dt, 0))

    @ti.func
    def advance_surfaces(dt):
        """Heat delivered by each surface and the heated foils over one step (a few items each: serial
        loops, without a thread-pool round trip)."""
        if ti.static(heat):
            booked = dt * S.conduct[None]  # the particles get the flows over m dt at an evaluation, 0 between
            ti.loop_config(serialize=True)
            for s in range(n_surf):
                S.surf_energy[s] += booked * S.surf_rate[s]
            if ti.static(angle_bins > 0):  # heated tubes: only with heat
                ti.loop_config(serialize=True)
                for k, b in ti.ndrange(*S.tube_bin_rate.shape):
                    S.tube_bin_energy[k, b] += booked * S.tube_bin_rate[k, b]
                ti.loop_config(serialize=True)
                for k, r in ti.ndrange(*S.tube_route_rate.shape):
                    S.tube_route_energy[k, r] += booked * S.tube_route_rate[k, r]
        if ti.static(foil):
            ti.loop_config(serialize=True)
            for k, b in ti.ndrange(*S.tube_bin_T.shape):
                foil_k = S.tube_foil[k]
                if foil_k[0] > 0.0:
                    t_b = S.tube_bin_T[k, b]
                    along = S.tube_bin_T[k, (b + angle_bins - 1) % angle_bins] + S.tube_bin_T[k, (b + 1) % angle_bins]
                    S.tube_bin_dT[k, b] = dt / foil_k[1] * (
                        foil_k[0] - S.tube_bin_rate[k, b] / foil_k[2] + foil_k[3] * (along - 2.0 * t_b))
                    S.tube_bin_Tsum[k, b] += dt * t_b
            ti.loop_config(serialize=True)
            for k, b in ti.ndrange(*S.tube_bin_T.shape):
                S.tube_bin_T[k, b] += S.tube_bin_dT[k, b]
        if ti.static(wall_foil):
            ti.loop_config(serialize=True)
            for s in range(n_planes):
                foil_s = S.plane_foil[s]
                if foil_s[0] > 0.0:
                    S.plane_foil_T[s] += dt / foil_s[1] * (foil_s[0] - S.surf_rate[s] / foil_s[2])

    @ti.func
    def kick_particle(i, t, dt, drift, kick):
        """Finish particle i's force (`before_kick`) and, with kick = 1, kick it, and with drift = 1 go on
        with its next kick-drift; kick = 0 only finishes the forces, as the first force evaluation needs.
        Returns the squared displacement of the kick-drift (0 without)."""
        moved2 = 0.0
        for finish in ti.static(before_kick):
            finish(i, t)
        if kick:
            if ti.static(reacts):
                if S.rx[i] >= 0:
                    react.particle(i, t, dt, 0)
            # plain stores: i may come from a slab list, and Taichi makes `S.v[i] += ...` with such an
            # index an atomic (`kernels/contact.py`, add)
            S.v[i] = S.v[i] + 0.5 * dt * S.f[i] * S.inv_mass[i]
            S.w[i] = S.w[i] + 0.5 * dt * S.tq[i] * S.inv_inertia[i]
            if ti.static(heat):
                S.T[i] = S.T[i] + dt * S.q[i] * S.inv_heat_cap[i]
            if drift:
                moved2 = drift_particle(i, dt, drift >> 1)
        return moved2

    @ti.kernel
    def kick(n: ti.i32, t: float, dt: float, drift: ti.i32):
        S.max_disp[None] = 0.0
        for i in range(n):
            if S.active[i]:
                raise_max(S.max_disp, kick_particle(i, t, dt, drift, 1))
        if ti.static(reacts):
            react.hand_over(n)
        advance_surfaces(dt)

    if forces is None:
        return kick_drift, kick, None

    passes_and_kick = forces.passes(kick_particle)

    @ti.kernel
    def forces_and_kick(n: ti.i32, t: float, dt: float, conduct: ti.i32, diag: ti.i32, drift: ti.i32, kick: ti.i32):
        passes_and_kick(n, t, dt, conduct, diag, drift, kick)  # (which zeroes S.max_disp once it has read it)
        if kick:
            if ti.static(reacts):
                react.hand_over(n)
            advance_surfaces(dt)

    return kick_drift, kick, forces_and_kick
