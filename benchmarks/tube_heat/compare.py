"""Tube-to-bed heat transfer of finished bubbling-bed runs against the correlations
(docs/validation.md, "Tube-to-bed heat transfer"): Molerus, Burschka & Dietz (1995) with its
gas- and particle-convective parts, and Zabrodsky's maximum coefficient
(`tidem.analytic.fluidized_bed_heat`).

    python benchmarks/tube_heat/compare.py RUN_DIR [RUN_DIR ...] [--eps-mf 0.45] [--block 0.25]

For each heated tube of each run: the time mean of the instantaneous coefficient
`tubesK_alpha_W_m2K` (particles and gas) from `heat.profile_start` to the end, its standard
error from the means of blocks of `--block` seconds (several bubble periods each, so the blocks
are close to independent), and the share of the heat that went to the gas. The bed's grain
diameter, densities, heat capacities and the superficial velocity come from the run's own
scene (`scene_echo` in run.json); eps_mf is not measured by the run (0.45 for sand, as the
correlation's authors take for Geldart B sands).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import tidem
from tidem.analytic.fluidized_bed_heat import molerus, wen_yu_minimum_fluidization, zabrodsky_maximum


def bed_properties(scene: dict) -> dict:
    """Grain diameter, particle density and heat capacity, gas properties and velocity of a scene (of a scheduled
    inlet velocity the last value, which the run holds to its end)."""
    group = scene["particles"][0]
    mat = scene["materials"][group["material"]]
    gas = scene["gas"]
    u = gas["inlet_velocity"]
    return {"d": group["diameter"]["value"], "rho_p": mat["density"], "c_p": mat["heat_capacity"],
            "rho_g": gas["density"], "mu": gas["viscosity"], "c_g": gas["heat_capacity"],
            "k_g": scene["heat"].get("gas_conductivity", 0.026), "U": u["values"][-1] if isinstance(u, dict) else u}


def block_mean(t: np.ndarray, y: np.ndarray, block: float) -> tuple[float, float, int]:
    """Mean of y over t, and its standard error from the means of consecutive whole blocks of `block` s."""
    index = np.floor((t - t[0]) / block + 1e-9).astype(int)
    n = max(1, int(round((t[-1] - t[0]) / block)))
    means = [y[index == b].mean() for b in range(n) if (index == b).any()]
    se = float(np.std(means, ddof=1) / np.sqrt(len(means))) if len(means) > 1 else float("nan")
    return float(y.mean()), se, len(means)


def compare(run_dir: str, eps_mf: float, block: float) -> list[str]:
    run = tidem.read_run(run_dir)
    scene = run.summary["scene_echo"]
    p = bed_properties(scene)
    u_mf = wen_yu_minimum_fluidization(p["d"], p["rho_p"], p["rho_g"], p["mu"])
    ref = molerus(p["U"], u_mf, eps_mf, p["rho_p"], p["c_p"], p["rho_g"], p["mu"], p["k_g"], p["c_g"])
    a_max = zabrodsky_maximum(p["k_g"], p["rho_p"], p["d"])
    start = scene.get("heat", {}).get("profile_start", 0.0)
    s = run.series
    t = s["time_s"]
    late = t >= start
    lines = [f"{run_dir}: {scene['name']}, d = {p['d'] * 1e3:g} mm, U = {p['U']:g} m/s, U_mf (Wen-Yu) = {u_mf:.3f} m/s "
             f"(U/U_mf = {p['U'] / u_mf:.2f}), averaged over {t[late][0]:.2f}-{t[late][-1]:.2f} s",
             f"  Molerus-Burschka-Dietz (eps_mf {eps_mf}): {ref.total:.0f} W/(m2 K) = particle-convective "
             f"{ref.particle_convective:.0f} + gas-convective {ref.gas_convective:.0f}; Zabrodsky maximum {a_max:.0f}"]
    k = 0
    while f"tubes{k}_alpha_W_m2K" in s:
        alpha = s[f"tubes{k}_alpha_W_m2K"][late]
        mean, se, n = block_mean(t[late], alpha, block)
        heat = s[f"tubes{k}_heat_W"][late].mean()
        gas = s[f"tubes{k}_gas_heat_W"][late].mean() if f"tubes{k}_gas_heat_W" in s else 0.0
        share = gas / (heat + gas)
        lines.append(f"  tube {k}: alpha {mean:.1f} +- {se:.1f} W/(m2 K) ({n} blocks of {block:g} s), gas part "
                     f"{share * mean:.1f} ({100 * share:.0f} %), particles {(1 - share) * mean:.1f}; "
                     f"alpha / Molerus {mean / ref.total:.2f}, / Zabrodsky max {mean / a_max:.2f}")
        k += 1
    return lines


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--eps-mf", type=float, default=0.45)
    ap.add_argument("--block", type=float, default=0.25)
    a = ap.parse_args(argv)
    for r in a.runs:
        print("\n".join(compare(r, a.eps_mf, a.block)))


if __name__ == "__main__":
    main(sys.argv[1:])
