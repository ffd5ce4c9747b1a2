"""The observables registry: scalar results of a run, declared by the scene
(`observables = ["bed_height", ...]`), written to run.json by every run and compared by
`tidem tradeoff` and `tidem sweep`.

Each observable is one function of a `RunRecord` (the state at the end of a run and its
time series) that returns named values, one per column (several for per-tube values); its
docstring gives the definition and the unit. The names and what each needs of a scene (a
heated tube, a gas phase) are listed in `tidem.scene.observable_names`, so that scene
validation refuses a scene asking for one it cannot give without importing this module.
docs/scenes.md lists the same definitions.

"Second half" means the time-series samples with t >= t_end / 2.

Per-particle and per-tube tables behind some observables go to run.json as well:
contact_times (first-contact durations next to Hertz, t_c = 2.868 (m*^2 / (R* E*^2 v))^(1/5),
Johnson 1985), impact_heat (heat gained per particle next to the quasi-static Hertz integral
and Sun & Chen 1988, `tidem.heat.impact_conduction`) and packet_model (Schluender's packet model
next to the simulated mean alpha, `tidem.heat.packet_model`), measured by `tidem.results.tables`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from tidem.heat.drum_heat import mesh_heat_rows
from tidem.results.dispersion import run_dispersion
from tidem.results.hydrodynamics import MIN_PERIODS, bed_top, dominant_frequency, second_half
from tidem.results.tables import alpha_profile, contact_times, impact_heat_rows, packet_model_rows
from tidem.scene.observable_names import NEEDS
from tidem.walls.surfaces import plate_z


@dataclass
class RunRecord:
    """What the observables see of a finished run. Arrays cover the active particles."""

    time_s: float
    x: np.ndarray
    """Particle centres at the end [m], shape [n, 3]."""
    v: np.ndarray
    """Particle velocities at the end [m/s], shape [n, 3]."""
    mass: np.ndarray
    """Particle masses [kg], shape [n]; zero-motion (fixed) particles included."""
    radius: np.ndarray
    """Particle radii [m], shape [n]."""
    v0: np.ndarray
    """Initial velocities of the same particles [m/s], shape [n, 3]."""
    floor_z: float
    """Height of the bed's floor at the end [m]: the outlet plate, else the domain's min z."""
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    """The scene's gravity [m/s^2]."""
    series: dict[str, np.ndarray] = field(default_factory=dict)
    """timeseries.csv as columns."""
    temperature: np.ndarray | None = None
    """Particle temperatures at the end [K], shape [n]; None without [heat]."""
    alpha_means: list[dict] = field(default_factory=list)
    """Mean heat-transfer coefficient per heated tube (`alpha_profile`)."""
    contact_rows: list[dict] = field(default_factory=list)
    """First-contact durations per particle (`contact_times`)."""
    impact_rows: list[dict] = field(default_factory=list)
    """Heat per impact per particle (`impact_heat_rows`), when the scene declares impact_heat."""
    packet_rows: list[dict] = field(default_factory=list)
    """Packet model per heated tube (`packet_model_rows`), for a moving-plate outlet."""
    bed_profiles: dict | None = None
    """Summary of the packed-bed profiles against Schumann (`tidem.results.bed_profiles.profile_rows`)."""
    mesh_rows: list[dict] = field(default_factory=list)
    """Heat transfer of each heated mesh, and a drum's bed geometry (`tidem.heat.drum_heat`)."""
    snapshots: list[tuple[float, Path]] = field(default_factory=list)
    """The run's snapshot files on disk with their times [(s, path)], in time order."""


def record(model, solver, series: dict[str, np.ndarray], bed_profiles: dict | None = None,
           snapshots: list[tuple[float, Path]] | None = None) -> RunRecord:
    """The RunRecord of a run at its end (after the time series and the snapshots are closed); `bed_profiles`
    is the packed-bed profile summary the run loop computed, if the scene declares it; `snapshots` the run's
    snapshot files [(time, path)]."""
    S = solver.state
    active = S.active.to_numpy().astype(bool)
    floor = model.scene.domain.min[2]
    for p in model.planes:
        if p["name"] == "outlet plate":
            floor = plate_z(p, solver.t)
    means = alpha_profile(model, solver)[1]
    ident = S.ident.to_numpy()[active]  # index in the scene's arrays (`tidem.particles.storage_order`)
    x, radius = S.x.to_numpy()[active], S.radius.to_numpy()[active]
    return RunRecord(
        time_s=solver.t, x=x, v=S.v.to_numpy()[active], mass=model.mass[ident],
        radius=radius, v0=model.v0[ident], floor_z=float(floor), gravity=tuple(model.scene.domain.gravity),
        series=series,
        temperature=S.T.to_numpy()[active] if model.features.heat else None,
        alpha_means=means,
        contact_rows=contact_times(model, solver) if model.features.contact_time else [],
        impact_rows=impact_heat_rows(model, solver) if "impact_heat" in model.scene.observables else [],
        packet_rows=packet_model_rows(model, means), bed_profiles=bed_profiles,
        mesh_rows=mesh_heat_rows(model, x, radius, series), snapshots=list(snapshots or []))


Compute = Callable[[RunRecord], dict[str, float]]
OBSERVABLES: dict[str, Compute] = {}


def observable(name: str) -> Callable[[Compute], Compute]:
    """Register `fn` as observable `name`, one of the names a scene may declare
    (`tidem.scene.observable_names`, which also says what each needs of the scene)."""
    if name not in NEEDS:
        raise KeyError(f"observable '{name}' is not listed in tidem.scene.observable_names")

    def register(fn: Compute) -> Compute:
        OBSERVABLES[name] = fn
        return fn
    return register


def compute(names: list[str], rec: RunRecord) -> dict[str, dict[str, float]]:
    """{observable name: {column: value}} for the declared names, in their order."""
    return {name: OBSERVABLES[name](rec) for name in names}


def flatten(observed: dict[str, dict[str, float]]) -> dict[str, float]:
    """run.json's observables as one {column: value} table of numbers (what tradeoff compares):
    values left out (None) and notes (text saying why) are dropped."""
    return {col: float(val) for values in observed.values() for col, val in values.items()
            if isinstance(val, (int, float)) and not isinstance(val, bool)}


def _late_mean(rec: RunRecord, column: str) -> float:
    t = rec.series["time_s"]
    return float(np.nanmean(rec.series[column][t >= 0.5 * t[-1]]))


@observable("tube_heat")
def tube_heat(rec: RunRecord) -> dict[str, float]:
    """Heat flow from each heated surface into the bed [W] (`tubes1_heat_W`, named
    after the surface), time mean over the second half of the run (timeseries.csv)."""
    return {k: _late_mean(rec, k) for k in rec.series if k.endswith("_heat_W")}


@observable("tube_mean_alpha")
def tube_mean_alpha(rec: RunRecord) -> dict[str, float]:
    """Mean heat-transfer coefficient of each heated tube [W/(m^2 K)] (`tube1_mean_alpha_W_m2K`):
    heat delivered since heat.profile_start / (time x tube area x (T_tube - heat.initial_temperature)),
    source 3 eq. 34-36 averaged over the whole circumference; for a heated foil the mean of the
    local q_el / (T_foil - T_ref), with `tube1_alpha_of_mean_excess_W_m2K` and
    `tube1_foil_storage_pct` beside it; a fixed-temperature tube's split by route beside it
    (`tube1_contact_spot_alpha_W_m2K`, `_gas_gap_`, `_gas_lens_`, and with gas convection `_particles_`
    and `_gas_alpha_W_m2K`; `alpha_profile`)."""
    out = {}
    for row in rec.alpha_means:
        out[f"tube{row['tube']}_mean_alpha_W_m2K"] = row["mean_alpha_W_m2K"]
        for key in ("particles_alpha_W_m2K", "contact_spot_alpha_W_m2K", "gas_gap_alpha_W_m2K", "gas_lens_alpha_W_m2K",
                    "gas_alpha_W_m2K", "alpha_of_mean_excess_W_m2K", "foil_storage_pct"):  # by route; heated foils
            if key in row:
                out[f"tube{row['tube']}_{key}"] = row[key]
    return out


def _top(rec: RunRecord) -> float:
    return bed_top(rec.x[:, 2])


@observable("bed_height")
def bed_height(rec: RunRecord) -> dict[str, float]:
    """Bed height [m] (`bed_height_m`): the 99th percentile of the particle centres' z at the
    end (absolute z, not above the floor; the percentile ignores a few thrown particles), and
    the time mean of the same height over the second half (`bed_height_mean_m`, timeseries
    column bed_height_m; a bubbling bed heaves, so its end value is one instant of that)."""
    mean = _late_mean(rec, "bed_height_m") if "bed_height_m" in rec.series else None
    return {"bed_height_m": _top(rec), "bed_height_mean_m": mean}


@observable("centre_of_mass")
def centre_of_mass(rec: RunRecord) -> dict[str, float]:
    """Height of the particles' centre of mass [m] (absolute z): at the end, sum m z / M
    (`centre_of_mass_m`), and its time mean over the second half (`centre_of_mass_mean_m`) from the
    timeseries column potential_energy_J = sum m |g| z, divided by M |g|. A bed's expansion that, unlike
    the bed height, no few particles at its surface decide, and that parcels of any size weigh alike;
    it needs gravity along -z and a bed whose mass M stays the same (no outlet, no pour)."""
    mass = float(rec.mass.sum())
    mean = (_late_mean(rec, "potential_energy_J") / (mass * abs(rec.gravity[2]))
            if "potential_energy_J" in rec.series else None)
    return {"centre_of_mass_m": float(np.dot(rec.mass, rec.x[:, 2]) / mass), "centre_of_mass_mean_m": mean}


@observable("outlet_mass_flow")
def outlet_mass_flow(rec: RunRecord) -> dict[str, float]:
    """Solids mass flow down through a horizontal section [kg/s] (`outlet_mass_flow_kg_s`), at
    the end, averaged over the bed's height H: sum_i m_i (-v_z,i) / H, with H from the floor
    (outlet plate or domain bottom) to the bed top (bed_height + mean radius). In a steady bed
    this is the outlet flux; a plug sinking at the plate speed u gives M u / H."""
    h = _top(rec) + float(rec.radius.mean()) - rec.floor_z
    return {"outlet_mass_flow_kg_s": float(np.sum(rec.mass * -rec.v[:, 2]) / h)}


@observable("discharge_rate")
def discharge_rate(rec: RunRecord) -> dict[str, float]:
    """Discharge rate of a sink outlet [kg/s] (`discharge_rate_kg_s`): the least-squares slope of
    the discharged mass over time after the first quarter of the run (a fill has settled, the flow
    set in) while less than 70 % of the mass discharged by the end has left (before a bin runs low),
    and the same over the first and the second half of that window (`discharge_rate_early_kg_s`,
    `discharge_rate_late_kg_s`: equal in a flow independent of the fill height, as Beverloo's). NaN
    with fewer than four samples there."""
    t, m = rec.series.get("time_s"), rec.series.get("discharged_mass_kg")
    out = {k: float("nan") for k in ("discharge_rate_kg_s", "discharge_rate_early_kg_s", "discharge_rate_late_kg_s")}
    if t is None or m is None or len(m) == 0 or m[-1] <= 0.0:
        return out
    pick = (t >= 0.25 * t[-1]) & (m <= 0.7 * m[-1])
    t, m = t[pick], m[pick]
    if len(t) < 4:
        return out
    half = len(t) // 2
    out["discharge_rate_kg_s"] = float(np.polyfit(t, m, 1)[0])
    if half >= 2 and len(t) - half >= 2:
        out["discharge_rate_early_kg_s"] = float(np.polyfit(t[:half], m[:half], 1)[0])
        out["discharge_rate_late_kg_s"] = float(np.polyfit(t[half:], m[half:], 1)[0])
    return out


@observable("wall_heat_transfer")
def wall_heat_transfer(rec: RunRecord) -> dict[str, float]:
    """Heat-transfer coefficient of each heated mesh [W/(m^2 K)] over the second half
    (`tidem.heat.drum_heat`): `meshes0_mean_alpha_W_m2K` over its whole area against the bed's mean
    temperature, with its heat flow `meshes0_heat_W`; for a rotating mesh (a drum) also the dynamic
    angle of repose and the filling angle [deg], the coefficient over the wetted wall and the
    penetration model's (`meshes0_wetted_alpha_W_m2K`, `meshes0_model_alpha_W_m2K`, their ratio
    `meshes0_over_model`, the contact time under the bed [s])."""
    out = {}
    for row in rec.mesh_rows:
        out.update({f"meshes{row['mesh']}_{k}": v for k, v in row.items() if k != "mesh"})
    return out


@observable("mean_temperature")
def mean_temperature(rec: RunRecord) -> dict[str, float]:
    """Mean particle temperature at the end [K] (`mean_temperature_K`), unweighted."""
    return {"mean_temperature_K": float(rec.temperature.mean())}


@observable("contact_time")
def contact_time(rec: RunRecord) -> dict[str, float]:
    """Mean first-contact duration [s] (`contact_time_s`) over the particles that touched and
    let go (first touch to first release, measured by the force kernel), and the mean Hertz
    prediction for the same particles (`hertz_contact_time_s`, see `contact_times`)."""
    rows = [r for r in rec.contact_rows if r.get("contact_time_s")]
    hertz = [r["hertz_contact_time_s"] for r in rows if "hertz_contact_time_s" in r]
    return {"contact_time_s": float(np.mean([r["contact_time_s"] for r in rows])) if rows else None,
            "hertz_contact_time_s": float(np.mean(hertz)) if hertz else None}


@observable("restitution")
def restitution(rec: RunRecord) -> dict[str, float]:
    """Rebound over impact speed [-] (`restitution`): mean over the particles that moved at
    t = 0 of -(v_end . v0) / |v0|^2. For head-on impacts without gravity, with the centre of
    mass at rest (two equal spheres closing, or a sphere hitting a wall square on), this is the
    normal coefficient of restitution."""
    speed2 = np.einsum("ij,ij->i", rec.v0, rec.v0)
    moving = speed2 > 0
    if not moving.any():
        return {"restitution": None}
    return {"restitution": float(np.mean(-np.einsum("ij,ij->i", rec.v[moving], rec.v0[moving]) / speed2[moving]))}


@observable("pressure_drop")
def pressure_drop(rec: RunRecord) -> dict[str, float]:
    """Gas pressure drop across the bed [Pa] (`pressure_drop_Pa`): the distributor-level minus
    the top pressure (timeseries column gas_pressure_drop_Pa), time mean over the second half."""
    return {"pressure_drop_Pa": _late_mean(rec, "gas_pressure_drop_Pa")}


@observable("pressure_fluctuation")
def pressure_fluctuation(rec: RunRecord) -> dict[str, float | str | None]:
    """Fluctuation of the gas pressure drop over the second half (timeseries column
    gas_pressure_drop_Pa): its standard deviation [Pa] (`pressure_drop_std_Pa`) and its dominant
    frequency [Hz] (`pressure_drop_frequency_Hz`: the highest peak of the detrended spectrum,
    `tidem.results.hydrodynamics.dominant_frequency`). The frequency is given only where the second half
    holds at least five of its periods; otherwise it is null and `pressure_drop_frequency_note`
    says why (the run is too short to tell a frequency)."""
    t, p = second_half(rec.series["time_s"], rec.series["gas_pressure_drop_Pa"])
    out: dict[str, float | str | None] = {"pressure_drop_std_Pa": float(np.std(p)) if len(p) else None,
                                          "pressure_drop_frequency_Hz": None}
    peak = dominant_frequency(t, p)
    if peak is None:
        out["pressure_drop_frequency_note"] = f"too few samples in the second half ({len(p)}) for a spectrum"
    elif not peak.resolved:
        out["pressure_drop_frequency_note"] = (
            f"the strongest peak ({peak.frequency_Hz:.3g} Hz) has {peak.periods:.1f} periods in the second half "
            f"({t[-1] - t[0]:.3g} s), fewer than {MIN_PERIODS}; run longer (numerics.t_end) to resolve it")
    else:
        out["pressure_drop_frequency_Hz"] = peak.frequency_Hz
    return out


@observable("kinetic_energy")
def kinetic_energy(rec: RunRecord) -> dict[str, float]:
    """Translational kinetic energy of the particles at the end [J] (`kinetic_energy_J`),
    sum_i m_i |v_i|^2 / 2."""
    return {"kinetic_energy_J": float(0.5 * np.sum(rec.mass * np.einsum("ij,ij->i", rec.v, rec.v)))}


@observable("granular_temperature")
def granular_temperature(rec: RunRecord) -> dict[str, float]:
    """The solids' granular temperature [m^2/s^2] (`granular_temperature_m2_s2`): time mean over the second
    half of the timeseries column of the same name, each sample's theta = sum n/(n - 1) sum m |v - u_cell|^2 /
    (3 sum m) over cubes of 6 diameters of the largest grain that hold two particles or more
    (`tidem.results.granular`); per grain at any coarse graining."""
    column = "granular_temperature_m2_s2"
    return {column: _late_mean(rec, column) if column in rec.series else None}


@observable("dispersion")
def dispersion(rec: RunRecord) -> dict[str, float]:
    """The solids' vertical dispersion coefficient [m^2/s] (`dispersion_m2_s`), a mixing rate: half the slope
    of the particles' mean square vertical displacement over lags of 0.02-0.1 s, particles followed by id
    through the snapshots of the second half (`tidem.results.dispersion`); per grain at any coarse graining.
    None with `dispersion_note` where the snapshots are too sparse or too few (output.interval not 0.02 s or a
    divisor of it, or a run shorter than 0.08 s)."""
    return run_dispersion(rec.snapshots, rec.time_s)


@observable("impact_heat")
def impact_heat(rec: RunRecord) -> dict[str, float]:
    """Heat passed in the head-on impacts [J] (`impact_heat_J`: mean over the particles that
    gained heat of m c (T_end - T_0)) and its mean ratios to the quasi-static Hertz integral of
    the spot conductance (`over_quasi_static`) and to Sun & Chen's transient impact conduction
    (`over_sun_chen`); per-particle rows in run.json's `impact_heat`."""
    rows = [r for r in rec.impact_rows if "quasi_static_heat_J" in r and r["heat_gained_J"] > 0]
    if not rows:
        return {"impact_heat_J": None}
    return {"impact_heat_J": float(np.mean([r["heat_gained_J"] for r in rows])),
            "over_quasi_static": float(np.mean([r["simulated_over_quasi_static"] for r in rows])),
            "over_sun_chen": float(np.mean([r["simulated_over_sun_chen"] for r in rows]))}


@observable("packet_model")
def packet_model(rec: RunRecord) -> dict[str, float]:
    """Schluender's packet model alpha of each heated tube [W/(m^2 K)]
    (`tube1_packet_alpha_W_m2K`) and the simulated mean alpha over it (`tube1_over_packet`)."""
    out = {}
    for row in rec.packet_rows:
        out[f"tube{row['tube']}_packet_alpha_W_m2K"] = row["alpha_W_m2K"]
        out[f"tube{row['tube']}_over_packet"] = row["simulated_over_packet"]
    return out


@observable("packed_bed_profiles")
def packed_bed_profiles(rec: RunRecord) -> dict[str, float]:
    """Axial solid-temperature profiles of a fixed bed heated by the gas against Schumann's
    solution for the same bed (`tidem.results.bed_profiles`): the largest deviation of a bin mean
    over all profile times [K] (`packed_bed_max_deviation_K`) and in % of T_in - T_0
    (`packed_bed_max_deviation_pct`); `preheat_profiles.csv` and run.json's
    `packed_bed_profiles` hold the profiles and the reference bed."""
    p = rec.bed_profiles or {}
    return {"packed_bed_max_deviation_K": p.get("max_deviation_K"),
            "packed_bed_max_deviation_pct": p.get("max_deviation_pct")}
