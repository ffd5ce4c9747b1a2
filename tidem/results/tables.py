"""Measurements from a finished run's solver state that the observables draw on
(`tidem.results.observables.record`): first-contact durations of head-on pairs next to Hertz (Johnson
1985), heat per impact next to the quasi-static Hertz integral and Sun & Chen (1988), the packet
model next to each heated tube's mean alpha, and each heated tube's alpha profile by angle.
"""

from __future__ import annotations

import math

import numpy as np

from tidem.heat.impact_conduction import hertz_impact, quasi_static_impact_heat, sun_chen_impact_heat
from tidem.heat.packet_model import packet_alpha
from tidem.kernels import contact_laws as cl
from tidem.particles.timestep import hertz_contact_time
from tidem.scene.schedule import value_at
from tidem.walls.surfaces import angle_bin_area, is_heated


def head_on_partners(model):
    """For every particle i: its nearest particle j at t = 0 and, when they approach, the
    approach speed along the line of centres, m* and R* (else speed None)."""
    x0, v0, r, m = model.x0, model.v0, model.radius, model.mass
    for i in range(model.capacity):
        d = np.linalg.norm(x0 - x0[i], axis=1)
        d[i] = np.inf
        j = int(np.argmin(d)) if model.capacity > 1 else i
        speed = float(np.dot(v0[i] - v0[j], (x0[j] - x0[i]) / d[j])) if j != i else 0.0
        if speed > 0:
            yield i, j, speed, m[i] * m[j] / (m[i] + m[j]), r[i] * r[j] / (r[i] + r[j])
        else:
            yield i, j, None, None, None


def contact_times(model, solver) -> list[dict]:
    S = solver.state
    start = S.touch_start.to_numpy()
    end = S.touch_end.to_numpy()
    rows = []
    for i, j, speed, m_eff, r_eff in head_on_partners(model):
        row = {"particle": i, "partner": j,
               "contact_time_s": float(end[i] - start[i]) if start[i] >= 0 and end[i] >= 0 else None}
        if speed is not None:
            e_star = model.pair_params[model.material[i], model.material[j], cl.ESTAR]
            row["impact_speed_m_s"] = speed
            row["hertz_contact_time_s"] = hertz_contact_time(m_eff, r_eff, e_star, speed)
        rows.append(row)
    return rows


def impact_heat_rows(model, solver) -> list[dict]:
    """Heat gained by each particle [J] against the two analytic estimates for one impact with
    its partner (positive: heat flows into the particle)."""
    gained = model.heat_capacity * (solver.state.T.to_numpy() - model.temperature0)
    mats = list(model.scene.materials.values())
    rows = []
    for i, j, speed, m_eff, r_eff in head_on_partners(model):
        row = {"particle": i, "partner": j, "heat_gained_J": float(gained[i])}
        d_t = model.temperature0[j] - model.temperature0[i]
        if speed is not None and d_t != 0.0:
            p = model.pair_params[model.material[i], model.material[j]]
            e_real = p[cl.ESTAR] / p[cl.A_CORR] ** 3  # A_CORR = (E*_sim / E*_real)^(1/3)
            sim, real = hertz_impact(m_eff, r_eff, p[cl.ESTAR], speed), hertz_impact(m_eff, r_eff, e_real, speed)
            effusivity = [math.sqrt(mats[model.material[k]].density * mats[model.material[k]].heat_capacity
                                    * mats[model.material[k]].conductivity) for k in (i, j)]
            q_qs = quasi_static_impact_heat(p[cl.K_EFF], sim, d_t, radius_scale=p[cl.A_CORR])
            q_sc = sun_chen_impact_heat(real, d_t, *effusivity)
            row.update({"impact_speed_m_s": speed, "quasi_static_heat_J": q_qs, "sun_chen_heat_J": q_sc,
                        "simulated_over_quasi_static": float(gained[i]) / q_qs,
                        "simulated_over_sun_chen": float(gained[i]) / q_sc})
        rows.append(row)
    return rows


def packet_model_rows(model, tube_means: list[dict]) -> list[dict]:
    """Schluender's packet model for each heated tube next to its simulated mean alpha; needs a
    moving-plate outlet (its speed is the bed speed u_ref). The bed is the first particle group."""
    outlet = model.scene.outlet
    if outlet is None or outlet.type != "moving_plate":
        return []
    heat = model.scene.heat
    group = model.scene.particles[0]
    mat = model.scene.materials[group.material]
    first = model.group == 0
    rows = []
    for row in tube_means:
        tube = model.scene.tubes[row["tube"]]
        ref = packet_alpha(tube_diameter=tube.diameter, speed=value_at(outlet.speed, model.t_end),
                           particle_diameter=float(2.0 * (model.radius[first] / model.coarse_grain[first]).mean()),
                           solid_density=mat.density,
                           solid_conductivity=mat.conductivity, heat_capacity=mat.heat_capacity,
                           gas_conductivity=heat.gas_conductivity, gap=heat.gas_mean_free_path + heat.roughness)
        rows.append({"tube": row["tube"], **ref.as_dict(), "simulated_mean_alpha_W_m2K": row["mean_alpha_W_m2K"],
                     "simulated_over_packet": row["mean_alpha_W_m2K"] / ref.alpha_W_m2K})
    return rows


def alpha_profile(model, solver) -> tuple[list[dict], list[dict]]:
    """Local heat-transfer coefficient around each heated tube (source 3 eq. 34-36, ring
    sectors), time-averaged since heat.profile_start, T_ref = heat.initial_temperature (the
    temperature the bed enters with):
    * fixed temperature: alpha(omega) = q(omega) / (T_wall - T_ref), q the heat flux through
      the sector of angle omega from the top of the tube;
    * heated foil (source 3 eq. 4, as measured): alpha(omega) = q_el / (T_foil(omega) - T_ref),
      q_el the electric heating per area and T_foil the foil's mean temperature in the sector;
      the mean alpha is the circumference mean of alpha(omega), as the experiment averages
      its local values (for a fixed-temperature tube the two definitions agree);
      `alpha_of_mean_excess` = q_el / (mean of T_foil - T_ref) gives the tube's heat from its
      mean temperature, and `foil_storage_pct` is the share of the heating still warming the
      foil (0 in a steady state).
    A fixed-temperature tube's mean alpha is split by route: the solid contact spots of touching
    particles (contact_spot_alpha), Schluender's gas gap of touching particles with their radiation
    (gas_gap_alpha), the gas lens of particles near the tube that do not touch it (gas_lens_alpha).
    With gas-tube convection the mean alpha adds the tube's heat to the gas (gas_alpha) to
    the particles'. Returns (rows of tube, angle_deg, alpha, and the mean alpha per tube)."""
    if not model.angle_bins or solver.profile_t0 is None or solver.t <= solver.profile_t0:
        return [], []
    S = solver.state
    energy = S.tube_bin_energy.to_numpy()
    route = S.tube_route_energy.to_numpy()
    foil_T = S.tube_bin_Tsum.to_numpy() if model.features.foil else None
    gas_energy = solver.gas.G.wall_energy.to_numpy() if solver.gas is not None and solver.gas.walls else None
    span = solver.t - solver.profile_t0
    t_ref = model.scene.heat.initial_temperature
    rows, means = [], []
    bins = model.angle_bins
    for k, tube in enumerate(model.tubes):
        if not is_heated(tube):
            continue
        area = angle_bin_area(model, tube)
        if tube["flux"] is not None:
            excess = foil_T[k] / span - t_ref
            local = tube["flux"] / excess
            mean = {"tube": k, "mean_alpha_W_m2K": float(local.mean()), "averaged_over_s": span,
                    "alpha_of_mean_excess_W_m2K": float(tube["flux"] / excess.mean()),
                    "foil_storage_pct": float(100 * (1 - energy[k].sum() / (tube["flux"] * area * bins * span)))}
        else:
            dT = tube["T"] - t_ref
            local = energy[k] / span / area / dT
            scale = span * area * bins * dT
            mean = {"tube": k, "mean_alpha_W_m2K": float(energy[k].sum() / scale), "averaged_over_s": span}
            spot, lens = (float(e / scale) for e in route[k])
            mean.update(contact_spot_alpha_W_m2K=spot, gas_gap_alpha_W_m2K=mean["mean_alpha_W_m2K"] - spot - lens,
                        gas_lens_alpha_W_m2K=lens)
            if gas_energy is not None:  # convection to the gas joins the particles' share
                mean["particles_alpha_W_m2K"] = mean["mean_alpha_W_m2K"]
                mean["gas_alpha_W_m2K"] = float(gas_energy[k] / scale)
                mean["mean_alpha_W_m2K"] += mean["gas_alpha_W_m2K"]
        rows += [{"tube": k, "angle_deg": (b + 0.5) * 360.0 / bins, "alpha_W_m2K": float(local[b])}
                 for b in range(bins)]
        means.append(mean)
    return rows, means


def tube_alpha_columns(model, row: dict) -> dict[str, float]:
    """Each heated tube's heat-transfer coefficient at one time-series sample [W/(m^2 K)]
    (`tubes0_alpha_W_m2K`): `alpha_profile`'s definitions at an instant rather than averaged, the
    reference T_ref = heat.initial_temperature. A fixed-temperature tube: its heat flow into the
    particles and (with gas-tube convection) into the gas, `row`'s `tubes0_heat_W` and
    `tubes0_gas_heat_W`, over its area in the domain and T_wall - T_ref; a heated foil: q_el over
    its mean foil temperature's excess, `tubes0_foil_T_K` - T_ref. Empty without [heat]."""
    if not model.features.heat:
        return {}
    t_ref = model.scene.heat.initial_temperature
    out = {}
    for tube in model.tubes:
        key = tube["name"].replace("[", "").replace("]", "")
        if tube["flux"] is not None and f"{key}_foil_T_K" in row and row[f"{key}_foil_T_K"] != t_ref:
            out[f"{key}_alpha_W_m2K"] = tube["flux"] / (row[f"{key}_foil_T_K"] - t_ref)
        elif tube["T"] is not None and tube["T"] != t_ref and f"{key}_heat_W" in row:
            length = model.grid.length[tube["mask"].index(0.0)]
            area = 2 * math.pi * tube["r"] * length
            heat = row[f"{key}_heat_W"] + row.get(f"{key}_gas_heat_W", 0.0)
            out[f"{key}_alpha_W_m2K"] = heat / (area * (tube["T"] - t_ref))
    return out
