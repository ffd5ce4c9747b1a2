"""The gas step's checks after the velocity correction (`kernels/gas_flow.py`): the continuity residual
and the Courant number the gas energy and species advection are held to (`tidem.gas.phase`, `tidem.gas.limits`)."""

import taichi as ti

from .gas_grid import serial_loops


def make_check_kernels(gg, G, index, cut_faces: bool) -> dict:
    """Return {"divergence", "courant"} for gas grid `gg`, fields `G` and the grid's index functions `index`
    (`gas_flow.make_flow_kernels`); with `cut_faces` the faces' apertures and the cells' gas parts count."""
    serial = serial_loops(gg)
    cells = tuple(gg.cells)
    faces = [gg.face_shape(c) for c in range(3)]
    h = ti.Vector(list(gg.h))
    U = G.u
    unit, face_index, face_eps, aperture, part = index.unit, index.face_index, index.face_eps, index.aperture, index.part

    @ti.kernel
    def divergence(dt: ti.f64) -> ti.f64:
        """max over fluid cells of |d eps/dt + div(eps u)| [1/s] after the correction."""
        worst = 0.0
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
            if G.solid[I] == 0:
                div = part(I) * (G.eps[I] - G.eps_old[I]) / dt
                for c in ti.static(range(3)):
                    fp = face_index(I + unit(c), c)
                    div += (aperture(fp, c) * face_eps(fp, c) * U[c][fp] - aperture(I, c) * face_eps(I, c) * U[c][I]) / h[c]
                ti.atomic_max(worst, ti.abs(div / part(I)))
        return worst

    @ti.kernel
    def courant(dt: ti.f64) -> ti.f64:
        """Largest face Courant number |u| dt / h (the gas energy's MUSCL faces are total variation
        diminishing up to 0.5); with cut faces, also half the share of a cut cell's gas it loses in a step,
        sum over its faces of a_f max(u_f out, 0) dt / (f h): its faces are first order (`gas_energy`),
        bounded while that share is at most 1."""
        worst = 0.0
        for c in ti.static(range(3)):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*faces[c])):
                ti.atomic_max(worst, ti.abs(U[c][I]) * dt / h[c])
        if ti.static(cut_faces):
            if ti.static(serial):
                ti.loop_config(serialize=True)
            for I in ti.grouped(ti.ndrange(*cells)):
                if G.solid[I] == 0 and G.part[I] < 1.0:
                    leaving = 0.0
                    for c in ti.static(range(3)):
                        high = face_index(I + unit(c), c)
                        leaving += (ti.max(-U[c][I], 0.0) * G.aperture[c][I]
                                    + ti.max(U[c][high], 0.0) * G.aperture[c][high]) / h[c]
                    ti.atomic_max(worst, 0.5 * leaving * dt / G.part[I])
        return worst

    return dict(divergence=divergence, courant=courant)
