"""Material-pair and material-surface parameter tables of the contact laws
(`kernels/contact_laws.py`, slot names there): effective moduli, damping from restitution,
friction and rolling values, the hysteretic law's unloading ratio, and with heat the
conduction and radiation parameters of a contact (`kernels/heat.py`).
"""

from __future__ import annotations

import math

import numpy as np

from tidem.kernels import contact_laws as cl
from tidem.scene.sizes import parcel_ratios

FLOOR = 0.001  # repulsive floor of the hysteretic law, F >= FLOOR k_l delta (source 3)


def hysteretic_stiffness_ratio(e: float) -> float:
    """k_l / k_ul that gives restitution e for the Walton-Braun law *with* its force floor.

    Without the floor e^2 = k_l/k_ul (source 3 eq. 28). The floor FLOOR k_l delta returns
    extra energy; integrating loading (k_l delta up to delta_m) and unloading
    (max(k_ul (delta - delta_0), FLOOR k_l delta)) gives, with a = k_l/k_ul,
        e^2 = a + FLOOR (1 - a)^2 / (1 - FLOOR a),
    solved here by bisection so that the measured restitution is exactly e.
    """
    if e >= 1.0:
        return 1.0
    target = e * e
    lo, hi = 0.0, 1.0
    for _ in range(100):
        a = 0.5 * (lo + hi)
        if a + FLOOR * (1 - a) ** 2 / (1 - FLOOR * a) < target:
            lo = a
        else:
            hi = a
    return max(0.5 * (lo + hi), 1e-12)


def kinetic_theory_restitution(e: float, k: float) -> float:
    """The restitution of a collision between parcels of k^3 grains that dissipates, per volume and at
    the same granular temperature, what the grains' collisions of restitution e dissipate.

    Kinetic theory's collisional dissipation rate (Lun, Savage, Jeffrey & Chepurniy 1984),
    Gamma = 12 (1 - e^2) g0 eps_s^2 rho_s theta^(3/2) / (d sqrt(pi)), falls as 1/d at a given solids
    fraction and theta; matching it for parcels of diameter k d gives
        1 - e_p^2 = k (1 - e^2),   e_p = sqrt(1 - k (1 - e^2))
    (the coarse-grained particles' restitution of Lu et al.'s EMMS-DPM; PhasicFlow's "LU" dissipation
    model). It exists while k (1 - e^2) < 1 (`tidem.scene.checks.coarse_grain_checks` refuses beyond)."""
    return math.sqrt(1.0 - k * (1.0 - e * e))


def pair_vector(a, b, wall_friction=None, heat=None, coarse_grain: float = 1.0) -> np.ndarray:
    """Parameters of a contact between materials a and b (indices in `contact_laws`).

    E* and G* combine both bodies; restitution, friction and rolling values are the mean of
    the two materials, except that a wall's or tube's own `friction` replaces both frictions.
    `coarse_grain` k > 1 (parcels with `contact.parcel_restitution = "kinetic_theory"`) replaces the
    mean restitution e by `kinetic_theory_restitution(e, k)`.
    With heat: harmonic-mean conductivity (a wall without one takes the particle's), and the
    contact-radius factor (E*_sim / E*_real)^(1/3) for softened moduli (Morris et al. 2016).
    """
    p = np.zeros(cl.N_PARAMS)
    e_star = 1.0 / ((1 - a.poisson_ratio**2) / a.youngs_modulus + (1 - b.poisson_ratio**2) / b.youngs_modulus)
    g_a = a.youngs_modulus / (2 * (1 + a.poisson_ratio))
    g_b = b.youngs_modulus / (2 * (1 + b.poisson_ratio))
    g_star = 1.0 / ((2 - a.poisson_ratio) / g_a + (2 - b.poisson_ratio) / g_b)
    e = 0.5 * (a.restitution + b.restitution)
    if coarse_grain != 1.0:
        e = kinetic_theory_restitution(e, coarse_grain)
    ln_e = math.log(e) if e < 1.0 else 0.0
    nu = 0.5 * (a.poisson_ratio + b.poisson_ratio)
    dyn_a = a.friction if a.dynamic_friction is None else a.dynamic_friction
    dyn_b = b.friction if b.dynamic_friction is None else b.dynamic_friction
    mu_s = 0.5 * (a.friction + b.friction) if wall_friction is None else wall_friction
    mu_d = 0.5 * (dyn_a + dyn_b) if wall_friction is None else wall_friction
    p[cl.ESTAR] = e_star
    p[cl.GSTAR] = g_star
    p[cl.GAMMA] = -ln_e / math.sqrt(ln_e**2 + math.pi**2)
    p[cl.KAPPA] = 2 * (1 - nu) / (2 - nu)
    p[cl.MU_S] = mu_s
    p[cl.MU_D] = mu_d
    p[cl.MU_R] = 0.5 * (a.rolling_friction + b.rolling_friction)
    p[cl.ETA_R] = 0.5 * (a.rolling_damping + b.rolling_damping)
    p[cl.UNLOAD_RATIO] = 1.0 / hysteretic_stiffness_ratio(e)
    p[cl.E_I] = a.youngs_modulus
    p[cl.E_J] = b.youngs_modulus
    p[cl.ROOT_2E], p[cl.ROOT_8G], p[cl.ROOT_KAPPA] = math.sqrt(2 * e_star), math.sqrt(8 * g_star), math.sqrt(p[cl.KAPPA])
    if heat is not None:
        k_a = a.conductivity or 0.0
        k_b = b.conductivity or k_a
        p[cl.K_EFF] = 2 * k_a * k_b / (k_a + k_b) if k_a + k_b > 0 else 0.0
        real_a = a.real_youngs_modulus or a.youngs_modulus
        real_b = b.real_youngs_modulus or b.youngs_modulus
        e_real = 1.0 / ((1 - a.poisson_ratio**2) / real_a + (1 - b.poisson_ratio**2) / real_b)
        p[cl.A_CORR] = (e_star / e_real) ** (1.0 / 3.0)
        p[cl.LAMBDA_GAS] = heat.gas_conductivity
        p[cl.GAP] = heat.gas_mean_free_path + heat.roughness
        if heat.radiation and a.emissivity and b.emissivity:  # two grey parallel surfaces
            p[cl.EMIS] = 1.0 / (1.0 / a.emissivity + 1.0 / b.emissivity - 1.0)
    return p


def hysteretic_floor_errors(scene) -> list[str]:
    """Materials whose restitution, or whose parcels' kinetic-theory restitution, the hysteretic law cannot
    give with its force floor."""
    if scene.contact.model != "hysteretic":
        return []
    mats = scene.materials
    least = math.sqrt(FLOOR * 1.01)
    low = [n for n, m in mats.items() if m.restitution <= least]
    errors = [f"materials.{n}.restitution: {mats[n].restitution} is below what the hysteretic law "
              f"can give with its force floor ({least:.3f}); raise it or use contact.model = 'linear'" for n in low]
    for n, k in parcel_ratios(scene).items():
        e = mats[n].restitution
        if n not in low and k * (1 - e * e) < 1 and kinetic_theory_restitution(e, k) <= least:
            errors.append(f"particles[*].coarse_grain: parcels of k = {k:g} of materials.{n} would collide with the "
                          f"kinetic-theory restitution {kinetic_theory_restitution(e, k):.3g}, below what the hysteretic "
                          f"law can give with its force floor ({least:.3f}); lower coarse_grain, raise the restitution "
                          "or use contact.parcel_restitution = 'grains'")
    return errors


def parameter_tables(scene, mat_names: list[str], surfaces: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """The material-pair table [P, P, N_PARAMS] and the material-surface table
    [P, max(surfaces, 1), N_PARAMS] (surfaces: planes, then tubes). With
    `contact.parcel_restitution = "kinetic_theory"` a pair of materials whose groups are parcels takes
    the restitution of `kinetic_theory_restitution` at the mean of the two materials' k (one k per
    material, `tidem.scene.checks.coarse_grain_checks`); walls and tubes keep the materials' own."""
    mats = scene.materials
    P = len(mat_names)
    k = parcel_ratios(scene)
    pair = np.zeros((P, P, cl.N_PARAMS))
    for a, na in enumerate(mat_names):
        for b, nb in enumerate(mat_names):
            k_pair = 0.5 * (k[na] + k[nb]) if na in k and nb in k else 1.0  # a pair of particle materials
            pair[a, b] = pair_vector(mats[na], mats[nb], heat=scene.heat, coarse_grain=k_pair)
    surf = np.zeros((P, max(len(surfaces), 1), cl.N_PARAMS))
    for a, na in enumerate(mat_names):
        for s, sd in enumerate(surfaces):
            surf[a, s] = pair_vector(mats[na], mats[sd["material"]], sd["friction"], scene.heat)
            surf[a, s, cl.E_J] = 0.0  # a wall is a body of infinite size for the linear laws
    return pair, surf
