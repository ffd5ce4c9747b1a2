"""Schluender's packet model: heat transfer from a tube wall to a moving packed bed.

The bed slides along the wall and stays on it for a residence time t; then fresh bulk
replaces it (the "packet" theory of Mickley & Fairbanks 1955, with the contact resistance
of Baskakov and Schluender in series; source 3, section 2.2 and Figure 4):

    1/alpha = 1/alpha_c + 1/alpha_S0

* contact coefficient at the wall (source 3 eq. 18-20), phi = 0.8 the share of the wall
  covered by touching particles (source 3 Table 2):
      alpha_c = phi alpha_WP,
      alpha_WP = (4 lambda_g/d) {[1 + 2(l + h_R)/d] ln[1 + d/(2(l + h_R))] - 1};
  gas conduction to the second particle layer and radiation, the other terms of eq. 18,
  are left out, as tidem's own wall model leaves them out;
* penetration into the bulk, a homogeneous half-space heated from its surface, averaged
  over the residence time (Mickley & Fairbanks; alpha ~ t^-1/2):
      alpha_S0 = (2/sqrt(pi)) sqrt(lambda_bed rho_bed c / t),  rho_bed = (1 - psi) rho_s;
* residence time on a tube: a particle slides from the top to the bottom of the tube, half
  the circumference, at the bed speed u (the outlet speed u_ref):  t = pi D / (2 u);
* bed conductivity lambda_bed of a packed bed of spheres in a stagnant gas after Zehner &
  Schluender (1970), without radiation and contact flattening (the conductivity the
  continuum model of source 3 uses):
      lambda_bed/lambda_g = 1 - sqrt(1 - psi) + sqrt(1 - psi) k_c,
      k_c = (2/N) [B (kappa - 1)/(N^2 kappa) ln(kappa/B) - (B + 1)/2 - (B - 1)/N],
      N = 1 - B/kappa,  B = 1.25 ((1 - psi)/psi)^(10/9),  kappa = lambda_s/lambda_g,
  psi the bed porosity.

The series form of two time-averaged coefficients is Schluender's approximation; the exact
average of a half-space behind a constant contact coefficient differs from it by a few per
cent where alpha_c and alpha_S0 are alike.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from tidem.kernels.heat import schluender_alpha_wp

COVERED_SHARE = 0.8  # phi, share of the wall covered by touching particles (source 3 Table 2)
BED_POROSITY = 0.4  # psi of a random packing of spheres (solid fraction 0.6)


def zehner_schluender_conductivity(lambda_solid: float, lambda_gas: float, porosity: float) -> float:
    """Effective conductivity [W/(m K)] of a packed bed of spheres in a stagnant gas (Zehner &
    Schluender 1970, no radiation, no flattening)."""
    if not 0.0 < porosity < 1.0:
        raise ValueError(f"porosity must lie between 0 and 1 (got {porosity})")
    kappa = lambda_solid / lambda_gas
    b = 1.25 * ((1.0 - porosity) / porosity) ** (10.0 / 9.0)
    n = 1.0 - b / kappa
    k_c = 2.0 / n * (b * (kappa - 1.0) / (n * n * kappa) * math.log(kappa / b) - (b + 1.0) / 2.0 - (b - 1.0) / n)
    root = math.sqrt(1.0 - porosity)
    return lambda_gas * (1.0 - root + root * k_c)


def tube_residence_time(tube_diameter: float, speed: float) -> float:
    """t = pi D / (2 u) [s]: half the tube circumference at the bed speed u."""
    if speed <= 0.0:
        raise ValueError(f"the bed speed must be > 0 (got {speed})")
    return math.pi * tube_diameter / (2.0 * speed)


def penetration_alpha(lambda_bed: float, rho_bed: float, heat_capacity: float, residence_time: float) -> float:
    """alpha_S0 = (2/sqrt(pi)) sqrt(lambda rho c / t) [W/(m^2 K)], time-averaged over t."""
    return 2.0 / math.sqrt(math.pi) * math.sqrt(lambda_bed * rho_bed * heat_capacity / residence_time)


@dataclass(frozen=True)
class PacketAlpha:
    """The packet model's coefficients for one tube."""

    alpha_W_m2K: float  # alpha, contact and penetration in series
    contact_alpha_W_m2K: float  # alpha_c = phi alpha_WP
    penetration_alpha_W_m2K: float  # alpha_S0
    bed_conductivity_W_mK: float  # lambda_bed (Zehner-Schluender)
    residence_time_s: float  # t = pi D / (2 u)

    def as_dict(self) -> dict:
        return asdict(self)


def packet_alpha(*, tube_diameter: float, speed: float, particle_diameter: float, solid_density: float,
                 solid_conductivity: float, heat_capacity: float, gas_conductivity: float, gap: float,
                 porosity: float = BED_POROSITY, covered_share: float = COVERED_SHARE) -> PacketAlpha:
    """Mean heat-transfer coefficient of a tube in a moving bed (module docstring); `gap` is the
    gas mean free path plus the surface roughness, l + h_R [m]."""
    t = tube_residence_time(tube_diameter, speed)
    lambda_bed = zehner_schluender_conductivity(solid_conductivity, gas_conductivity, porosity)
    a_c = covered_share * float(schluender_alpha_wp(gas_conductivity, particle_diameter, gap))
    a_s = penetration_alpha(lambda_bed, (1.0 - porosity) * solid_density, heat_capacity, t)
    return PacketAlpha(alpha_W_m2K=1.0 / (1.0 / a_c + 1.0 / a_s), contact_alpha_W_m2K=a_c,
                       penetration_alpha_W_m2K=a_s, bed_conductivity_W_mK=lambda_bed, residence_time_s=t)
