"""Whole-system sums for the time series: translational and rotational kinetic energy,
potential energy in gravity, contact count. They feed the output only, never the dynamics, so
the last-bit order dependence of their atomic sums does not affect reproducibility."""

import taichi as ti

CHUNK = 64  # particles summed in registers before one atomic add per sum (atomics on one cache line contend)


def make_energy_kernel(gravity, S):
    """Return `energies(n)` that fills S.sums with [E_kin, E_rot, E_pot, contacts, active]."""
    g = ti.Vector(list(gravity))

    @ti.kernel
    def energies(n: ti.i32):
        for q in ti.static(range(5)):
            S.sums[q] = 0.0
        for c in range((n + CHUNK - 1) // CHUNK):
            part = ti.Vector([0.0, 0.0, 0.0, 0.0, 0.0])
            for i in range(c * CHUNK, ti.min(n, (c + 1) * CHUNK)):
                if S.active[i]:
                    m = S.mass[i]
                    part += ti.Vector([0.5 * m * S.v[i].norm_sqr(), 0.2 * m * S.radius[i] ** 2 * S.w[i].norm_sqr(),
                                       -m * g.dot(S.x[i]), S.ncontact[i], 1.0])
            for q in ti.static(range(5)):
                ti.atomic_add(S.sums[q], part[q])

    return energies
