"""Published correlations for the heat transfer between a bubbling fluidized bed and an immersed
surface, and for the gas convection at the wall of a packed bed: the references the tube scenes'
heat-transfer coefficients are compared with (docs/validation.md, `benchmarks/tube_heat/`).

SI units; g = 9.81 m/s^2 unless given.

* Minimum fluidization velocity, Wen & Yu (1966):
      Re_mf = sqrt(33.7^2 + 0.0408 Ar) - 33.7,   Ar = d^3 rho_g (rho_p - rho_g) g / mu^2.
* Bed-to-surface coefficient of a bubbling bed, Molerus, Burschka & Dietz (1995), Chem. Eng. Sci.
  50, 879-885 (also in Molerus & Wirth, Heat Transfer in Fluidized Beds, 1997), with the laminar
  length l_L = [mu / (sqrt(g) (rho_p - rho_g))]^(2/3) and the excess velocity made dimensionless
  as u* = (U - U_mf) [rho_p c_p / (k_g g)]^(1/3):
      alpha l_L / k_g = Nu_pc + Nu_gc,
      Nu_pc = 0.125 (1 - eps_mf) [1 + 33.3 (U_mf / (U - U_mf))^(1/3) / u*]^-1
              / (1 + k_g / (2 c_p mu) [1 + 0.28 (1 - eps_mf)^2 (rho_g / (rho_p - rho_g))^(1/2)
                                           u*^2 U_mf / (U - U_mf)]),
      Nu_gc = 0.165 Pr^(1/3) (rho_g / (rho_p - rho_g))^(1/3) / (1 + 0.05 U_mf / (U - U_mf)),
  the particle-convective and the gas-convective part (c_p the particles' heat capacity).
* Maximum bed-to-surface coefficient, Zabrodsky, Antonishin & Parnas (1976), Can. J. Chem.
  Eng. 54, 52-58: alpha_max = 35.8 rho_p^0.2 k_g^0.6 d^-0.36 (at the optimum gas velocity).
* A bare cylinder in cross flow, Churchill & Bernstein (1977):
      Nu_D = 0.3 + 0.62 Re^1/2 Pr^1/3 / [1 + (0.4/Pr)^2/3]^1/4 [1 + (Re/282000)^5/8]^4/5.
* Gas convection at the wall of a packed bed, the flow term of Martin & Nilles (1993),
  Chem.-Ing.-Tech. 65, 1468 (VDI Heat Atlas): Nu_w = alpha_w d / k_g = 0.19 Re_0^0.75 Pr^(1/3),
  Re_0 = rho_g U_0 d / mu with U_0 the superficial velocity (the stagnant part of their Nu_w,
  conduction through the bed, is what the particles' contact, gap and lens conduction carry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

G = 9.81


def wen_yu_minimum_fluidization(d: float, rho_p: float, rho_g: float, mu: float, g: float = G) -> float:
    """Minimum fluidization velocity [m/s] of spheres of diameter d (Wen & Yu 1966)."""
    ar = d**3 * rho_g * (rho_p - rho_g) * g / mu**2
    re_mf = math.sqrt(33.7**2 + 0.0408 * ar) - 33.7
    return re_mf * mu / (rho_g * d)


@dataclass(frozen=True)
class BedToSurface:
    """Molerus-Burschka-Dietz coefficient [W/(m^2 K)] split into its two parts."""

    particle_convective: float
    gas_convective: float
    laminar_length: float

    @property
    def total(self) -> float:
        return self.particle_convective + self.gas_convective


def molerus(U: float, U_mf: float, eps_mf: float, rho_p: float, c_p: float, rho_g: float, mu: float,
            k_g: float, c_g: float, g: float = G) -> BedToSurface:
    """Bed-to-surface heat-transfer coefficient of a bubbling bed at superficial velocity U > U_mf
    (module docstring; Molerus, Burschka & Dietz 1995)."""
    if not U > U_mf:
        raise ValueError(f"the correlation holds for a bubbling bed: U = {U} m/s must exceed U_mf = {U_mf} m/s")
    excess = U - U_mf
    l_lam = (mu / (math.sqrt(g) * (rho_p - rho_g))) ** (2.0 / 3.0)
    u_star = excess * (rho_p * c_p / (k_g * g)) ** (1.0 / 3.0)
    density_ratio = rho_g / (rho_p - rho_g)
    solid = 1.0 - eps_mf
    renewal = 1.0 / (1.0 + 33.3 * (U_mf / excess) ** (1.0 / 3.0) / u_star)
    gap = 1.0 + k_g / (2.0 * c_p * mu) * (1.0 + 0.28 * solid**2 * math.sqrt(density_ratio) * u_star**2 * U_mf / excess)
    nu_pc = 0.125 * solid * renewal / gap
    nu_gc = 0.165 * (c_g * mu / k_g) ** (1.0 / 3.0) * density_ratio ** (1.0 / 3.0) / (1.0 + 0.05 * U_mf / excess)
    return BedToSurface(nu_pc * k_g / l_lam, nu_gc * k_g / l_lam, l_lam)


def zabrodsky_maximum(k_g: float, rho_p: float, d: float) -> float:
    """Largest bed-to-surface coefficient [W/(m^2 K)] over gas velocity (Zabrodsky et al. 1976)."""
    return 35.8 * rho_p**0.2 * k_g**0.6 * d**-0.36


def packed_bed_wall_convection(U0: float, d: float, rho_g: float, mu: float, k_g: float, c_g: float) -> float:
    """Gas-convective wall coefficient [W/(m^2 K)] of a packed bed of grains of diameter d at
    superficial velocity U0 (Martin & Nilles 1993, flow term)."""
    re0 = rho_g * abs(U0) * d / mu
    return 0.19 * re0**0.75 * (c_g * mu / k_g) ** (1.0 / 3.0) * k_g / d


def cylinder_cross_flow(re: float, pr: float) -> float:
    """Nusselt number h D / k of a cylinder in cross flow at Reynolds number re, a float or an array
    (Churchill & Bernstein 1977)."""
    return 0.3 + 0.62 * re**0.5 * pr ** (1.0 / 3.0) / (1.0 + (0.4 / pr) ** (2.0 / 3.0)) ** 0.25 \
        * (1.0 + (re / 282000.0) ** 0.625) ** 0.8
