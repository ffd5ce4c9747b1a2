"""Time integration: velocity Verlet for translation, the same kick-drift-kick for spin.

Step n -> n+1 (as in LAMMPS' fix nve/sphere):
  kick_drift:  v += dt/2 f/m,  w += dt/2 T/I,  x += dt v   (then periodic wrap)
  (forces at the new positions, with the half-step velocities in the dashpots)
  kick:        v += dt/2 f/m,  w += dt/2 T/I
`kick_drift` also records the largest displacement since the last neighbour build in
`max_disp[None]`; the run loop rebuilds the Verlet list when it exceeds half the skin.
"""

import taichi as ti

from .geometry import make_geometry


def make_integrators(grid, S, heat: bool = False, n_surf: int = 0, angle_bins: int = 0):
    """Return (kick_drift(n, dt), kick(n, dt)); with heat, `kick` also advances temperatures
    explicitly, T += dt q / (m c), and the heat delivered by each surface, E_s += dt q_s."""
    min_image, wrap, _cc, _cid = make_geometry(grid)

    @ti.kernel
    def kick_drift(n: ti.i32, dt: float):
        S.max_disp[None] = 0.0
        for i in range(n):
            if S.active[i]:
                S.v[i] += 0.5 * dt * S.f[i] * S.inv_mass[i]
                S.w[i] += 0.5 * dt * S.tq[i] * S.inv_inertia[i]
                x = wrap(S.x[i] + dt * S.v[i])
                S.x[i] = x
                ti.atomic_max(S.max_disp[None], min_image(x - S.x_build[i]).norm())

    @ti.kernel
    def kick(n: ti.i32, dt: float):
        if ti.static(heat):
            for s in range(n_surf):
                S.surf_energy[s] += dt * S.surf_rate[s]
        if ti.static(angle_bins > 0):
            for k, b in S.tube_bin_rate:
                S.tube_bin_energy[k, b] += dt * S.tube_bin_rate[k, b]
        for i in range(n):
            if S.active[i]:
                S.v[i] += 0.5 * dt * S.f[i] * S.inv_mass[i]
                S.w[i] += 0.5 * dt * S.tq[i] * S.inv_inertia[i]
                if ti.static(heat):
                    S.T[i] += dt * S.q[i] * S.inv_heat_cap[i]

    return kick_drift, kick
