"""Gas-particle drag and heat-exchange correlations for one particle (Taichi functions).

Drag is returned as a coefficient K [kg/s] with F_drag = K (u - v), u the interstitial gas
velocity at the particle and v the particle velocity; eps is the local voidage, d the
diameter, w = |u - v|, rho and mu the gas density and viscosity.

* GIDASPOW (Gidaspow 1994, the Ergun / Wen-Yu switch of source 1), F = V_p beta/(1-eps) (u - v):
    eps <  0.8 (Ergun):  beta = 150 (1-eps)^2 mu / (eps d^2) + 1.75 (1-eps) rho w / d
    eps >= 0.8 (Wen-Yu): beta = 0.75 C_D Re (1-eps) mu / d^2 eps^-2.65,
                         Re = eps rho w d / mu, C_D Re = 24 (1 + 0.15 Re^0.687) (Re < 1000),
                         0.44 Re above (Schiller-Naumann).
  For eps -> 1 this is the single-sphere drag C_D (pi d^2/4) rho w^2 / 2.
* DI_FELICE (Di Felice 1994): F = C_D (pi d^2/4) rho eps^2 w (u - v) eps^-chi / 2,
    C_D = (0.63 + 4.8 Re^-1/2)^2, chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2), Re as above.
* BEETSTRA (Beetstra, van der Hoef & Kuipers 2007, AIChE J. 53, 489, eq. 9, monodisperse; fitted to
  lattice-Boltzmann flows through random arrays, 0 <= phi <= 0.6, Re <= 1000): F = K (u - v) with
  K = 3 pi mu d eps F(phi, Re), phi = 1 - eps, Re as above, and
    F = 10 phi / eps^2 + eps^2 (1 + 1.5 phi^1/2)
        + 0.413 Re / (24 eps^2) (1/eps + 3 eps phi + 8.4 Re^-0.343) / (1 + 10^(3 phi) Re^-(1 + 4 phi)/2).
  F is the drag without the mean pressure gradient's share, normalized by the Stokes drag at the
  superficial slip velocity eps w (3 pi mu d eps w): at low Re a packed bed's gradient is then
  Carman-Kozeny's 180 mu phi^2 U / (eps^3 d^2) (the first term), and one sphere's drag Stokes's.
* TANG (Tang, Peters, Kuipers, Kriebitzsch & van der Hoef 2015, AIChE J. 61, 688, monodisperse; fitted to
  immersed-boundary flows through static random arrays, 0.1 <= phi <= 0.6, Re <= 1000): K as BEETSTRA's, with
    F = 10 phi / eps^2 + eps^2 (1 + 1.5 phi^1/2)
        + Re (0.11 phi (1 + phi) - 0.00456 / eps^4 + Re^-0.343 (0.169 eps + 0.0644 / eps^4)).

Heat exchange h [W/(m^2 K)] from the Nusselt number Nu = h d / k_g:
* RANZ_MARSHALL (Ranz & Marshall 1952; source 1): Nu = 2 + 0.6 Re_p^1/2 Pr^1/3, Re_p = rho w d / mu.
* GUNN (Gunn 1978): Nu = (7 - 10 eps + 5 eps^2)(1 + 0.7 Re^0.2 Pr^1/3)
                         + (1.33 - 2.4 eps + 1.2 eps^2) Re^0.7 Pr^1/3, Re = eps rho w d / mu.
"""

import math

import taichi as ti

GIDASPOW, DI_FELICE, BEETSTRA, TANG = 0, 1, 2, 3
DRAG_IDS = {"gidaspow": GIDASPOW, "di_felice": DI_FELICE, "beetstra": BEETSTRA, "tang": TANG}
RANZ_MARSHALL, GUNN = 0, 1
NUSSELT_IDS = {"ranz_marshall": RANZ_MARSHALL, "gunn": GUNN}
PI = math.pi


def make_drag(model: int, rho: float, mu: float):
    """Return drag_coefficient(eps, d, w) -> K [kg/s] for the chosen correlation."""

    @ti.func
    def stokes_part(phi, eps):
        """BEETSTRA's and TANG's low-Re part of F: 10 phi / eps^2 + eps^2 (1 + 1.5 phi^1/2)."""
        return 10.0 * phi / (eps * eps) + eps * eps * (1.0 + 1.5 * ti.sqrt(phi))

    @ti.func
    def drag_coefficient(eps, d, w):
        re = eps * rho * w * d / mu
        k = 0.0
        if ti.static(model == GIDASPOW):
            vol = PI / 6.0 * d * d * d
            beta = 0.0
            if eps < 0.8:
                beta = 150.0 * (1.0 - eps) ** 2 * mu / (eps * d * d) + 1.75 * (1.0 - eps) * rho * w / d
            else:
                cd_re = 0.44 * re
                if re < 1000.0:
                    cd_re = 24.0 * (1.0 + 0.15 * re**0.687)
                beta = 0.75 * cd_re * (1.0 - eps) * mu / (d * d) * eps**-2.65
            k = vol * beta / ti.max(1.0 - eps, 1e-12)
        elif ti.static(model == BEETSTRA):
            phi = 1.0 - eps
            a = 0.5 * (1.0 + 4.0 * phi)  # the inertial term times Re^a over Re^a, finite at Re = 0
            re_a = re**a
            inertial = 0.413 / (24.0 * eps * eps) * (re / eps + 3.0 * eps * phi * re + 8.4 * re**0.657) \
                * re_a / (re_a + 10.0 ** (3.0 * phi))
            k = 3.0 * PI * mu * d * eps * (stokes_part(phi, eps) + inertial)
        elif ti.static(model == TANG):
            phi = 1.0 - eps
            e4 = eps**4
            inertial = re * (0.11 * phi * (1.0 + phi) - 0.00456 / e4) + re**0.657 * (0.169 * eps + 0.0644 / e4)
            k = 3.0 * PI * mu * d * eps * (stokes_part(phi, eps) + inertial)
        else:
            re_s = ti.max(re, 1e-12)
            cd_w = (0.63 * ti.sqrt(w) + 4.8 * ti.sqrt(mu / (eps * rho * d))) ** 2  # C_D w, finite at w = 0
            lg = ti.log(re_s) / ti.log(10.0)
            chi = 3.7 - 0.65 * ti.exp(-0.5 * (1.5 - lg) ** 2)
            k = 0.5 * cd_w * (0.25 * PI * d * d) * rho * eps * eps * eps**-chi
        return k

    return drag_coefficient


def make_nusselt(model: int, rho: float, mu: float, prandtl: float):
    """Return nusselt(eps, d, w) for the chosen correlation."""
    pr3 = prandtl ** (1.0 / 3.0)

    @ti.func
    def nusselt(eps, d, w):
        nu = 0.0
        if ti.static(model == RANZ_MARSHALL):
            nu = 2.0 + 0.6 * ti.sqrt(rho * w * d / mu) * pr3
        else:
            re = eps * rho * w * d / mu
            nu = (7.0 - 10.0 * eps + 5.0 * eps * eps) * (1.0 + 0.7 * re**0.2 * pr3) \
                + (1.33 - 2.4 * eps + 1.2 * eps * eps) * re**0.7 * pr3
        return nu

    return nusselt
