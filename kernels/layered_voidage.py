"""The layered voidage (`gas.voidage = "layered"`): the solid volume binned on horizontal layers about one grain
high inside each gas cell, and the voidage a particle reads back from them (`kernels/gas_coupling.py`).

A particle deposits its volume on the layers with cloud-in-cell weights at its centre and reads the layers' voidage
back with the same weights. A parcel of k^3 grains (`coarse_grain`, `gas.parcel_voidage = "grain_layers"`) is
k grains high and its layers are one grain high: its volume stands in n = round(k) rows, row j holding the sphere's
volume between the heights z - r + 2 r j / n and z - r + 2 r (j + 1) / n,
    f_j = F(-1 + 2 (j + 1) / n) - F(-1 + 2 j / n),   F(u) = (1 + u)^2 (2 - u) / 4                   (1)
(F the share of a sphere's volume below height u r from its centre, the spherical cap), each row deposited with the
CIC weights at its mid-height z - r + r (2 j + 1) / n and read back with the same weights, so that the parcel's
grains see the layers they sit in and the deposit and read-back stay adjoint (the volume is conserved to rounding:
sum_j f_j = 1). n = 1 (grains, or `"parcel_layers"`) is the plain CIC point at the centre.

A particle's own volume adds to the voidage it reads back in proportion to its self-share, the sum over lattice
points of its weight there squared (`gas_weights.make_self_share`). That of a parcel in rows is the across share
times, along z,
    sum_j sum_j' f_j f_j' sum_L w_L(z_j) w_L(z_j')                                                   (2)
(w_L the CIC weight on layer L), taken in the separable form beside tubes and meshes too.
"""

import math

import taichi as ti

from .gas_grid import layer_grid, make_cic
from .gas_weights import make_gas_weights, make_in_gas, make_self_share, plain_weights


def parcel_rows(k: float) -> int:
    """The rows n of eq. (1) for a parcel of coarse-graining factor k: k rounded, half up, at least 1."""
    return max(1, math.floor(k + 0.5))


def make_layered_voidage(gg, G, S, layers: int, rows: int, cut_cells: bool, min_voidage: float,
                         cell_own=None, layer_own=None):
    """Return (deposit_layers(i, vp), layered_voidage(i, x, vp)), Taichi funcs for particle i of volume vp at x: add
    its volume to G.solid_layer; the voidage it sees. `rows` > 1 (parcels, S.cg allocated): the most rows of eq. (1) of
    any parcel; 1: every particle one CIC point. `cell_own` / `layer_own`: the averaging-length filters' own shares
    (`gas_smoothing.Filter.own`), None for an unfiltered lattice."""
    cic, corner, weight, corners = make_cic(gg)
    lcic, lcorner, lweight, lcorners = make_cic(layer_grid(gg, layers))
    inv_vol = 1.0 / gg.volume
    inv_lvol = 1.0 / layer_grid(gg, layers).volume
    cell_filtered, layer_filtered = cell_own is not None, layer_own is not None
    lself = make_self_share(lcorner, layer_own or (0.0, 0.0, 0.0))
    cself = make_self_share(corner, cell_own or (0.0, 0.0, 0.0))
    own = layer_own or (0.0, 0.0, 0.0)
    across_self = make_self_share(lcorner, (own[0], own[1], 1.0))  # eq. (2)'s factor across
    share, gweight, gself = plain_weights(weight)
    lshare, lgweight, lgself = plain_weights(lweight)
    if cut_cells:
        in_gas, in_gas_layer = make_in_gas(gg, G, layers)
        share, gweight, gself = make_gas_weights(corner, weight, corners, in_gas)
        lshare, lgweight, lgself = make_gas_weights(lcorner, lweight, lcorners, in_gas_layer)
    z_only = [(0, 0, 0), (0, 0, 1)]

    @ti.func
    def rows_of(i):
        n = 1
        if ti.static(rows > 1):
            n = ti.max(1, ti.min(rows, ti.cast(ti.floor(S.cg[i] + 0.5), ti.i32)))
        return n

    @ti.func
    def below(u):
        """F(u) of eq. (1)."""
        return (1.0 + u) ** 2 * (2.0 - u) / 4.0

    @ti.func
    def row(i, j, n):
        """Row j of n of particle i: (its mid-height point, its share f_j of the volume), eq. (1)."""
        x = S.x[i]
        f = 1.0
        if ti.static(rows > 1):
            if n > 1:
                x[2] += S.radius[i] * (-1.0 + (2.0 * j + 1.0) / n)
                f = below(-1.0 + 2.0 * (j + 1) / n) - below(-1.0 + 2.0 * j / n)
        return x, f

    @ti.func
    def deposit_row(i, vp, j, n):
        x, f = row(i, j, n)
        base, frac = lcic(x, -1)
        s, m = lshare(base, frac, -1)
        for o_t in ti.static(lcorners(-1)):
            o = ti.Vector(o_t)
            G.solid_layer[lcorner(base, o, -1)] += lgweight(base, frac, o, -1, s, m) * (f * vp)

    @ti.func
    def deposit_layers(i, vp):
        if ti.static(rows == 1):
            deposit_row(i, vp, 0, 1)
        else:
            n = rows_of(i)
            for j in range(n):
                deposit_row(i, vp, j, n)

    @ti.func
    def read_layers(x):
        """(sum of w (the layers' voidage), sum of w (their open share)) over the CIC weights w at x."""
        base, frac = lcic(x, -1)
        s, m = lshare(base, frac, -1)
        eps_l = 0.0
        open_l = 0.0
        for o_t in ti.static(lcorners(-1)):
            o = ti.Vector(o_t)
            J = lcorner(base, o, -1)
            open_vol = 1.0
            if ti.static(cut_cells):
                open_vol = G.open_layer[J]
            w = lgweight(base, frac, o, -1, s, m)
            eps_l += w * (1.0 - G.solid_layer[J] * inv_lvol / open_vol)
            open_l += w * open_vol
        return eps_l, open_l

    @ti.func
    def rows_self(i, n):
        """Eq. (2)'s factor along z."""
        out = 0.0
        for j in range(n):
            xa, fa = row(i, j, n)
            ba, ga = lcic(xa, -1)
            for jj in range(n):
                xb, fb = row(i, jj, n)
                bb, gb = lcic(xb, -1)
                for oa_t in ti.static(z_only):
                    oa = ti.Vector(oa_t)
                    wa = ga[2] if oa[2] == 1 else 1.0 - ga[2]
                    for ob_t in ti.static(z_only):
                        ob = ti.Vector(ob_t)
                        if lcorner(ba, oa, -1)[2] == lcorner(bb, ob, -1)[2]:
                            out += fa * fb * wa * (gb[2] if ob[2] == 1 else 1.0 - gb[2])
        return out

    @ti.func
    def layered_voidage(i, x, vp):
        """The voidage particle i of volume vp sees (docs/scenes.md, `gas.voidage`): eps_l, the layers' voidage
        read back with its deposit's weights, with its own share moved from the layer scale to the cell scale in
        proportion to S0(phi) = (1 - phi)^4 / (1 + 2 phi)^2, the Percus-Yevick structure factor at zero wave number
        of its neighbours' solid fraction phi (a loose suspension, S0 -> 1: a lone grain sees the cell voidage; a
        packed bed, S0 -> 0: the layer voidage as it is)."""
        eps_l, open_l = read_layers(x)
        base, frac = lcic(x, -1)
        own_l = vp * inv_lvol / open_l * lself(base, frac)
        if ti.static(not layer_filtered):
            s, m = lshare(base, frac, -1)
            if m:
                own_l = vp * inv_lvol / open_l * lgself(base, frac, s)
        if ti.static(rows > 1):
            n = rows_of(i)
            if n > 1:
                eps_l, open_l = 0.0, 0.0
                for j in range(n):
                    xj, f = row(i, j, n)
                    e, v = read_layers(xj)
                    eps_l += f * e
                    open_l += f * v
                own_l = vp * inv_lvol / open_l * across_self(base, frac) * rows_self(i, n)
        cbase, cfrac = cic(x, -1)
        cs, cm = share(cbase, cfrac, -1)
        own_c = vp * inv_vol / open_l * cself(cbase, cfrac)
        if ti.static(not cell_filtered):  # (filtered: the separable form beside walls too)
            if cm:
                own_c = vp * inv_vol / open_l * gself(cbase, cfrac, cs)
        phi = ti.min(ti.max(1.0 - eps_l - own_l, 0.0), 1.0)
        s0 = (1.0 - phi) ** 4 / (1.0 + 2.0 * phi) ** 2
        return ti.min(ti.max(eps_l + s0 * (own_l - own_c), min_voidage), 1.0)

    return deposit_layers, layered_voidage
