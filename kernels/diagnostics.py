"""Whole-system sums for the time series: translational and rotational kinetic energy,
potential energy in gravity, contact count. Sums use atomics: they feed the output only,
never the dynamics, so their last-bit order dependence does not affect reproducibility."""

import taichi as ti


def make_energy_kernel(gravity, S):
    """Return `energies(n)` that fills S.sums with [E_kin, E_rot, E_pot, contacts, active]."""
    g = ti.Vector(list(gravity))

    @ti.kernel
    def energies(n: ti.i32):
        for q in ti.static(range(5)):
            S.sums[q] = 0.0
        for i in range(n):
            if S.active[i]:
                m = S.mass[i]
                S.sums[0] += 0.5 * m * S.v[i].norm_sqr()
                S.sums[1] += 0.2 * m * S.radius[i] ** 2 * S.w[i].norm_sqr()
                S.sums[2] += -m * g.dot(S.x[i])
                S.sums[3] += S.ncontact[i]
                S.sums[4] += 1.0

    return energies
