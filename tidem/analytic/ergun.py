"""Ergun's packed-bed pressure gradient, and a whole bed's pressure drop integrated over the bed's own
voidage profile (the reference of the settled-bed check: `benchmarks/whole_bed_ergun.py`,
`tests/kernels/test_gas_voidage.py`), in a column of constant or of varying cross-section (a tapered bed
between mesh walls: `tests/gas/test_mesh.py`, `benchmarks/mesh_scenes/tapered_ergun.py`)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np


def ergun_gradient(eps, u: float, d: float, mu: float, rho: float):
    """Ergun (1952) pressure gradient [Pa/m] of a packed bed of voidage eps (scalar or array) at superficial
    velocity u [m/s], grain diameter d [m], gas viscosity mu [Pa s] and density rho [kg/m^3]:
    150 (1 - eps)^2 mu u / (eps^3 d^2) + 1.75 (1 - eps) rho u^2 / (eps^3 d)."""
    eps = np.asarray(eps, dtype=float)
    return 150 * (1 - eps) ** 2 * mu * u / (eps**3 * d * d) + 1.75 * (1 - eps) * rho * u * u / (eps**3 * d)


Area = float | Callable[[np.ndarray], np.ndarray]


def slice_voidage(z: np.ndarray, d: float, area: Area, height: float, dz: float, sub: int = 50) -> np.ndarray:
    """Voidage of horizontal slices dz high from 0 to `height` of a column of cross-section `area` [m^2] (a
    number, or a function of the height giving the open cross-section there) holding spheres of diameter d
    centred at heights z: each sphere's cross-section pi (r^2 - (s - z)^2) summed at `sub` points a slice,
    over the cross-section there, and averaged over the slice (exact in the limit of many points)."""
    nb = int(round(height / dz))
    s = (np.arange(nb * sub) + 0.5) * dz / sub
    solid = np.zeros_like(s)
    r2 = (d / 2) ** 2
    for zi in np.asarray(z, dtype=float):
        lo, hi = np.searchsorted(s, (zi - d / 2, zi + d / 2))
        solid[lo:hi] += math.pi * np.clip(r2 - (s[lo:hi] - zi) ** 2, 0.0, None)
    return (1.0 - solid / (area(s) if callable(area) else area)).reshape(nb, sub).mean(axis=1)


def whole_bed_ergun(z: np.ndarray, d: float, area: float, height: float, u: float, mu: float, rho: float,
                    dz: float) -> float:
    """Pressure drop [Pa] of the bed of spheres at heights z: Ergun's gradient at each slice's voidage
    (`slice_voidage`, slices dz high) times dz, summed over the slices that hold grains."""
    eps = slice_voidage(z, d, area, height, dz)
    bed = eps < 0.999
    return float(ergun_gradient(eps[bed], u, d, mu, rho).sum() * dz)


def tapered_bed_ergun(z: np.ndarray, d: float, area: Callable[[np.ndarray], np.ndarray], height: float, flow: float,
                      mu: float, rho: float, dz: float) -> float:
    """Pressure drop [Pa] of the bed of spheres at heights z in a column whose open cross-section at height s is
    area(s) [m^2] (a cone, a wedge), with the volume flow `flow` [m^3/s] through it: the one-dimensional
    model of a tapered packed bed, Ergun's gradient at each slice's voidage (`slice_voidage`, slices dz high)
    and superficial velocity flow / area at the slice's middle, times dz, summed over the slices that hold
    grains. It leaves out the flow across the taper, small where the walls lean little from the axis."""
    eps = slice_voidage(z, d, area, height, dz)
    u = flow / area((np.arange(len(eps)) + 0.5) * dz)
    bed = eps < 0.999
    return float(ergun_gradient(eps[bed], u[bed], d, mu, rho).sum() * dz)
