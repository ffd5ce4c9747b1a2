"""Recycling outlet: a particle whose centre falls below the outlet height re-enters at the
reinsertion height with the same horizontal position and velocity and no spin (mass is
conserved; the column behaves as an endless bed). Its wall history is cleared; its pair history is dropped
by the neighbour rebuild that the solver triggers whenever a particle was moved."""

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
                moved += 1
        return moved

    return recycle
