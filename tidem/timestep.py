"""Critical time scales of a contact law and the time step chosen from them.

* Rayleigh time (shear-wave transit of the smallest particle):
  T_R = pi r sqrt(rho/G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)).
* Contact time of the stiffest pair: linear laws t_c = pi sqrt(m*/k) (k the unloading stiffness
  k_l/e^2 for the hysteretic law); Hertz t_c = 2.868 (m*^2 / (R* E*^2 v))^(1/5) at the largest
  expected impact speed v (Johnson 1985).
* Stability limit of the explicit (Verlet) step: dt < 2 sqrt(m*/k_max), k_max the largest
  contact stiffness (for Hertz, S_n at the peak overlap of an impact at v), and for Hertz also
  dt < T_R.
The default step is `dt_fraction * min(T_R, t_c)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class TimeScales:
    """Time scales of the stiffest and lightest contact in a scene [s]."""

    rayleigh: float
    contact: float
    limit: float

    @property
    def reference(self) -> float:
        return min(self.rayleigh, self.contact)


def rayleigh_time(radius: float, density: float, youngs: float, poisson: float) -> float:
    shear = youngs / (2.0 * (1.0 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def hertz_contact_time(m_eff: float, r_eff: float, e_star: float, speed: float) -> float:
    return 2.868 * (m_eff**2 / (r_eff * e_star**2 * speed)) ** 0.2


def hertz_peak_overlap(m_eff: float, r_eff: float, e_star: float, speed: float) -> float:
    return (15.0 * m_eff * speed**2 / (16.0 * e_star * math.sqrt(r_eff))) ** 0.4


def wall_impact_overlap(law: str, d: float, density: float, youngs: float, poisson: float, speed: float) -> float:
    """Peak overlap / radius of a particle hitting a wall of its own material at `speed`:
    Hertz (m* = m, R* = R, E* = E / (2 (1 - nu^2))) or linear (delta = v sqrt(m / k), k = E d / 2)."""
    r = 0.5 * d
    m = density * math.pi / 6.0 * d**3
    if law == "hertz_mindlin":
        return hertz_peak_overlap(m, r, youngs / (2.0 * (1.0 - poisson**2)), speed) / r
    return speed * math.sqrt(m / (0.5 * youngs * d)) / r


def weight_overlap(law: str, d: float, density: float, youngs: float, poisson: float, height: float,
                   gravity: float) -> float:
    """Overlap / radius of a particle at the bottom of a bed `height` deep, carrying its share
    of the weight above (solid fraction 0.6, d^2 of bed section, shared by 3 contacts below):
    F = 0.2 rho g height d^2; Hertz delta = (3 F / (4 E* sqrt(R*)))^(2/3) for a like pair,
    linear delta = F / k, k = E d / 2."""
    force = 0.2 * density * gravity * height * d * d
    r = 0.5 * d
    if law == "hertz_mindlin":
        e_star = youngs / (2.0 * (1.0 - poisson**2))
        return (3.0 * force / (4.0 * e_star * math.sqrt(0.5 * r))) ** (2.0 / 3.0) / r
    return force / (0.5 * youngs * d) / r


def time_scales(law: str, d_min: float, density: float, youngs: float, poisson: float,
                restitution: float, speed: float) -> TimeScales:
    """Time scales for the lightest particle of a material, against a like particle or a wall."""
    r = 0.5 * d_min
    m = density * math.pi / 6.0 * d_min**3
    t_r = rayleigh_time(r, density, youngs, poisson)
    m_eff = 0.5 * m
    if law == "hertz_mindlin":
        e_star = youngs / (2.0 * (1.0 - poisson**2))
        r_eff = 0.5 * r
        t_c = hertz_contact_time(m_eff, r_eff, e_star, speed)
        s_n = 2.0 * e_star * math.sqrt(r_eff * hertz_peak_overlap(m_eff, r_eff, e_star, speed))
        limit = min(2.0 * math.sqrt(m_eff / s_n), t_r)
    else:
        k = 0.5 * youngs * d_min
        if law == "hysteretic":
            k /= max(restitution**2 - 0.001, 1e-6)
        t_c = math.pi * math.sqrt(m_eff / k)
        limit = 2.0 * math.sqrt(m_eff / k)
    return TimeScales(rayleigh=t_r, contact=t_c, limit=limit)
