"""Stability limits of the explicit heat updates, checked before the first step: the particle
temperature update (`kernels/heat.py` conductances summed in `kernels/contact.py`, advanced in
`kernels/integrate.py`) and the heated-foil update of tubes and walls (`kernels/integrate.py`).
"""

from __future__ import annotations

import math

import numpy as np

from tidem.kernels.heat import STEFAN_BOLTZMANN, schluender_alpha_wp


def wall_conductance_bound(scene, mats, mat_names, material, radius, surfaces, grain_scale=1.0) -> np.ndarray:
    """Largest conductance [W/K] between each particle and a heated surface it touches:
    Schluender's alpha_WP pi d^2 / 4, the contact spot 2 k a at the largest allowed overlap,
    and with radiation its linearisation 4 sigma T^3 pi r^2 at the hottest fixed temperature;
    a parcel of k^3 grains (`grain_scale` k) carries k^2 grains' (kernels/heat.wall_conductance)."""
    h = scene.heat
    delta = scene.numerics.max_overlap * radius
    k = np.array([mats[m].conductivity or 0.0 for m in mat_names])[material]
    grain_d = 2 * radius / grain_scale
    out = schluender_alpha_wp(h.gas_conductivity, grain_d, h.gas_mean_free_path + h.roughness) * np.pi * radius**2
    out = out + grain_scale * 2 * k * np.sqrt(radius * delta)
    if h.radiation:
        hottest = max([s["T"] for s in surfaces if s["T"] is not None] + [h.initial_temperature])
        out = out + 4 * STEFAN_BOLTZMANN * hottest**3 * np.pi * radius**2
    return out


def thermal_limit(scene, mats, mat_names, material, radius, heat_cap, max_neighbors, surfaces, grain_scale=1.0) -> float:
    """Stability limit of the explicit temperature update: min over particles of m c / H_sum,
    with H_sum the conductance of a full row of contacts at the largest allowed overlap
    (contact spot 2 k a, a = sqrt(R* delta)) plus one wall contact (`wall_conductance_bound`),
    and with particle-fluid-particle conduction up to 20 neighbours at its touching value
    (for parcels, their grains' lenses: delta_f / k in the logarithm)."""
    h = scene.heat
    delta = scene.numerics.max_overlap * radius
    k = np.array([mats[m].conductivity or 0.0 for m in mat_names])[material]
    a = np.sqrt(0.5 * radius * delta)
    wall = wall_conductance_bound(scene, mats, mat_names, material, radius, surfaces, grain_scale)
    conductance = min(max_neighbors, 12) * 2 * k * a + wall
    if h.fluid_layer > 0:  # every neighbour in the lens at the smallest gap
        s_min = h.gas_mean_free_path + h.roughness
        layer = h.fluid_layer * radius / grain_scale
        lens = 2 * np.pi * h.gas_conductivity * 0.5 * radius * (1 + np.log(np.maximum(layer / s_min, 1)))
        conductance += min(max_neighbors, 20) * lens
    return float(np.min(heat_cap / np.maximum(conductance, 1e-300)))


def foil_step_errors(scene, mats, mat_names, material, radius, surfaces, dt, grain_scale=1.0) -> list[str]:
    """The explicit foil update of a heated-foil tube or wall (kernels/integrate.py) is stable
    while dt (h_bed + 2 G / ds^2) / C_A <= 1: C_A the foil's heat capacity per area, h_bed the
    largest bed-side conductance per area (the best wall conductance over the wall area of a
    particle in a close-packed layer, 2 sqrt(3) r^2), G the foil's conductance along a tube's
    circumference and ds the arc length of one angle bin (G = 0 for a wall)."""
    foils = [s for s in surfaces if s.get("flux") is not None]
    if not foils:
        return []
    wall = wall_conductance_bound(scene, mats, mat_names, material, radius, surfaces, grain_scale)
    h_bed = float(np.max(wall / (2 * math.sqrt(3) * radius**2)))
    errs = []
    for t in foils:
        along = 0.0
        if "r" in t:  # a tube: conduction between angle bins
            along = 2 * t["foil_G"] / (2 * math.pi * t["r"] / scene.heat.angle_bins) ** 2
        rate = (h_bed + along) / t["foil_C"]
        if dt * rate > 1.0:
            errs.append(f"{t['name']}.foil_heat_capacity: the explicit foil update needs dt <= C_A / (h_bed + 2 G / ds^2) "
                        f"= {1 / rate:.3g} s, the time step is {dt:.3g} s; raise foil_heat_capacity above "
                        f"{dt * rate * t['foil_C']:.3g} J/(m^2 K), lower foil_conductance, or lower the time step")
    return errs


def heat_step_errors(scene, material, radius, heat_cap, max_neighbors, surfaces, dt,
                     contacts: bool, grain_scale=1.0) -> tuple[float | None, list[str]]:
    """The conduction limit of the particle temperature update (None without contacts) and the
    refusals of a scene with [heat]: a gas lens with no smallest gap, a step above the
    conduction limit, a heated foil whose explicit update the step would make unstable.
    `grain_scale`: k of each particle (parcels of k^3 grains conduct as those grains)."""
    mats = scene.materials
    mat_names = list(mats)
    if scene.heat.fluid_layer > 0 and scene.heat.gas_mean_free_path + scene.heat.roughness <= 0:
        return None, ["heat.roughness: gas conduction between neighbours needs a smallest gap "
                      "gas_mean_free_path + roughness > 0 (got 0); set roughness (e.g. 1e-6) or fluid_layer = 0"]
    limit = (thermal_limit(scene, mats, mat_names, material, radius, heat_cap, max_neighbors, surfaces, grain_scale)
             if contacts else None)
    every = scene.heat.conduction_interval
    if contacts and every > 1 and every * dt > limit:
        fix = (f"lower heat.conduction_interval to {int(limit / dt)} or less" if limit >= dt
               else "set heat.conduction_interval = 1 and lower the time step")
        return limit, [
            f"heat.conduction_interval: the conduction is evaluated every {every} steps, an explicit step of "
            f"{every * dt:.3g} s, above the conduction limit {limit:.3g} s (min over particles of m c / sum of "
            f"contact conductances); {fix}"]
    if contacts and dt > limit:
        return limit, [
            f"heat: the time step {dt:.3g} s exceeds the explicit conduction limit {limit:.3g} s "
            "(min over particles of m c / sum of contact conductances); raise materials.*.heat_capacity, "
            "lower materials.*.conductivity, or lower the time step"]
    return limit, foil_step_errors(scene, mats, mat_names, material, radius, surfaces, dt, grain_scale)
