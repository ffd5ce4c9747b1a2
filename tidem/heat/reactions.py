"""Reacting particles, set-up side: the scene's `[[reactions]]` turned into plain numbers for
`kernels/reactions.py`, the stability refusals before the first step, and the balances and
observables a run reports. The equations are in the kernel module's docstring.

Reaction constants (per kg of carbon; co_fraction phi = share of the carbon leaving as CO):
  O2 used       nu M_O2 / M_C,   nu = 1 - phi/2 mol O2 per mol C
  heat          [(1 - phi) 393.5 + phi 110.5] kJ/mol / M_C   (C + O2 -> CO2, C + 1/2 O2 -> CO)
"""

from __future__ import annotations

import math

import numpy as np

from tidem.gas.geometry import gas_grid
from tidem.gas.limits import fastest_inlet
from tidem.gas.species import M_O2
from tidem.kernels.reactions import (CHAR, ENTHALPY_OUT, ESCAPED, GONE, HEAT_RELEASED, LATENT,  # noqa: F401
                                     MASS_ESCAPED, O2_USED, POLY, REACTED, SUBL)
from tidem.scene.schedule import lowest, peak

R_GAS = 8.314462618  # J/(mol K)
M_C = 0.012011  # kg/mol
H_CO2 = 393.5e3  # J/mol C, C + O2 -> CO2
H_CO = 110.5e3  # J/mol C, C + 1/2 O2 -> CO
MAX_FRACTION = 0.01  # largest share of a particle's mass one step may consume or add

KIND_IDS = {"char_combustion": CHAR, "polymerization": POLY, "sublimation": SUBL}

N_SUMS = 9  # S.rsum slots, named in kernels/reactions.py


def reaction_constants(scene) -> list[dict]:
    """One dict of plain numbers per reaction, in scene order (what the kernels bake in)."""
    out = []
    groups = [g.name for g in scene.particles]
    for r in scene.reactions:
        group = groups.index(r.group)
        c = dict(kind=KIND_IDS[r.type], group=group, cg=scene.particles[group].coarse_grain)
        if r.type == "char_combustion":
            ox = scene.gas.oxygen
            phi = r.co_fraction
            nu = 1.0 - 0.5 * phi
            c.update(A=r.pre_exponential, E_R=r.activation_energy / R_GAS, shrink=r.burnout == "shrink",
                     o2_per_c=nu * M_O2 / M_C, heat_per_c=((1 - phi) * H_CO2 + phi * H_CO) / M_C,
                     film=M_C / (nu * R_GAS), x_per_y=ox.molar_mass / M_O2, pressure=ox.pressure,
                     D=ox.diffusivity, sc=scene.gas.viscosity / (scene.gas.density * ox.diffusivity))
        elif r.type == "polymerization":
            c.update(k=r.rate_constant * r.monomer_pressure, E_R=r.activation_energy / R_GAS,
                     T_ref=r.reference_temperature, enthalpy=r.enthalpy, grow=r.growth,
                     d_max=r.max_diameter or 0.0)
        else:
            z = scene.domain.max[2] if r.exit_height is None else r.exit_height
            c.update(T_s=r.temperature, L=r.latent_heat, exit=z)
        out.append(c)
    return out


def reaction_index(scene, group: np.ndarray) -> np.ndarray:
    """Per particle: the index of its group's reaction, -1 for inert particles."""
    by_group = {[g.name for g in scene.particles].index(r.group): i for i, r in enumerate(scene.reactions)}
    return np.array([by_group.get(int(g), -1) for g in group], np.int32)


def reaction_step_checks(scene, dt: float, radius: np.ndarray, density: np.ndarray, rx: np.ndarray) -> list[str]:
    """Refusals before the first step: a step that would consume (or turn into vapour) more
    than MAX_FRACTION of a particle's mass at its starting size, with the largest rate the
    scene allows, and the explicit O2 diffusion number on the gas grid."""
    errs = []
    gas, heat = scene.gas, scene.heat
    for i, r in enumerate(scene.reactions):
        sel = rx == i
        if not sel.any():
            continue
        d = 2.0 * float(radius[sel].min())
        rho = float(density[sel][np.argmin(radius[sel])])
        key = f"reactions[{i}]"
        if r.type == "polymerization":
            if r.growth:  # mass added per step, at the reference temperature's rate
                per_s = r.rate_constant * r.monomer_pressure
                if per_s * dt > MAX_FRACTION:
                    errs.append(f"{key}: a step of {dt:.3g} s grows a particle's mass by {100 * per_s * dt:.2g} % "
                                f"(limit {100 * MAX_FRACTION:g} %); use numerics.dt <= {MAX_FRACTION / per_s:.3g}")
            continue  # heat: its explicit limit is the temperature step
        temps = [heat.initial_temperature, lowest(gas.inlet_temperature) or 0.0, peak(gas.inlet_temperature) or 0.0,
                 gas.initial_temperature or 0.0]
        temps += [g.temperature or 0.0 for g in scene.particles]
        if r.type == "char_combustion":
            ox = gas.oxygen
            # film limit (bounds the series rate) at the coldest film and the fastest slip
            re = gas.density * _max_speed(gas) * d / gas.viscosity
            sc = gas.viscosity / (gas.density * ox.diffusivity)
            sh = 2.0 + 0.6 * math.sqrt(re) * sc ** (1 / 3)
            nu = 1.0 - 0.5 * r.co_fraction
            t_f = min(t for t in temps if t > 0)
            k_d = M_C / nu * sh * ox.diffusivity / (d * R_GAS * t_f)
            x = max(ox.mole_fraction, ox.initial_mole_fraction or 0.0)
            per_s = math.pi * d * d * k_d * x * ox.pressure / (rho * math.pi * d**3 / 6)
            what = "burns"
        else:
            re = gas.density * _max_speed(gas) * d / gas.viscosity
            pr = gas.heat_capacity * gas.viscosity / heat.gas_conductivity
            nu_max = 2.0 + 0.6 * math.sqrt(re) * pr ** (1 / 3)
            t_hot = max(temps)
            q = nu_max * heat.gas_conductivity * math.pi * d * max(t_hot - r.temperature, 0.0)
            per_s = q / (rho * math.pi * d**3 / 6 * r.latent_heat)
            what = "sublimates"
        if per_s * dt > MAX_FRACTION:
            errs.append(f"{key}: a step of {dt:.3g} s {what} up to {100 * per_s * dt:.2g} % of the smallest particle's "
                        f"mass (limit {100 * MAX_FRACTION:g} %); use numerics.dt <= {MAX_FRACTION / per_s:.3g}")
    if gas is not None and gas.oxygen is not None:
        h = gas_grid(scene).h
        dt_gas = gas.coupling_interval * dt
        number = gas.oxygen.diffusivity * dt_gas * sum(1 / v**2 for v in h)
        if number > 0.5:
            stable = max(1, int(0.5 / (gas.oxygen.diffusivity * dt * sum(1 / v**2 for v in h))))
            errs.append(f"gas.oxygen.diffusivity: the O2 diffusion number D dt_gas sum(1/h^2) = {number:.2f} exceeds "
                        f"0.5; use gas.coupling_interval <= {stable} or larger gas cells")
    return errs


def _max_speed(gas) -> float:
    return fastest_inlet(gas) / gas.min_voidage


def reaction_summary(solver) -> dict:
    """Time-series columns: totals of the reaction accumulators and the O2 left in the gas."""
    s = solver.state.rsum.to_numpy()
    out = dict(reacted_mass_kg=float(s[REACTED]), reaction_heat_J=float(s[HEAT_RELEASED]),
               latent_heat_J=float(s[LATENT]), particles_gone=round(s[GONE]), particles_escaped=round(s[ESCAPED]))
    if solver.model.features.species:
        out["o2_used_kg"] = float(s[O2_USED])
        out["gas_o2_mean_mole_fraction"] = solver.gas.mean_o2_mole_fraction()
    return out
