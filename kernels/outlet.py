"""Outlets along z. Recycling: a particle whose centre falls below the outlet height re-enters at the
reinsertion height with the same horizontal position and velocity and no spin (mass is
conserved; the column behaves as an endless bed), its mass and count added to `sink_sum` (kg,
particles; float64: the mass that passed the outlet). Its wall history is cleared; its pair history
is dropped by the neighbour rebuild that the solver triggers whenever a particle was moved.
Sink: a particle whose centre falls below the outlet height leaves the run (inactive), its mass and
count added to `sink_sum` (kg, particles; float64), from which the discharge rate follows."""

import taichi as ti


def make_recycle_kernel(height: float, reinsert_height: float, W: int, S):
    """Return `recycle(n) -> number of particles moved`."""

    @ti.kernel
    def recycle(n: ti.i32) -> ti.i32:
        moved = 0
        for i in range(n):
            if S.active[i] and S.x[i][2] < height:
                S.x[i][2] = reinsert_height
                S.w[i] = ti.Vector([0.0, 0.0, 0.0])
                for q in range(W):
                    S.wid[i, q] = -1
                S.wmask[i] = 0
                ti.atomic_add(S.sink_sum[0], ti.cast(S.mass[i], ti.f64))
                ti.atomic_add(S.sink_sum[1], 1.0)
                moved += 1
        return moved

    return recycle


def make_sink_kernel(height: float, W: int, S):
    """Return `sink(n) -> number of particles that left` (module docstring)."""

    @ti.kernel
    def sink(n: ti.i32) -> ti.i32:
        gone = 0
        for i in range(n):
            if S.active[i] and S.x[i][2] < height:
                S.active[i] = 0
                S.v[i] = ti.Vector([0.0, 0.0, 0.0])
                S.w[i] = ti.Vector([0.0, 0.0, 0.0])
                for q in range(W):
                    S.wid[i, q] = -1
                S.wmask[i] = 0
                ti.atomic_add(S.sink_sum[0], ti.cast(S.mass[i], ti.f64))
                ti.atomic_add(S.sink_sum[1], 1.0)
                gone += 1
        return gone

    return sink
