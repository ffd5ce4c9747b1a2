"""Whole-system sums for the time series: translational and rotational kinetic energy,
potential energy in gravity, contact count. They feed the output only, never the dynamics, so
the last-bit order dependence of their atomic sums does not affect reproducibility. And the
health check's reductions (`make_health_kernel`), on the device: on a GPU, copying every
position and overlap to the host every 100 steps took 0.57 ms a step of the 700 000-grain bed
(`benchmarks/README.md`)."""

import taichi as ti

from .ordered import raise_max

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


FINITE = 1e300  # |x| above this, or NaN (every comparison false), is not a position


def make_health_kernel(S):
    """Return `health(n)`, which writes S.worst_at = [first active particle with a non-finite
    position, first active particle with the largest overlap ratio] (storage indices; the first
    is n where there is none) and S.worst[None] = that overlap ratio (0 without particles), the
    largest raised by `raise_max` (a float atomic max from every GPU thread on one address is slow).
    Integer indices and a max: the same on any thread count."""

    @ti.kernel
    def health(n: ti.i32):
        S.worst_at[0] = n
        S.worst_at[1] = n
        S.worst[None] = 0.0
        for i in range(n):
            if S.active[i]:
                x = S.x[i]
                if not (ti.abs(x[0]) <= FINITE and ti.abs(x[1]) <= FINITE and ti.abs(x[2]) <= FINITE):
                    ti.atomic_min(S.worst_at[0], i)
                raise_max(S.worst, S.ovl[i])
        for i in range(n):
            if S.active[i] and S.ovl[i] == S.worst[None]:
                ti.atomic_min(S.worst_at[1], i)

    return health
