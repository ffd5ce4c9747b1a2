"""Whole-system sums for the time series: translational and rotational kinetic energy,
potential energy in gravity, contact count. They feed the output only, never the dynamics, so
the last-bit order dependence of their atomic sums does not affect reproducibility. And the
health check's reductions (`make_health_kernel`), on the device: on a GPU, copying every
position and overlap to the host every 100 steps took 0.57 ms a step of the 700 000-grain bed
(`benchmarks/README.md`)."""

import taichi as ti

from .ordered import raise_max

CHUNK = 64  # particles summed in registers before one atomic add per sum (atomics on one cache line contend)
FINITE = 1e300  # |x| above this, or NaN (every comparison false), is not a position


@ti.func
def finite(x):
    """Whether position x is one (every coordinate within FINITE)."""
    return ti.abs(x[0]) <= FINITE and ti.abs(x[1]) <= FINITE and ti.abs(x[2]) <= FINITE


def make_energy_kernel(gravity, S):
    """Return (energies(n), sample(n)). `energies` fills S.sums with [E_kin, E_rot, E_pot, contacts,
    active]; `sample`, a time-series row's reductions in the same pass over the particles, also sets
    S.worst to the largest overlap ratio and S.worst_at[0] to the first active particle with a
    non-finite position (n if none), as the health check's first loop does (`make_health_kernel`):
    one loop and one read of the tallies a sample instead of three loops and two reads (`tidem.sim.solver`).
    S.worst_at[1] (the particle of the largest overlap) is left as it was."""
    g = ti.Vector(list(gravity))

    @ti.func
    def reduce(n, health: ti.template()):
        for q in ti.static(range(5)):
            S.sums[q] = 0.0
        if ti.static(health):
            S.worst_at[0] = n
            S.worst[None] = 0.0
        for c in range((n + CHUNK - 1) // CHUNK):
            part = ti.Vector([0.0, 0.0, 0.0, 0.0, 0.0])
            worst = 0.0
            for i in range(c * CHUNK, ti.min(n, (c + 1) * CHUNK)):
                if S.active[i]:
                    m = S.mass[i]
                    part += ti.Vector([0.5 * m * S.v[i].norm_sqr(), 0.2 * m * S.radius[i] ** 2 * S.w[i].norm_sqr(),
                                       -m * g.dot(S.x[i]), S.ncontact[i], 1.0])
                    if ti.static(health):
                        if not finite(S.x[i]):
                            ti.atomic_min(S.worst_at[0], i)
                        if S.ovl[i] > worst:  # (as raise_max: a NaN never raises it)
                            worst = S.ovl[i]
            for q in ti.static(range(5)):
                ti.atomic_add(S.sums[q], part[q])
            if ti.static(health):
                raise_max(S.worst, worst)

    @ti.kernel
    def energies(n: ti.i32):
        reduce(n, False)

    @ti.kernel
    def sample(n: ti.i32):
        reduce(n, True)

    return energies, sample


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
                if not finite(S.x[i]):
                    ti.atomic_min(S.worst_at[0], i)
                raise_max(S.worst, S.ovl[i])
        for i in range(n):
            if S.active[i] and S.ovl[i] == S.worst[None]:
                ti.atomic_min(S.worst_at[1], i)

    return health


def make_sample_kernel(S, P, z_lo: float, z_bin: float, bins: int, heat: bool):
    """Return `sample_stats(n)` for a GPU's time series (`tidem.results.particle_stats`): P.z_hist[b] = the
    active particles whose centre height z lies in bin b (width z_bin from z_lo; heights beyond
    count in the end bins), and with `heat` P.T_sum[None] = sum of their temperatures,
    P.T_top[None] = the largest, P.T_low[None] = minus the smallest (both raised by `raise_max`).
    Sums and extremes over CHUNK particles in registers, then one atomic each."""

    @ti.kernel
    def sample_stats(n: ti.i32):
        for b in P.z_hist:
            P.z_hist[b] = 0
        if ti.static(heat):
            P.T_sum[None] = 0.0
            P.T_top[None] = -1e300
            P.T_low[None] = -1e300
        for c in range((n + CHUNK - 1) // CHUNK):
            total, top, low = 0.0, -1e300, -1e300
            for i in range(c * CHUNK, ti.min(n, (c + 1) * CHUNK)):
                if S.active[i]:
                    b = ti.cast(ti.floor((S.x[i][2] - z_lo) / z_bin), ti.i32)
                    ti.atomic_add(P.z_hist[ti.min(ti.max(b, 0), bins - 1)], 1)
                    if ti.static(heat):
                        T = S.T[i]
                        total += T
                        top = ti.max(top, T)
                        low = ti.max(low, -T)
            if ti.static(heat):
                ti.atomic_add(P.T_sum[None], total)
                raise_max(P.T_top, top)
                raise_max(P.T_low, low)

    return sample_stats
