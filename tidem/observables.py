"""Observables computed from a finished run.

contact_time: for every particle, the duration of its first contact (first touch to first
release, measured by the force kernel), next to the Hertz prediction for a head-on impact
with its nearest particle at t = 0, t_c = 2.868 (m*^2 / (R* E*^2 v))^(1/5) (Johnson 1985),
v the initial relative speed along the line of centres.
"""

from __future__ import annotations

import numpy as np

from tidem.kernels import contact_laws as cl
from tidem.timestep import hertz_contact_time


def contact_times(model, solver) -> list[dict]:
    S = solver.state
    start = S.touch_start.to_numpy()
    end = S.touch_end.to_numpy()
    x0, v0, r, m = model.x0, model.v0, model.radius, model.mass
    rows = []
    for i in range(model.capacity):
        d = np.linalg.norm(x0 - x0[i], axis=1)
        d[i] = np.inf
        j = int(np.argmin(d)) if model.capacity > 1 else i
        row = {"particle": i, "partner": j,
               "contact_time_s": float(end[i] - start[i]) if start[i] >= 0 and end[i] >= 0 else None}
        if j != i:
            n = (x0[j] - x0[i]) / d[j]
            speed = float(np.dot(v0[i] - v0[j], n))
            if speed > 0:
                e_star = model.pair_params[model.material[i], model.material[j], cl.ESTAR]
                m_eff = m[i] * m[j] / (m[i] + m[j])
                r_eff = r[i] * r[j] / (r[i] + r[j])
                row["impact_speed_m_s"] = speed
                row["hertz_contact_time_s"] = hertz_contact_time(m_eff, r_eff, e_star, speed)
        rows.append(row)
    return rows


def alpha_profile(model, solver) -> tuple[list[dict], list[dict]]:
    """Local heat-transfer coefficient around each heated tube (source 3 eq. 34-36, ring
    sectors): alpha(omega) = q(omega) / (T_wall - T_ref), q the time-averaged heat flux
    through the sector of angle omega from the top of the tube since heat.profile_start,
    T_ref = heat.initial_temperature (the temperature the bed enters with). With gas-tube
    convection the mean alpha adds the tube's heat to the gas (gas_alpha) to the particles'.
    Returns (rows of tube, angle_deg, alpha, and the mean alpha per tube)."""
    if not model.angle_bins or solver.profile_t0 is None or solver.t <= solver.profile_t0:
        return [], []
    energy = solver.state.tube_bin_energy.to_numpy()
    gas_energy = solver.gas.G.wall_energy.to_numpy() if solver.gas is not None and solver.gas.walls else None
    span = solver.t - solver.profile_t0
    t_ref = model.scene.heat.initial_temperature
    rows, means = [], []
    bins = model.angle_bins
    for k, tube in enumerate(model.tubes):
        if tube["T"] is None:
            continue
        axis = 0 if tube["mask"][0] == 0.0 else 1
        length = model.grid.length[axis]
        area = 2 * np.pi * tube["r"] / bins * length
        dT = tube["T"] - t_ref
        for b in range(bins):
            rows.append({"tube": k, "angle_deg": (b + 0.5) * 360.0 / bins,
                         "alpha_W_m2K": float(energy[k, b] / span / area / dT)})
        mean = {"tube": k, "mean_alpha_W_m2K": float(energy[k].sum() / span / (area * bins) / dT),
                "averaged_over_s": span}
        if gas_energy is not None:  # convection to the gas joins the particles' share
            mean["particles_alpha_W_m2K"] = mean["mean_alpha_W_m2K"]
            mean["gas_alpha_W_m2K"] = float(gas_energy[k] / span / (area * bins) / dT)
            mean["mean_alpha_W_m2K"] += mean["gas_alpha_W_m2K"]
        means.append(mean)
    return rows, means
