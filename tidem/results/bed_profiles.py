"""The `packed_bed_profiles` observable: axial solid-temperature profiles of a fixed bed heated
by the gas, against Schumann's solution and source 4's explicit scheme for the same bed.

At each of `output.profile_times` the particles are binned by height above the distributor
(`output.profile_bins` equal bins over the domain height) and their temperatures averaged.
The reference bed is taken from the run itself, so the comparison is like for like:
  ha          = sum_p H_p / V_bed, H_p = h_p pi d_p^2 the gas-particle conductance the run
                uses (the scene's Nusselt correlation at the particle's own voidage and slip);
  rho_c_solid = sum_p m_p c_p / V_bed;   eps = 1 - sum_p V_p / V_bed;
  G c_g       = rho_g U c_g (U the inlet superficial velocity);  rho_c_gas = eps rho_g c_g;
V_bed the domain cross-section times the bed height (distributor to the top of the highest
particle). The reference temperatures are averaged over the same particles as the run's,
each taken at the particle's height. Written as `preheat_profiles.csv` and summarised in
`run.json` (largest deviation from Schumann in K and in % of T_in - T_0).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from tidem.analytic.kruczek import explicit_profiles
from tidem.analytic.packed_bed import PackedBed
from tidem.analytic.schumann import solid_temperature
from tidem.particles.storage_order import scene_order

CSV_NAME = "preheat_profiles.csv"


def profile_times(model) -> list[float]:
    """The scene's profile times, or 8 equal intervals of the run."""
    times = model.scene.output.profile_times
    return sorted(times) if times else [model.t_end * k / 8 for k in range(1, 9)]


def profile_bins(model) -> int:
    """The scene's bin count, or one bin per gas cell along z."""
    from tidem.gas.geometry import gas_grid

    return model.scene.output.profile_bins or gas_grid(model.scene).cells[2]


class ProfileRecorder:
    """Solid temperatures of every particle at the profile times, recorded during the run;
    `state()` gives them for a checkpoint and `saved` puts them back on resume."""

    def __init__(self, model, saved: list | None = None):
        self.model = model
        self.times = profile_times(model)
        self.records: list[tuple[float, np.ndarray]] = [(t, np.asarray(T)) for t, T in saved or []]

    def state(self) -> list:
        return [(t, T.tolist()) for t, T in self.records]

    def due(self, t: float) -> bool:
        k = len(self.records)
        return k < len(self.times) and t >= self.times[k] - 1e-9 * self.model.t_end

    def record(self, solver) -> None:
        self.records.append((solver.t, scene_order(solver.state, solver.state.T.to_numpy())))


def reference_bed(model, solver) -> tuple[PackedBed, float, float]:
    """The bed of the run as Schumann's model sees it, its height [m] and voidage (module docstring)."""
    scene = model.scene
    dom, gas = scene.domain, scene.gas
    z = model.x0[:, 2] - dom.min[2]
    height = float((z + model.radius).max())
    volume = (dom.max[0] - dom.min[0]) * (dom.max[1] - dom.min[1]) * height
    solid = float((4.0 / 3.0 * math.pi * model.radius**3).sum()) / volume
    h_p = solver.state.gH.to_numpy()[: model.capacity]
    t_in = gas.inlet_temperature or scene.heat.initial_temperature
    bed = PackedBed(ha=float(h_p.sum()) / volume, rho_c_solid=float(model.heat_capacity.sum()) / volume,
                    g_c=gas.density * gas.inlet_velocity * gas.heat_capacity,
                    rho_c_gas=(1.0 - solid) * gas.density * gas.heat_capacity,
                    t_in=t_in, t_0=float(model.temperature0[0]))
    return bed, height, 1.0 - solid


def profile_rows(model, solver, recorder: ProfileRecorder) -> tuple[list[dict], dict]:
    """CSV rows (height, time, binned solid temperature, Schumann, explicit scheme) and the summary."""
    if not recorder.records:
        return [], {}
    bed, height, voidage = reference_bed(model, solver)
    dom = model.scene.domain
    z = model.x0[:, 2] - dom.min[2]
    bins = profile_bins(model)
    which = np.minimum((z / (dom.max[2] - dom.min[2]) * bins).astype(int), bins - 1)
    times = [t for t, _ in recorder.records]
    explicit = explicit_profiles(bed, height, times, z, elements=max(200, math.ceil(4 * bed.distance(height))))
    delta_t = bed.t_in - bed.t_0
    rows, worst = [], []
    for k, (t, temps) in enumerate(recorder.records):
        schumann = solid_temperature(bed, z, t)
        dev = 0.0
        for b in range(bins):
            sel = which == b
            if not sel.any():
                continue
            row = dict(height_m=float(z[sel].mean()), time_s=t, T_solid_K=float(temps[sel].mean()),
                       T_schumann_K=float(schumann[sel].mean()), T_explicit_K=float(explicit[k][sel].mean()),
                       particles=int(sel.sum()))
            dev = max(dev, abs(row["T_solid_K"] - row["T_schumann_K"]))
            rows.append(row)
        worst.append(dict(time_s=t, max_deviation_K=dev, max_deviation_pct=100.0 * dev / abs(delta_t)))
    overall = max(w["max_deviation_K"] for w in worst)
    summary = dict(ha_W_m3K=bed.ha, rho_c_solid_J_m3K=bed.rho_c_solid, gas_heat_flux_W_m2K=bed.g_c,
                   voidage=voidage,
                   bed_height_m=height, max_deviation_K=overall, max_deviation_pct=100.0 * overall / abs(delta_t),
                   per_time=worst)
    return rows, summary


def write_csv(path: Path, rows: list[dict]) -> None:
    keys = ["height_m", "time_s", "T_solid_K", "T_schumann_K", "T_explicit_K", "particles"]
    lines = [",".join(keys)] + [",".join(f"{r[k]:.6g}" if isinstance(r[k], float) else str(r[k]) for k in keys)
                                for r in rows]
    Path(path).write_text("\n".join(lines) + "\n")
