"""kernels/gas_grid.py make_cic: the cloud-in-cell interpolation, with an axis across of one lattice
point visited once (weight 1) instead of twice (1 - f and f), against the plain eight-corner sum."""

import itertools

import numpy as np
import pytest
import taichi as ti

from tidem.kernels.gas_grid import GasGrid, make_cic

H = 0.004


def reference(gg: GasGrid, F: np.ndarray, x: np.ndarray, stagger: int) -> float:
    """The eight-corner CIC sum, each axis split into 1 - f and f, corners clamped or wrapped."""
    g = (x - np.array(gg.lo)) / np.array(gg.h) - 0.5
    if stagger >= 0:
        g[stagger] += 0.5
    base = np.floor(g).astype(int)
    frac = g - base
    out = 0.0
    for o in itertools.product((0, 1), repeat=3):
        idx, w = [], 1.0
        for a in range(3):
            k = base[a] + o[a]
            n = gg.cells[a]
            k = k % n if gg.periodic[a] else min(max(k, 0), n if stagger == a else n - 1)
            idx.append(k)
            w *= frac[a] if o[a] else 1.0 - frac[a]
        out += w * F[tuple(idx)]
    return out


@pytest.mark.parametrize("periodic_y", [True, False])
def test_a_one_cell_axis_is_visited_once_and_interpolates_as_eight_corners(periodic_y):
    gg = GasGrid(lo=(0.0, 0.0, 0.0), cells=(4, 1, 5), h=(H, H, H), periodic=(False, periodic_y, False))
    cic, corner, weight, corners = make_cic(gg)
    # cells and faces normal to x and z: y folds onto one point; faces normal to y: one (periodic) or two
    assert [len(corners(s)) for s in (-1, 0, 2)] == [4, 4, 4]
    assert len(corners(1)) == (4 if periodic_y else 8)
    rng = np.random.default_rng(3)
    points = rng.uniform((0.0, 0.0, 0.0), (4 * H, H, 5 * H), size=(40, 3))
    for stagger in (-1, 0, 1, 2):
        shape = gg.face_shape(stagger) if stagger >= 0 else gg.cells
        F = ti.field(ti.f64, shape=shape)
        values = rng.normal(size=shape)
        F.from_numpy(values)
        xs = ti.Vector.field(3, ti.f64, shape=len(points))
        xs.from_numpy(points)
        got = ti.field(ti.f64, shape=(len(points), 2))

        @ti.kernel
        def interpolate():
            for p in range(len(points)):
                base, frac = cic(xs[p], stagger)
                total, weights = 0.0, 0.0
                for o_t in ti.static(corners(stagger)):
                    o = ti.Vector(o_t)
                    w = weight(frac, o, stagger)
                    total += w * F[corner(base, o, stagger)]
                    weights += w
                got[p, 0] = total
                got[p, 1] = weights

        interpolate()
        result = got.to_numpy()
        expected = [reference(gg, values, x, stagger) for x in points]
        np.testing.assert_allclose(result[:, 0], expected, rtol=1e-12, atol=1e-12, err_msg=f"stagger {stagger}")
        np.testing.assert_allclose(result[:, 1], 1.0, rtol=1e-14)
