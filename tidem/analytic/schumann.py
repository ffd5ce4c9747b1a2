"""Schumann's solution for a packed bed heated by a gas in plug flow.

Schumann, T. E. W. (1929), "Heat transfer: a liquid flowing through a porous prism",
J. Franklin Inst. 208, 405-416. Gas and solid energy balances (no axial conduction, constant
properties, volumetric heat-transfer coefficient ha):
    eps rho_g c_g (dT_g/dt + v dT_g/dz) = -ha (T_g - T_s),
    (1 - eps) rho_s c_s dT_s/dt = ha (T_g - T_s),
with T_s = T_0 at t = 0 and T_g = T_in at z = 0. In the dimensionless distance
xi = ha z / (G c_g) and time eta = ha (t - z/v) / ((1 - eps) rho_s c_s) (see `packed_bed`)
the solution is, with theta = (T - T_0) / (T_in - T_0),
    theta_s(xi, eta) = exp(-xi) int_0^eta exp(-tau) I_0(2 sqrt(xi tau)) dtau = 1 - J(eta, xi),
    theta_g(xi, eta) = theta_s + exp(-xi - eta) I_0(2 sqrt(xi eta))        =     J(xi, eta),
J the J-function of the regenerator literature. Expanding I_0 in its power series and
integrating term by term gives Schumann's double series, evaluated here:
    theta_s = sum_k p_k(xi) Q_k(eta),   theta_g = sum_k p_k(xi) Q_{k-1}(eta),
    p_k(x) = exp(-x) x^k / k!  (Poisson weights),  Q_k(y) = 1 - sum_{m<=k} p_m(y),
all terms positive and bounded by 1, so the sum is accurate to rounding for any xi, eta
(terms are taken up to k = xi + eta + 12 sqrt(xi + eta) + 40, beyond which they are below 1e-16).
"""

from __future__ import annotations

import math

import numpy as np

from tidem.analytic.packed_bed import PackedBed


def _poisson_weights(x: float, kmax: int) -> np.ndarray:
    """p_k(x) for k = 0..kmax, from logarithms (no overflow for large x)."""
    k = np.arange(kmax + 1)
    if x <= 0.0:
        return (k == 0).astype(float)
    log_fact = np.concatenate(([0.0], np.cumsum(np.log(k[1:]))))
    return np.exp(k * math.log(x) - x - log_fact)


def _theta(xi: float, eta: float, gas: bool) -> float:
    if eta <= 0.0:
        return 0.0
    kmax = int(xi + eta + 12.0 * math.sqrt(xi + eta) + 40)
    p = _poisson_weights(xi, kmax)
    q = 1.0 - np.cumsum(_poisson_weights(eta, kmax))  # Q_k(eta)
    q = np.clip(q, 0.0, 1.0)
    if gas:
        q = np.concatenate(([1.0], q[:-1]))  # Q_{k-1}, Q_{-1} = 1
    return float(np.dot(p, q))


def schumann_theta(xi, eta, gas: bool = False) -> np.ndarray:
    """Dimensionless solid (or, with gas=True, gas) temperature theta at xi >= 0, eta (zero for eta <= 0)."""
    xi, eta = np.broadcast_arrays(np.asarray(xi, float), np.asarray(eta, float))
    if (xi < 0).any():
        raise ValueError("schumann_theta: the distance xi must be >= 0")
    out = np.array([_theta(a, b, gas) for a, b in zip(xi.ravel(), eta.ravel())])
    return out.reshape(xi.shape)


def solid_temperature(bed: PackedBed, z, t) -> np.ndarray:
    """Solid temperature [K] at heights z [m] above the gas inlet and times t [s]."""
    z, t = np.broadcast_arrays(np.asarray(z, float), np.asarray(t, float))
    theta = schumann_theta(bed.distance(z), bed.time(z, t))
    return bed.t_0 + (bed.t_in - bed.t_0) * theta


def gas_temperature(bed: PackedBed, z, t) -> np.ndarray:
    """Gas temperature [K] at heights z [m] and times t [s] (T_0 ahead of the gas front)."""
    z, t = np.broadcast_arrays(np.asarray(z, float), np.asarray(t, float))
    theta = schumann_theta(bed.distance(z), bed.time(z, t), gas=True)
    return bed.t_0 + (bed.t_in - bed.t_0) * theta
