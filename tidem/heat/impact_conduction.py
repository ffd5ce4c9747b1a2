"""Heat passed between two spheres in one elastic Hertzian impact: two analytic estimates.

Hertz impact at the approach speed v (Johnson 1985, section 11.4), m* and R* the effective
mass and radius, E* the contact modulus:

    delta_max = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5),   a_max = sqrt(R* delta_max).

Energy conservation gives v(delta) = v sqrt(1 - (delta/delta_max)^(5/2)); integrating
dt = d(delta)/v(delta) over loading and unloading (substitute u = (delta/delta_max)^(5/2),
which turns both integrals into Beta functions):

    t_c            = (4/5) B(2/5, 1/2) delta_max / v = 2.943 delta_max / v,
    int_0^t_c a dt = (4/5) B(3/5, 1/2) a_max delta_max / v = C_a a_max t_c,
    C_a            = B(3/5, 1/2) / B(2/5, 1/2) = 0.7541.

1. Quasi-static: tidem's own contact-spot conductance H = 2 k a(t) (Batchelor & O'Brien
   1977), integrated over the Hertz history:
       Q_qs = 2 k C_a a_max t_c (T_1 - T_2),
   k the harmonic mean of the two conductivities. A simulated impact must give this.
2. Transient: Sun & Chen (1988, Int. J. Heat Mass Transfer 31, 969-975), as used in DEM by
   Zhou, Yu & Horio (2008, Chem. Eng. J. 139, 510-516) and Zhou, Yu & Zulli (2010):
       Q_SC = 0.87 (T_1 - T_2) pi a_max^2 sqrt(t_c) / ((rho_1 c_1 k_1)^(-1/2) + (rho_2 c_2 k_2)^(-1/2)),
   the heat that penetrates both half-spaces through the growing and shrinking spot in the
   short contact; valid for small Fourier numbers Fo = k t_c / (rho c a_max^2) << 1. The
   quasi-static conductance is the long-time limit of that problem, so for a short impact
   (small Fo) it passes less heat than the transient estimate: Q_qs/Q_SC ~ sqrt(Fo).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


def _beta(a: float, b: float) -> float:
    return math.gamma(a) * math.gamma(b) / math.gamma(a + b)


CONTACT_TIME_FACTOR = 0.8 * _beta(0.4, 0.5)  # t_c = 2.943 delta_max / v
SPOT_INTEGRAL_FACTOR = _beta(0.6, 0.5) / _beta(0.4, 0.5)  # C_a: int a dt = C_a a_max t_c
SUN_CHEN_FACTOR = 0.87


@dataclass(frozen=True)
class HertzImpact:
    """Peak overlap [m], peak contact radius [m] and contact time [s] of an elastic impact."""

    delta_max: float
    a_max: float
    contact_time: float


def hertz_impact(m_eff: float, r_eff: float, e_star: float, speed: float) -> HertzImpact:
    """Peak overlap, peak contact radius and duration of an elastic Hertz impact at `speed`."""
    if speed <= 0.0:
        raise ValueError(f"the approach speed must be > 0 (got {speed})")
    delta = (15.0 * m_eff * speed**2 / (16.0 * e_star * math.sqrt(r_eff))) ** 0.4
    return HertzImpact(delta_max=delta, a_max=math.sqrt(r_eff * delta),
                       contact_time=CONTACT_TIME_FACTOR * delta / speed)


def quasi_static_impact_heat(conductivity: float, impact: HertzImpact, delta_t: float,
                             radius_scale: float = 1.0) -> float:
    """Q_qs = 2 k C_a a_max t_c (T_1 - T_2) [J]; `radius_scale` multiplies the contact radius
    (tidem's (E*_sim/E*_real)^(1/3) for a softened modulus)."""
    return 2.0 * conductivity * SPOT_INTEGRAL_FACTOR * radius_scale * impact.a_max * impact.contact_time * delta_t


def sun_chen_impact_heat(impact: HertzImpact, delta_t: float, effusivity_1: float, effusivity_2: float) -> float:
    """Q_SC = 0.87 dT pi a_max^2 sqrt(t_c) / (e_1^-1 + e_2^-1) [J], e = sqrt(rho c k) the
    thermal effusivity of each sphere [W s^1/2/(m^2 K)]."""
    return (SUN_CHEN_FACTOR * delta_t * math.pi * impact.a_max**2 * math.sqrt(impact.contact_time)
            / (1.0 / effusivity_1 + 1.0 / effusivity_2))
