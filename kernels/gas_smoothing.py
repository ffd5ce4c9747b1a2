"""The voidage's averaging length, set apart from the gas cell: a diffusion filter of the deposited solid volume.

Averaging a particle quantity with a Gaussian kernel is solving the diffusion equation d(phi)/d(tau) = lap(phi)
from the deposited field up to a pseudo-time tau (Sun & Xiao 2015, Int. J. Multiphase Flow 72, 233-247;
the kernel's variance per axis grows by 2 tau). Capecelatro & Desjardins 2013 (J. Comput. Phys. 238, 1-31)
filter their Lagrangian-Eulerian exchange the same way, with a filter width set apart from the mesh.

Cloud-in-cell deposition and read-back on cells of size h average over a kernel of variance h^2 / 3 per axis (two
hat functions of variance h^2 / 6): the variance of a box of width 2 h. With `gas.averaging_length` L the voidage
a grain sees is averaged over the variance of a box of width L, L^2 / 12, on any grid: the filter adds
    2 tau_a = max(L^2 / 12 - h_a^2 / 3, 0)                                                    (1)
along each axis a with more than one cell. Explicit steps of the conservative, no-flux form
    V_c += sum_{c' beside c along a} lam_a min(f_c, f_c') (V_c' / f_c' - V_c / f_c)            (2)
(V_c the solid volume of lattice point c, f_c its open share, 0 in a solid cell; lam_a = tau_a / (N h_a^2) per
step) keep the total solid volume to rounding, keep a uniform bed uniform up to walls and tubes, and add
exactly 2 lam_a h_a^2 of variance per step away from walls; sum_a 2 lam_a <= 1/2 keeps each step monotone.
"""

import math
from dataclasses import dataclass

import taichi as ti

MONOTONE = 0.5  # bound on sum_a 2 lam_a per step


@dataclass(frozen=True)
class Filter:
    """The steps of eq. (2) on one lattice: `steps` (even), `lam` per axis and, per axis, the share of a grain's
    own volume it reads back at its own place (`own`, 0 where the axis is not filtered: the CIC value holds)."""

    steps: int
    lam: tuple[float, float, float]
    own: tuple[float, float, float]


def plan_filter(h, cells, length: float | None, axes=(0, 1, 2)) -> Filter | None:
    """The filter of eq. (1)-(2) for a lattice of spacing h and `cells` per axis, along `axes`; None where no
    axis needs one (no length, or cells coarser than L / 2). `own`: a Gaussian read back at its centre,
    h / (sqrt(2 pi) s) with s^2 = h^2 / 3 + 2 tau (the CIC self-share averaged over positions, 2/3, is
    h / (sqrt(2 pi) h / sqrt(3)) = 0.69 of this form at tau = 0)."""
    if length is None:
        return None
    total = [0.0, 0.0, 0.0]
    own = [0.0, 0.0, 0.0]
    for a in axes:
        tau = 0.5 * max(length**2 / 12.0 - h[a] ** 2 / 3.0, 0.0)
        if cells[a] > 1 and tau > 0.0:
            total[a] = tau / h[a] ** 2
            own[a] = h[a] / math.sqrt(2.0 * math.pi * (h[a] ** 2 / 3.0 + 2.0 * tau))
    if not any(total):
        return None
    steps = max(2, math.ceil(2.0 * sum(total) / MONOTONE))
    steps += steps % 2
    return Filter(steps, tuple(t / steps for t in total), tuple(own))


def make_step_at(plan: Filter, shape, periodic, open_share):
    """Return step_at(src, dst, I): one step of eq. (2) at lattice point I of a lattice of `shape`, from field src
    into dst (a Taichi func); open_share(I) is f of point I (a Taichi func). A point with f = 0 keeps its value and
    takes no part in its neighbours' steps."""
    lam = plan.lam

    @ti.func
    def step_at(src: ti.template(), dst: ti.template(), I):
        fi = open_share(I)
        out = src[I]
        if fi > 0.0:
            phi = src[I] / fi
            for a in ti.static(range(3)):
                if ti.static(lam[a] > 0.0):
                    for side in ti.static((-1, 1)):
                        J = I
                        J[a] += side
                        inside = True
                        if ti.static(periodic[a]):
                            J[a] = (J[a] + shape[a]) % shape[a]
                        else:
                            inside = 0 <= J[a] < shape[a]
                        if inside:
                            fj = open_share(J)
                            if fj > 0.0:
                                out += lam[a] * ti.min(fi, fj) * (src[J] / fj - phi)
        dst[I] = out

    return step_at


def make_filter(plan: Filter, shape, periodic, vol, tmp, open_share, serial: bool):
    """Return apply(): `plan.steps` steps of eq. (2) on field `vol` (solid volume per lattice point, `shape`),
    through the scratch field `tmp`; open_share(I) is f of point I (a Taichi func)."""
    step_at = make_step_at(plan, shape, periodic, open_share)

    @ti.kernel
    def step(src: ti.template(), dst: ti.template()):
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*shape)):
            step_at(src, dst, I)

    def apply():
        for _ in range(plan.steps // 2):
            step(vol, tmp)
            step(tmp, vol)

    return apply


def make_open_shares(G, cut_cells: bool, layers: int):
    """Return (cell_open(I), layer_open(I)): f of eq. (2) at a cell and at a layer, the open share of its volume
    (G.open, G.open_layer) with tubes or meshes in the gas, 0 in a solid cell, else 1."""

    @ti.func
    def cell_open(I):
        f = 1.0
        if ti.static(cut_cells):
            f = G.open[I] if G.solid[I] == 0 else 0.0
        return f

    @ti.func
    def layer_open(I):
        f = 1.0
        if ti.static(cut_cells):
            f = G.open_layer[I] if G.solid[I[0], I[1], I[2] // layers] == 0 else 0.0
        return f

    return cell_open, layer_open
