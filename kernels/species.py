"""Transport of a gas species (O2) as a mass fraction Y on the gas grid's cells.

Finite volume, explicit, conservative (one gas step dt, cell volume V, gas density rho):
  rho [eps^{n+1} Y^{n+1} - eps^n Y^n] V / dt + rho sum_f (eps u)_f A_f Y_up
      = rho D sum_f eps_f A_f (Y_nb - Y) / h_f - S / dt,
advection upwind with the same face fluxes as the gas energy (`gas_energy.upwind`), Fickian
diffusion across interior faces only (no diffusive flux through walls, inlet or outlet), and
S [kg] the O2 particles consumed in the cell since the last gas step (`o2_sink`, deposited by
`kernels/reactions.py`). Stable for D dt sum(1/h^2) <= 1/2 (refused at set-up) and while a
cell holds the O2 its particles take: a cell that would go negative is reported (`bsum[2]`
gets the most negative value) and the gas step refuses it. The O2 that entered through the
inlet and outlet is summed in bsum[1] [kg], so O2 in the gas + O2 consumed - bsum[1] is constant.
"""

import taichi as ti

from .gas_grid import serial_loops


def make_species_kernel(gg, G, flow: dict, rho: float, diffusivity: float):
    """Return `species(dt, y_in)` advancing G.Y by one gas step."""
    vol = gg.volume
    serial = serial_loops(gg)  # the grid's loops in one thread (small grids on the CPU)
    cells = tuple(gg.cells)
    upwind, interior_diffusion, part = flow["upwind"], flow["interior_diffusion"], flow["part"]

    @ti.kernel
    def species(dt: ti.f64, y_in: ti.f64):
        G.bsum[2] = 0.0
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
            G.Y_new[I] = G.Y[I]
            if G.solid[I] == 0:
                net, boundary = upwind(G.Y, I, y_in, False)
                diff = interior_diffusion(G.Y, I)
                v = vol * part(I)
                y = (G.eps_old[I] * G.Y[I] * v - dt * net + dt * diffusivity * diff - G.o2_sink[I] / rho) \
                    / (G.eps[I] * v)
                G.o2_sink[I] = 0.0
                G.bsum[1] += -dt * rho * boundary
                if y < 0.0:
                    ti.atomic_min(G.bsum[2], y)
                G.Y_new[I] = y
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for I in ti.grouped(ti.ndrange(*cells)):
            G.Y[I] = G.Y_new[I]

    return species
