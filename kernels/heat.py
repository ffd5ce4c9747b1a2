"""Heat conduction between particles and to walls and tubes (evaluated in the contact loop).

* Through the contact spot (Batchelor & O'Brien 1977): H = 2 k a, k the harmonic mean of
  the two solid conductivities and a the contact radius. a = sqrt(R* delta) is the
  geometric radius of the overlap; a softened Young's modulus makes contacts too large, so
  a is scaled by (E*_sim / E*_real)^(1/3) (Hertz: a ~ E*^(-1/3) at equal force; Morris et
  al. 2016) when a material gives `real_youngs_modulus`.
* Particle to wall or tube (Schluender; source 3 eq. 20), through the gas near the contact:
      alpha_WP = (4 lambda_g / d) { [1 + 2 (l + h_R)/d] ln[1 + d / (2 (l + h_R))] - 1 },
  lambda_g the gas conductivity, l the gas mean free path, h_R the roughness; a touching
  particle exchanges H = alpha_WP pi d^2 / 4 (its share of the wall at full coverage) in
  addition to the solid contact spot 2 k a.
* Particle-fluid-particle (Rong & Horio 1999, source 1; lens of Zhou, Yu & Zulli 2009):
  between neighbours, touching or not, through the gas lens where the gap
  s(r) = h + r^2 / (2 R*) (h the surface gap) is below delta_f = fluid_layer * min(r_i, r_j),
  with a minimum gap s_min (mean free path + roughness):
      H = int 2 pi lambda_g r dr / max(s, s_min)
        = 2 pi lambda_g R* [(max(s_min, s0) - s0) / s_min + ln(delta_f / max(s_min, s0))],
  s0 = max(h, 0), and 0 for h >= delta_f.
* Radiation (heat.radiation; the alpha_rad of source 3 eq. 18): a particle touching a heated
  surface exchanges grey radiation over the same share of the wall, pi d^2 / 4,
      q = C sigma pi r^2 (T_w^4 - T_i^4),  C = 1 / (1/eps_p + 1/eps_w - 1)
  (two parallel grey surfaces; Schluender's wall-to-first-layer exchange).
Coarse-grained parcels (diameter k d_g for k^3 grains; docs/design/coarse_graining.md): the
contact spot needs no change (a = k a_g, so H/d and the bed's conductivity are kept); the gas
lens between parcels is k lenses of the grains, k H(R*/k, h/k, delta_f/k); to a wall a parcel
carries the k^2 grains that cover its share of the wall: spot and Schluender term as in
`wall_conductance`, lens k^2 H(r/k, h/k, delta_f/k); radiation over pi r^2 already scales as k^2.
The heat rate into particle i is q_i = sum_j H_ij (T_j - T_i) + sum_walls H_iw (T_w - T_i);
a pair's H is computed identically from both sides, so the pair terms cancel exactly and
an isolated bed keeps its heat to rounding.
"""

import numpy as np
import taichi as ti

from .contact_laws import A_CORR, EMIS, GAP, K_EFF, LAMBDA_GAS

STEFAN_BOLTZMANN = 5.670374419e-8  # W/(m^2 K^4)


def schluender_alpha_wp(lambda_gas, d, gap):
    """alpha_WP [W/(m^2 K)] of source 3 eq. 20 (numpy; gap = mean free path + roughness)."""
    d = np.asarray(d, dtype=float)
    x = 2.0 * gap / d
    return 4.0 * lambda_gas / d * ((1.0 + x) * np.log(1.0 + 1.0 / x) - 1.0)


def pfp_conductance_np(lambda_gas, r_eff, gap, s_min, delta_f):
    """Particle-fluid-particle conductance [W/K] (numpy; the closed form in the docstring)."""
    s0 = max(gap, 0.0)
    if s0 >= delta_f:
        return 0.0
    lo = max(s_min, s0)
    return 2.0 * np.pi * lambda_gas * r_eff * ((lo - s0) / s_min + np.log(delta_f / lo))


@ti.func
def pfp_conductance(p, r_eff, gap, delta_f):
    """Particle-fluid-particle conductance [W/K] through the gas lens (see the module docstring)."""
    s_min = p[GAP]
    s0 = ti.max(gap, 0.0)
    h = 0.0
    if s0 < delta_f:
        lo = ti.max(s_min, s0)
        h = 2.0 * 3.141592653589793 * p[LAMBDA_GAS] * r_eff * ((lo - s0) / s_min + ti.log(delta_f / lo))
    return h


@ti.func
def spot_conductance(p, r_eff, delta):
    """2 k a with a = sqrt(R* delta) (E*-corrected) [W/K]."""
    return 2.0 * p[K_EFF] * p[A_CORR] * ti.sqrt(r_eff * delta)


@ti.func
def wall_spot_conductance(p, r, delta, k):
    """The solid contact spots of a parcel of k^3 grains (radius r = k r_g) on a wall: the k^2 grains
    that cover its wall area, each at the parcel's relative overlap, k^2 2 k_s a_g = k 2 k_s a [W/K]."""
    return k * spot_conductance(p, r, delta)


@ti.func
def wall_gap_conductance(p, r, k):
    """Schluender's gas-gap coefficient over a touching particle's share of the wall, alpha_WP(d/k) pi r^2
    [W/K] (the grains' diameter d/k for a parcel of k^3 grains)."""
    d = 2.0 * r / k
    x = 2.0 * p[GAP] / d
    alpha = 4.0 * p[LAMBDA_GAS] / d * ((1.0 + x) * ti.log(1.0 + 1.0 / x) - 1.0)
    return alpha * 3.141592653589793 * r * r


@ti.func
def wall_conductance(p, r, delta, k):
    """Contact spot plus Schluender's gas-gap coefficient over pi d^2 / 4 [W/K]; for a parcel of
    k^3 grains (radius r = k r_g) the k^2 grains that cover its wall area, each at the
    parcel's relative overlap: k^2 H_wall(r/k, delta/k) = k 2 k_s a + alpha_WP(d/k) pi r^2."""
    return wall_spot_conductance(p, r, delta, k) + wall_gap_conductance(p, r, k)


@ti.func
def wall_radiation(p, r, t_wall, t_particle):
    """Grey radiation from a surface to a particle touching it over pi r^2 [W] (module docstring)."""
    return p[EMIS] * STEFAN_BOLTZMANN * 3.141592653589793 * r * r * (t_wall**4 - t_particle**4)
