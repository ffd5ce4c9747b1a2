"""Critical time scales of a contact law and the time step chosen from them.

* Rayleigh time (shear-wave transit of the smallest particle):
  T_R = pi r sqrt(rho/G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)).
* Contact time of the stiffest pair: linear laws t_c = pi sqrt(m*/k) (k the unloading stiffness
  k_l/e^2 for the hysteretic law); Hertz t_c = 2.868 (m*^2 / (R* E*^2 v))^(1/5) at the largest
  expected impact speed v (Johnson 1985).
* Stability limit of the explicit (Verlet) step: dt < 2 sqrt(m*/k_max), k_max the largest
  contact stiffness (for Hertz, S_n at the peak overlap of an impact at v), and for Hertz also
  dt < T_R.
The default step is `dt_fraction * min(T_R, t_c)` (`contact_time_step`, which also refuses
contacts too soft for the bed's weight or an impact, `too_soft`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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


def too_soft(scene, law, mats, mat_names, material, radius, x0, active, speed) -> list[str]:
    """Contacts that would overlap more than numerics.max_overlap before the first step is
    taken: under the weight of the initial bed (its height from the particles placed at the
    start), and, when the scene states numerics.impact_velocity, in a wall impact at it. Each
    message names the Young's modulus that would do (overlap ~ E^-2/3 under a load and
    E^-2/5 in an impact for Hertz, E^-1 and E^-1/2 for the linear laws)."""
    num = scene.numerics
    g = abs(scene.domain.gravity[2])
    out = []
    for mi, mname in enumerate(mat_names):
        sel = material == mi
        if not sel.any():
            continue
        m = mats[mname]
        d = 2.0 * float(radius[sel].max())
        placed = x0[sel & active]
        height = float(np.ptp(placed[:, 2])) + d if len(placed) else 0.0
        hertz = law == "hertz_mindlin"
        cases = [("the weight of the initial bed", weight_overlap(law, d, m.density, m.youngs_modulus, m.poisson_ratio,
                                                                   height, g), 1.5 if hertz else 1.0)]
        if num.impact_velocity is not None:
            cases.append((f"an impact at numerics.impact_velocity = {speed:g} m/s",
                          wall_impact_overlap(law, d, m.density, m.youngs_modulus, m.poisson_ratio, speed),
                          2.5 if hertz else 2.0))
        for what, ratio, power in cases:
            if ratio > num.max_overlap:
                need = m.youngs_modulus * (ratio / num.max_overlap) ** power
                out.append(f"materials.{mname}.youngs_modulus: {what} overlaps particles by {100 * ratio:.1f} % of "
                           f"their radius (limit numerics.max_overlap = {100 * num.max_overlap:.0f} %); use "
                           f"youngs_modulus >= {need:.3g}, or a larger max_overlap")
    return out


def impact_speed(scene, v0: np.ndarray) -> float:
    """The impact speed the contacts are sized for [m/s]: numerics.impact_velocity, else the larger of
    twice the fastest start velocity and the free fall over the domain's height (at least 1 cm/s)."""
    dom, num = scene.domain, scene.numerics
    if num.impact_velocity is not None:
        return num.impact_velocity
    vmax = float(np.linalg.norm(v0, axis=1).max()) if len(v0) else 0.0
    height = dom.max[2] - dom.min[2]
    return max(2.0 * vmax, math.sqrt(2.0 * abs(dom.gravity[2]) * height), 0.01)


def contact_time_step(scene, material: np.ndarray, radius: np.ndarray, x0: np.ndarray, v0: np.ndarray,
                      active: np.ndarray, surfaces: list[dict], all_fixed: bool) -> tuple[float, TimeScales, list[str]]:
    """The time step from the stiffest, lightest contact (`numerics.dt`, else dt_fraction times
    the reference time), its time scales, and the refusals: contacts too soft for the bed
    (`too_soft`) or a step above the stability limit. With every particle fixed nothing moves,
    so no contact can become unstable and the contact limits do not bind the step."""
    mats, num = scene.materials, scene.numerics
    law = scene.contact.model
    mat_names = list(mats)
    speed = impact_speed(scene, v0)
    scales = None
    for mi, mname in enumerate(mat_names):
        sel = material == mi
        if not sel.any():
            continue
        m = mats[mname]
        e_min = min(m.restitution, *[mats[s["material"]].restitution for s in surfaces]) if surfaces else m.restitution
        ts = time_scales(law, 2.0 * radius[sel].min(), m.density, m.youngs_modulus, m.poisson_ratio, e_min, speed)
        if scales is None or ts.limit < scales.limit:
            scales = ts
    contacts = law != "none"
    if contacts and not all_fixed:
        soft = too_soft(scene, law, mats, mat_names, material, radius, x0, active, speed)
        if soft:
            return 0.0, scales, soft
    if num.dt is not None:
        dt = num.dt
        if dt > scales.limit and not num.force_dt and contacts and not all_fixed:
            return dt, scales, [
                f"numerics.dt: {dt:g} s is above the stability limit {scales.limit:.3g} s of the stiffest contact "
                f"(Rayleigh time {scales.rayleigh:.3g} s, contact time {scales.contact:.3g} s); use dt <= {scales.limit:.3g}, "
                "leave dt out to get dt_fraction * min(Rayleigh, contact time), or set numerics.force_dt = true"]
    else:
        dt = num.dt_fraction * scales.reference
        if dt > scales.limit and not num.force_dt and not all_fixed:
            return dt, scales, [
                f"numerics.dt_fraction: {num.dt_fraction} gives dt = {dt:.3g} s, above the stability limit "
                f"{scales.limit:.3g} s; use dt_fraction <= {scales.limit / scales.reference:.2f} or set numerics.force_dt = true"]
    return dt, scales, []
