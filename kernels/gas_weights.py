"""Cloud-in-cell weights over the lattice points the gas's exchange uses (`kernels/gas_coupling.py`).

A grain beside a tube or a mesh reaches, with its CIC cube, cells the gas leaves out (inside a tube, or
sealed off behind a mesh) and faces inside them. The plain weights would put part of its volume, drag and
heat there, where the gas never sees them, and read back voidage, velocity and temperature from there: in
a packed bed between two mesh plates the gas ran along the plates at 1.5 times the middle's velocity and
the bed's pressure drop fell to 0.74 of Ergun's (docs/validation.md). With these weights a grain's CIC
cube keeps only the points the exchange uses, each weight divided by their sum, so that its volume, drag
and heat all reach the gas and what it reads is the gas's. A wall's own face, where it bounds a cell of
the gas, stays a point: the gas's normal velocity there is zero, as on the box's own walls (which are
treated as before). Where every point of the cube counts the weights are the plain ones, to the bit;
where none does (a grain sealed off with its cell) the plain ones too. The open volume the voidage and
drag are then taken over is `tidem.gas.open_volume`'s (docs/design/near_wall_weights.md).
"""

import taichi as ti

from .gas_grid import CLOSED


def make_in_gas(gg, G, layers: int):
    """Return (in_gas(J, stagger), in_gas_layer(J, stagger)): lattice point J is one the gas flows in. A cell
    (stagger -1): not solid (G.solid). A face normal to axis `stagger`: not closed, or closed but bounding a
    cell of the gas, where the gas's normal velocity is known, 0 (a wall's face, as the box's own walls are
    without tubes and meshes); the faces inside a tube or behind a mesh are left out. A layer cell of the
    layered voidage (`gas_grid.layer_grid`, `layers` per cell): its gas cell is not solid."""
    per, n = gg.periodic, gg.cells

    @ti.func
    def in_gas(J, stagger: ti.template()):
        ok = True
        if ti.static(stagger < 0):
            ok = G.solid[J] == 0
        else:
            if G.kind[stagger][J] == CLOSED:  # a wall's face where it bounds a cell of the gas (u_n = 0 there)
                below = J
                below[stagger] -= 1
                if ti.static(per[stagger]):
                    below[stagger] = (below[stagger] + n[stagger]) % n[stagger]
                    ok = G.solid[below] == 0 or G.solid[J] == 0
                else:
                    ok = (J[stagger] > 0 and G.solid[below] == 0) or (J[stagger] < n[stagger] and G.solid[J] == 0)
        return ok

    @ti.func
    def in_gas_layer(J, stagger: ti.template()):
        return G.solid[J[0], J[1], J[2] // layers] == 0

    return in_gas, in_gas_layer


def make_gas_weights(corner, weight, corners, point_in_gas):
    """For one lattice (`corner`, `weight`, `corners` of `gas_grid.make_cic`) and its test point_in_gas(J,
    stagger), return (gas_share, gas_weight, gas_self_share):
    gas_share(base, frac, stagger) -> (s, masked): masked where some corners of the cube lie out of the gas
    and some in it, s = 1 / (the weights of those in it), else (1, False);
    gas_weight(base, frac, o, stagger, s, masked): corner o's weight times s, 0 for a corner out of the gas;
    gas_self_share(base, frac, s): (cells only) the sum over the distinct points in the gas of the squared
    weight there, the masked form of `make_self_share` (corners that fold onto one point at a
    wall or on a one-point axis count as one)."""

    @ti.func
    def gas_share(base, frac, stagger: ti.template()):
        inside = 0.0
        outside = 0
        for o_t in ti.static(corners(stagger)):
            o = ti.Vector(o_t)
            if point_in_gas(corner(base, o, stagger), stagger):
                inside += weight(frac, o, stagger)
            else:
                outside += 1
        s = 1.0
        masked = outside > 0 and inside > 0.0
        if masked:
            s = 1.0 / inside
        return s, masked

    @ti.func
    def gas_weight(base, frac, o, stagger: ti.template(), s, masked):
        w = weight(frac, o, stagger) * s
        if masked:
            if not point_in_gas(corner(base, o, stagger), stagger):
                w = 0.0
        return w

    @ti.func
    def gas_self_share(base, frac, s):
        zero = ti.Vector([0, 0, 0])
        out = 0.0
        for o_t in ti.static(corners(-1)):
            o = ti.Vector(o_t)
            first = True  # the first of the corners that fold onto its point
            w = s
            for a in ti.static(range(3)):
                o1 = ti.Vector([0, 0, 0])
                o1[a] = 1
                if corner(base, zero, -1)[a] == corner(base, o1, -1)[a]:
                    if o[a] == 1:
                        first = False
                else:
                    w *= frac[a] if o[a] == 1 else 1.0 - frac[a]
            if first and point_in_gas(corner(base, o, -1), -1):
                out += w * w
        return out

    return gas_share, gas_weight, gas_self_share


def plain_weights(weight):
    """(gas_share, gas_weight, gas_self_share) of `gas_weights.make_gas_weights` where every lattice point is
    the gas's (no tubes or meshes): the plain CIC weights, unmasked."""

    @ti.func
    def gas_share(base, frac, stagger: ti.template()):
        return 1.0, False

    @ti.func
    def gas_weight(base, frac, o, stagger: ti.template(), s, masked):
        return weight(frac, o, stagger)

    @ti.func
    def gas_self_share(base, frac, s):
        return 0.0

    return gas_share, gas_weight, gas_self_share


def make_self_share(corner, own=(0.0, 0.0, 0.0)):
    """Return self_share(base, frac): the sum over lattice points J of (the CIC weight a particle puts on J)^2,
    what its own volume adds (per unit of volume / cell volume) to the voidage it reads back with the same
    weights; two corners folded onto one point at a wall, or wrapped onto one on a one-cell periodic axis, count
    as one point. Along an axis the averaging-length filter widens (`own[a]` > 0, `kernels/gas_smoothing.py`)
    that axis's factor is own[a]."""

    @ti.func
    def self_share(base, frac):
        s = 1.0
        for a in ti.static(range(3)):
            o1 = ti.Vector([0, 0, 0])
            o1[a] = 1
            if ti.static(own[a] > 0.0):
                s *= own[a]
            elif corner(base, ti.Vector([0, 0, 0]), -1)[a] != corner(base, o1, -1)[a]:
                s *= (1.0 - frac[a]) ** 2 + frac[a] ** 2
        return s

    return self_share
