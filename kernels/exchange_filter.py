"""The drag's exchange and the gas velocity a grain reads, averaged over the voidage's averaging length.

With `gas.drag_averaging = "length"` the drag coefficients the grains deposit on the faces of the gas grid
(`kernels/gas_coupling.py`: b_f = sum_p w_pf K_p and bv_f = sum_p w_pf K_p v_p, with the layered voidage
b_f = sum_p w_pf K_p / eps_p) are spread by the steps of eq. (2) of `kernels/gas_smoothing.py` on each face
lattice, and the gas velocity a grain reads is taken through the transposed steps:

    B = A^N b (times eps_f with the layered voidage),   Bv = A^N bv                                   (3)
    u~ = D^-1 A^N D s,   s_f = u_f (the layered voidage: eps_f u_f, the superficial velocity)          (4)

A is one step of eq. (2) with the face's open share f (D = diag(f)): the open volume of its drag
(`G.open_face`, 1 without tubes and meshes) on faces where the gas's velocity is solved (between cells and at
the outlet), 0 on walls and at the inlet, which keep their values and take no part. A = I + M D^-1 with M
symmetric, so A^T = I + D^-1 M = D^-1 A D: eq. (4) reads through the transpose of eq. (3). Then
sum_p K_p w_p . u~ = b . (A^N)^T s = (A^N b) . s, and A keeps sums, so the drag the gas feels,
sum_f B_f u_f - Bv_f, is still exactly minus the particles' (Capecelatro & Desjardins 2013, J. Comput. Phys. 238,
1-31, filter the exchange likewise with a width set apart from the mesh; reading through the transpose is what
keeps the balance exact here). The filter is the cells' (`tidem.gas.geometry.voidage_filters`): the face lattices
have the cells' spacing, so eq. (1) gives the same variance.
"""

import taichi as ti

from .gas_grid import INTERIOR, OUTLET
from .gas_smoothing import Filter, make_step_at


def make_exchange_filter(plan: Filter, gg, G, layered: bool, open_faces: bool, serial: bool, face_voidage):
    """Return (read_velocity(), spread_drag()): read_velocity fills G.uf with u~ of eq. (4) from G.u (and G.eps);
    spread_drag turns the deposits b, bv in G.B, G.Bv into B, Bv of eq. (3). face_voidage(J, c) is eps_f of face J
    normal to c (a Taichi func). Scratch: G.face_tmp, G.face_tmp2."""
    faces = [gg.face_shape(c) for c in range(3)]
    U, B, BV, UF, T1, T2 = G.u, G.B, G.Bv, G.uf, G.face_tmp, G.face_tmp2

    def open_share(c: int):
        @ti.func
        def share(I):
            kind = G.kind[c][I]
            f = 0.0
            if kind == INTERIOR or kind == OUTLET:
                f = 1.0
                if ti.static(open_faces):
                    f = G.open_face[c][I]
            return f

        return share

    shares = [open_share(c) for c in range(3)]
    steps = [make_step_at(plan, faces[c], gg.periodic, shares[c]) for c in range(3)]

    def over_faces(body):
        """A kernel running body(c, I) (a Taichi func, c static) at every face I of every face lattice c."""

        @ti.kernel
        def run():
            for c in ti.static(range(3)):
                if ti.static(serial):
                    ti.loop_config(serialize=True)
                for I in ti.grouped(ti.ndrange(*faces[c])):
                    body(c, I)

        return run

    def sweep(pairs):
        """A kernel of one step of eq. (2) on every face lattice, from each pair's source field into its target."""

        @ti.func
        def body(c: ti.template(), I):
            for k in ti.static(range(len(pairs))):
                ti.static(steps[c])(ti.static(pairs[k][0][c]), ti.static(pairs[k][1][c]), I)

        return over_faces(body)

    drag_there, drag_back = sweep([(B, T1), (BV, T2)]), sweep([(T1, B), (T2, BV)])
    velocity_there, velocity_back = sweep([(UF, T1)]), sweep([(T1, UF)])

    @ti.func
    def weigh(c: ti.template(), I):
        """UF = D s of eq. (4); s itself where f = 0 (kept by the steps)."""
        s = U[c][I]
        if ti.static(layered):
            s *= face_voidage(I, c)
        f = ti.static(shares[c])(I)
        UF[c][I] = f * s if f > 0.0 else s

    @ti.func
    def unweigh(c: ti.template(), I):
        f = ti.static(shares[c])(I)
        if f > 0.0:
            UF[c][I] /= f

    @ti.func
    def times_voidage(c: ti.template(), I):
        B[c][I] *= face_voidage(I, c)

    weigh_velocity, unweigh_velocity, times_face_voidage = over_faces(weigh), over_faces(unweigh), \
        over_faces(times_voidage)

    def read_velocity():
        weigh_velocity()
        for _ in range(plan.steps // 2):
            velocity_there()
            velocity_back()
        unweigh_velocity()

    def spread_drag():
        for _ in range(plan.steps // 2):
            drag_there()
            drag_back()
        if layered:
            times_face_voidage()

    return read_velocity, spread_drag
