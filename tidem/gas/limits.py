"""Stability refusals of the gas phase before the first step (`build_model` calls
`gas_step_checks`): drag relaxation time, gas Courant, diffusion and conduction numbers of
the explicit gas step (`kernels/gas_flow.py`, `kernels/gas_coupling.py`). The gas step
checks the Courant number again as it runs (`tidem.gas.phase.GasPhase.step`).
"""

from __future__ import annotations

import numpy as np

from tidem.gas.geometry import gas_grid
from tidem.kernels.gas_grid import GasGrid
from tidem.scene.schedule import first_above, is_scheduled, peak

MAX_COURANT = 0.5


def drag_rate_bound(gas, d: float, rho_p: float) -> float:
    """Upper estimate of K/m [1/s] for a particle of diameter d and density rho_p: the larger
    of the Wen-Yu Stokes-range drag at eps = 0.8 (Re from the fastest inlet velocity) and the
    Ergun drag at the clipped voidage; twice that for margin."""
    u = fastest_inlet(gas) / gas.min_voidage
    mu, rho = gas.viscosity, gas.density
    re = rho * u * d / mu
    wen_yu = 18 * mu / (rho_p * d * d) * (1 + 0.15 * re**0.687) * 0.8**-2.65
    eps = gas.min_voidage
    ergun = (150 * (1 - eps) * mu / (eps * d * d) + 1.75 * rho * u / (eps * d)) / rho_p
    return 2.0 * max(wen_yu, ergun)


def inlet_velocities(gas) -> list[tuple[str, object]]:
    """(key, value or schedule) of the background inlet velocity and each nozzle's."""
    return [("gas.inlet_velocity", gas.inlet_velocity)] + [
        (f"gas.nozzles[{i}].velocity", nz.velocity) for i, nz in enumerate(gas.nozzles)]


def fastest_inlet(gas) -> float:
    """The largest superficial inlet velocity at any time of the run [m/s]."""
    return max(peak(u) for _, u in inlet_velocities(gas))


def first_inlet_above(gas, limit: float) -> tuple[str, float] | None:
    """(key, time [s]) of the scheduled inlet velocity that first exceeds `limit` m/s, or None (also
    where only constant velocities exceed it: they do from the start)."""
    times = [(t, key) for key, u in inlet_velocities(gas) if is_scheduled(u) and (t := first_above(u, limit)) is not None]
    return (min(times)[1], min(times)[0]) if times else None


def fixed_bed_voidage(gg: GasGrid, x: np.ndarray, radius: np.ndarray) -> float:
    """Smallest voidage of a gas cell holding a fixed bed: particle volumes binned to the cell
    of their centre (the bed never moves, so this is the voidage the gas always sees)."""
    idx = np.floor((x - np.asarray(gg.lo)) / np.asarray(gg.h)).astype(int)
    idx = np.clip(idx, 0, np.asarray(gg.cells) - 1)
    solid = np.zeros(gg.cells)
    np.add.at(solid, tuple(idx.T), 4.0 / 3.0 * np.pi * radius**3)
    return float(1.0 - solid.max() / (gg.h[0] * gg.h[1] * gg.h[2]))


def gas_step_checks(scene, dt: float, radius: np.ndarray, density: np.ndarray,
                    fixed_x: np.ndarray | None = None, grain_radius: np.ndarray | None = None) -> list[str]:
    """Refusals before the first step: drag relaxation, gas Courant and diffusion numbers.
    The Courant number takes the interstitial inlet velocity at `gas.min_voidage` (a moving
    bed may pack that far), or for a bed whose particles are all fixed (at `fixed_x`) at its
    densest cell's voidage. The drag relaxation time is the grains' (`grain_radius`, for
    coarse-grained parcels; default `radius`)."""
    gas = scene.gas
    gg = gas_grid(scene)
    errs = []
    grain = radius if grain_radius is None else grain_radius
    i = int(np.argmin(density * grain**2))
    rate = drag_rate_bound(gas, 2 * grain[i], density[i])
    if dt * rate > 1.0:
        errs.append(f"gas: the drag relaxation time of the smallest, lightest particles (about {1 / rate:.3g} s) is "
                    f"shorter than the time step {dt:.3g} s; use numerics.dt <= {1 / rate:.3g} (or a smaller "
                    "dt_fraction), or larger particles")
    dt_gas = gas.coupling_interval * dt
    voidage = gas.min_voidage if fixed_x is None else max(gas.min_voidage, fixed_bed_voidage(gg, fixed_x, radius))
    u = fastest_inlet(gas) / voidage
    courant = u * dt_gas / min(gg.h)
    if courant > MAX_COURANT:
        stable = max(1, int(MAX_COURANT * min(gg.h) / (u * dt)))
        passed = first_inlet_above(gas, MAX_COURANT * min(gg.h) / dt_gas * voidage)
        when, fix = "", ""
        if passed is not None:
            when = f" that {passed[0]} reaches at t = {passed[1]:.4g} s on its schedule"
            fix = f", or keep {passed[0]} below {MAX_COURANT * min(gg.h) / dt_gas * voidage:.3g} m/s"
        errs.append(f"gas.coupling_interval: a gas step of {dt_gas:.3g} s gives a Courant number {courant:.2f} at the "
                    f"interstitial inlet velocity {u:.3g} m/s{when} (limit {MAX_COURANT}); use coupling_interval <= "
                    f"{stable}{fix}")
    diffusion = gas.viscosity / gas.density * dt_gas * sum(1 / h**2 for h in gg.h)
    if diffusion > 0.5:
        stable = max(1, int(0.5 / (gas.viscosity / gas.density * dt * sum(1 / h**2 for h in gg.h))))
        errs.append(f"gas.coupling_interval: the gas diffusion number nu dt sum(1/h^2) = {diffusion:.2f} exceeds 0.5; "
                    f"use coupling_interval <= {stable} or larger gas cells")
    if scene.heat is not None and gas.conduction:
        # explicit conduction stays positive while alpha dt sum(2/h^2) eps_f/eps <= 1, and a face
        # between a cell at min_voidage and an empty one has eps_f/eps = (1 + 1/min_voidage)/2
        per_dt = (scene.heat.gas_conductivity / (gas.density * gas.heat_capacity) * sum(1 / h**2 for h in gg.h)
                  * (1 + 1 / gas.min_voidage) / 2)
        if per_dt * dt_gas > 0.5:
            stable = max(1, int(0.5 / (per_dt * dt)))
            errs.append(f"gas.conduction: the gas conduction number alpha dt sum(1/h^2) (1 + 1/min_voidage)/2 = "
                        f"{per_dt * dt_gas:.2f} exceeds 0.5; use gas.coupling_interval <= {stable}, larger gas cells, "
                        "or gas.conduction = false")
    return errs
