"""Heat transfer from heated mesh walls to the bed, and the rotating drum's bed geometry.

For every heated mesh, from the time series (second half of the run): the heat flow Q(t) into
the bed (`meshesK_heat_W`) over the mesh's whole area A and the difference between its temperature
and the bed's mean temperature, alpha = mean of Q / (A (T_wall - T_bed)); with gas convection from
the mesh, its heat flow into the gas (`meshesK_gas_heat_W`) adds gas_alpha over the same A and
difference to the particles' share.

A rotating mesh (a drum or kiln, axis through `center`) gets more, from the particles at the end:
- the bed's free surface: the top particle of each slice one mean diameter wide across the drum
  (perpendicular to the axis and to gravity) over the middle 60 % of the bed's width, fitted by a
  line; its slope is the dynamic angle of repose;
- the filling angle eps, the central angle of the wall under that chord, 2 arccos(p / R), p the
  distance of the chord from the axis and R the drum's radius (its vertices' largest distance from
  the axis); the wetted wall A_w = eps R L (L the drum's length in the domain) and the coefficient
  over it, alpha_w = mean of Q / (A_w (T_wall - T_bed));
- the penetration model of rotary drums (Schluender's packet model, `tidem.heat.packet_model`: contact
  coefficient phi alpha_WP in series with a half-space heated for the contact time t_c = eps / omega,
  (2 / sqrt(pi)) sqrt(lambda_bed rho_bed c / t_c)), the time a wall element spends under the bed.
"""

from __future__ import annotations

import math

import numpy as np

from tidem.heat.packet_model import BED_POROSITY, COVERED_SHARE, penetration_alpha, zehner_schluender_conductivity
from tidem.kernels.heat import schluender_alpha_wp

SURFACE_SPAN = 0.6  # share of the bed's width, about its middle, whose top particles make the free surface


def _late(series: dict, column: str) -> np.ndarray:
    t = series["time_s"]
    return np.asarray(series[column])[t >= 0.5 * t[-1]]


def _late_times(series: dict) -> np.ndarray:
    t = np.asarray(series["time_s"])
    return t[t >= 0.5 * t[-1]]


def free_surface(x: np.ndarray, radius: np.ndarray, centre, axis, gravity) -> tuple[float, float] | None:
    """(slope angle [deg], distance of the surface line from the axis [m], > 0 below it) of the bed
    in the drum's cross-section; None for too few slices."""
    down = np.asarray(gravity, float) / np.linalg.norm(gravity)
    a = np.asarray(axis, float)
    across = np.cross(a, down)
    across /= np.linalg.norm(across)
    rel = x - np.asarray(centre, float)
    u, h = rel @ across, -(rel @ down)  # across the drum, and height above the axis
    d = 2.0 * float(np.mean(radius))
    lo, hi = np.percentile(u, 1), np.percentile(u, 99)
    mid, half = 0.5 * (lo + hi), 0.5 * SURFACE_SPAN * (hi - lo)
    edges = np.arange(mid - half, mid + half + d, d)
    tops_u, tops_h = [], []
    for e0, e1 in zip(edges[:-1], edges[1:]):
        pick = (u >= e0) & (u < e1)
        if pick.any():
            k = np.argmax(h[pick])
            tops_u.append(u[pick][k])
            tops_h.append(h[pick][k] + radius[pick][k])
    if len(tops_u) < 3:
        return None
    slope, height = np.polyfit(tops_u, tops_h, 1)
    return math.degrees(math.atan(abs(slope))), -height / math.sqrt(1.0 + slope * slope)


def mesh_heat_rows(model, x: np.ndarray, radius: np.ndarray, series: dict) -> list[dict]:
    """One row per heated mesh (module docstring)."""
    rows = []
    scene = model.scene
    if scene.heat is None or "T_mean_K" not in series:
        return rows
    t_bed = _late(series, "T_mean_K")
    for k, mesh in enumerate(model.meshes):
        key = f"meshes{k}_heat_W"
        if mesh.temperature is None or key not in series:
            continue
        q = _late(series, key)
        dt = np.array([mesh.temperature_at(t) for t in _late_times(series)]) - t_bed  # a schedule's value at each sample
        row = {"mesh": k, "heat_W": float(np.mean(q)), "area_m2": float(mesh.stats.get("area", np.nan))}
        row["mean_alpha_W_m2K"] = float(np.mean(q / (row["area_m2"] * dt)))
        if f"meshes{k}_gas_heat_W" in series:  # convection to the gas joins the particles' share
            q_gas = _late(series, f"meshes{k}_gas_heat_W")
            row["particles_alpha_W_m2K"] = row["mean_alpha_W_m2K"]
            row["gas_heat_W"] = float(np.mean(q_gas))
            row["gas_alpha_W_m2K"] = float(np.mean(q_gas / (row["area_m2"] * dt)))
            row["mean_alpha_W_m2K"] += row["gas_alpha_W_m2K"]
        if mesh.rotates and mesh.speed_at(float(series["time_s"][-1])) != 0.0 and len(x):
            row.update(_drum(model, mesh, x, radius, q, dt, float(series["time_s"][-1])))
        rows.append(row)
    return rows


def _drum(model, mesh, x, radius, q, dt, t_end: float) -> dict:
    """Bed geometry, the wetted-wall coefficient and the penetration model of a rotating mesh (its
    rotation speed at the end, `t_end`, where a schedule gives it)."""
    out = {}
    surface = free_surface(x, radius, mesh.center, mesh.axis, model.scene.domain.gravity)
    big_r = mesh.reach_from_axis()
    if surface is None or not 0.0 <= surface[1] < big_r:
        return out
    angle, p = surface
    eps = 2.0 * math.acos(p / big_r)
    a = np.abs(np.asarray(mesh.axis, float))
    length = float(np.dot(a, np.asarray(model.grid.length)))  # the drum's length inside the domain
    wetted = eps * big_r * length
    out.update(repose_angle_deg=angle, fill_angle_deg=math.degrees(eps), wetted_area_m2=wetted,
               wetted_alpha_W_m2K=float(np.mean(q / (wetted * dt))))
    group = model.scene.particles[0]
    mat = model.scene.materials[group.material]
    heat = model.scene.heat
    t_c = eps / abs(mesh.speed_at(t_end))
    d = 2.0 * float(np.mean(radius))
    lam = zehner_schluender_conductivity(mat.conductivity, heat.gas_conductivity, BED_POROSITY)
    a_c = COVERED_SHARE * float(schluender_alpha_wp(heat.gas_conductivity, d, heat.gas_mean_free_path + heat.roughness))
    a_s = penetration_alpha(lam, (1.0 - BED_POROSITY) * mat.density, mat.heat_capacity, t_c)
    model_alpha = 1.0 / (1.0 / a_c + 1.0 / a_s)
    out.update(contact_time_s=t_c, contact_alpha_W_m2K=a_c, penetration_alpha_W_m2K=a_s,
               model_alpha_W_m2K=model_alpha, over_model=out["wetted_alpha_W_m2K"] / model_alpha)
    return out
