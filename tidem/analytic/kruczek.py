"""Source 4's explicit (forward-difference) scheme for the temperatures of a gas flowing
through a granular bed (Kruczek 1992, seed 004), without conduction in the solid.

The bed is split into elements of thickness dx; each is isothermal during a step dt and
exchanges heat with the gas at the temperature of the gas *entering* it (assumptions a, b).
Per unit cross-section, with W_G = G c_g and W_s = dx (1 - eps) rho_s c_s (constant
properties, so chi_G = chi_s = 1 in eqs. 8 and 10):
    eq. 7:  T_G,i+1 = T_G,i - phi_G (T_G,i - T_s,i),     phi_G = dx ha / W_G,
    eq. 9:  T_s,i(t + dt) = T_s,i + phi_s dt (T_G,i - T_s,i),   phi_s = dx ha / W_s
(the source's eq. 9 prints phi_G where eq. 10 defines phi_s; the conduction term of eq. 9
drops out for R -> infinity, i.e. no solid conduction, as in Schumann's model). The source's
limits are enforced: eq. 12, 1 - phi_G > 0 (element thickness), and eq. 14,
dt < (1 - phi_G) / phi_s (the gas leaving an element stays hotter than its solid). The gas
holdup is neglected (the gas is steady within a step).
"""

from __future__ import annotations

import math

import numpy as np

from tidem.analytic.packed_bed import PackedBed


def explicit_profiles(bed: PackedBed, length: float, times, heights, elements: int = 200,
                      dt_fraction: float = 0.05) -> np.ndarray:
    """Solid temperature [K] at `heights` [m] (interpolated between element centres) at each of
    `times` [s]; shape [len(times), len(heights)]. The step is dt_fraction times the eq. 14 limit
    (a positivity limit, not an accuracy one: Euler steps near it overheat the inlet layer),
    shortened so that every requested time falls on a step."""
    if not length > 0 or elements < 1:
        raise ValueError("explicit_profiles: the bed length must be > 0 and elements >= 1")
    if not 0 < dt_fraction < 1:
        raise ValueError(f"explicit_profiles: dt_fraction must lie in (0, 1) (got {dt_fraction})")
    dx = length / elements
    phi_g = dx * bed.ha / bed.g_c
    if not phi_g < 1.0:
        raise ValueError(f"explicit_profiles: phi_G = {phi_g:.3g} >= 1 violates eq. 12; use more than "
                         f"{math.ceil(length * bed.ha / bed.g_c)} elements")
    phi_s = bed.ha / bed.rho_c_solid
    dt_max = dt_fraction * (1.0 - phi_g) / phi_s
    times = np.asarray(times, float)
    if (times < 0).any() or (np.diff(times) < 0).any():
        raise ValueError("explicit_profiles: times must be >= 0 and ascending")
    centres = (np.arange(elements) + 0.5) * dx
    t_s = np.full(elements, bed.t_0)
    out = np.empty((len(times), len(heights)))
    t = 0.0
    for k, t_out in enumerate(times):
        span = t_out - t
        steps = max(1, math.ceil(span / dt_max - 1e-12)) if span > 0 else 0
        dt = span / steps if steps else 0.0
        for _ in range(steps):
            t_g = np.empty(elements)
            t_g[0] = bed.t_in
            for i in range(elements - 1):  # eq. 7
                t_g[i + 1] = t_g[i] - phi_g * (t_g[i] - t_s[i])
            t_s = t_s + phi_s * dt * (t_g - t_s)  # eq. 9
        t = t_out
        out[k] = np.interp(heights, centres, t_s)
    return out
