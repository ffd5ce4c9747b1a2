"""Local averaging of the bed (source 3, Bartsch 2020, eq. 34-36): one sample of the sums.

Each call adds every active particle to the control volume its centre lies in (eq. 36:
w_i = 1 inside, 0 outside), with atomic adds into float64 accumulators, and counts the sample:
  avg_cells[i, k, c]   rectangular cell (i along x, k along z) spanning the domain's depth (y);
  avg_rings[t * rings + j, b, c]   ring j (radial layer of `ring_width` from the surface) and
                       sector b (angle omega from the top of tube t: omega = atan2(offset . side,
                       offset_z), 0 = top, 90 deg = the +side, 180 deg = below, as the tube heat-flux
                       bins of kernels/contact.py; side = the horizontal axis across the tube);
  avg_samples[None]    the number of samples taken.
Channels c: COUNT (N), VOLUME (sum V_i), VOL_V (3, sum V_i v_i), NUM_V (3, sum v_i) and, with
heat, VOL_T (sum V_i T_i). The fields of eq. 34 (Q = (1/V) sum w_i V_i Q_i: packing fraction
with Q_i = 1, solid flux with Q_i = v_i) and eq. 35 (number mean Q = (1/N) sum w_i Q_i of the
velocity) follow from these sums divided by the number of samples (`tidem/results/averaging.py`). In
the cells the velocity components are (x, y, z); in the ring sectors (radial outwards,
tangential towards increasing omega, along the tube axis). Tube offsets use the periodic
minimum image.
"""

import math

import taichi as ti

from .geometry import make_geometry

COUNT, VOLUME, VOL_V, NUM_V, VOL_T = 0, 1, 2, 5, 8


def channels(heat: bool) -> int:
    """Accumulator channels per control volume."""
    return VOL_T + 1 if heat else VOL_T


def make_averaging_kernel(grid, lo, cells, size, n_tubes: int, rings: int, ring_width: float, sectors: int,
                          heat: bool, S):
    """Return `sample(n)`: add particles 0..n-1 to the sums of the cells (lower x-z corner `lo`,
    `cells` along x and z of `size` [m]) and of the ring sectors around `n_tubes` tubes."""
    min_image, wrap, _cc, _cid = make_geometry(grid)
    nx, nz = cells
    inv_dx, inv_dz = 1.0 / size[0], 1.0 / size[1]
    inv_w = 1.0 / ring_width
    two_pi = 2.0 * math.pi
    vol_factor = 4.0 / 3.0 * math.pi

    @ti.func
    def add(acc: ti.template(), a, b, vol, u, temp):
        """Add one particle (volume vol, velocity components u, temperature temp) to acc[a, b]."""
        ti.atomic_add(acc[a, b, COUNT], 1.0)
        ti.atomic_add(acc[a, b, VOLUME], vol)
        for c in ti.static(range(3)):
            ti.atomic_add(acc[a, b, VOL_V + c], vol * u[c])
            ti.atomic_add(acc[a, b, NUM_V + c], u[c])
        if ti.static(heat):
            ti.atomic_add(acc[a, b, VOL_T], vol * temp)

    @ti.kernel
    def sample(n: ti.i32):
        for p in range(n):
            if S.active[p]:
                x = wrap(S.x[p])
                r = ti.cast(S.radius[p], ti.f64)
                vol = vol_factor * r * r * r
                v = ti.cast(S.v[p], ti.f64)
                temp = ti.cast(0.0, ti.f64)
                if ti.static(heat):
                    temp = ti.cast(S.T[p], ti.f64)
                i = ti.cast(ti.floor((x[0] - lo[0]) * inv_dx), ti.i32)
                k = ti.cast(ti.floor((x[2] - lo[1]) * inv_dz), ti.i32)
                if i >= 0 and i < nx and k >= 0 and k < nz:
                    add(S.avg_cells, i, k, vol, v, temp)
                for t in ti.static(range(n_tubes)):
                    mask = S.tube_mask[t]
                    off = min_image(x - S.tube_c[t]) * mask
                    dist = off.norm()
                    j = ti.cast(ti.floor((dist - S.tube_r[t]) * inv_w), ti.i32)
                    if dist > 0.0 and j >= 0 and j < rings:
                        side = ti.Vector([1.0 - mask[1], mask[1], 0.0])
                        e_r = off / dist
                        across = e_r.dot(side)
                        omega = ti.atan2(across, e_r[2])
                        if omega < 0.0:
                            omega += two_pi
                        b = ti.min(ti.cast(omega / two_pi * sectors, ti.i32), sectors - 1)
                        e_t = e_r[2] * side - across * ti.Vector([0.0, 0.0, 1.0])
                        e_axis = ti.Vector([1.0, 1.0, 1.0]) - mask
                        u = ti.Vector([v.dot(e_r), v.dot(e_t), v.dot(e_axis)], ti.f64)
                        add(S.avg_rings, t * rings + j, b, vol, u, temp)
        S.avg_samples[None] += 1

    return sample
