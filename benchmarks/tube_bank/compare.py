"""Runs of scenes/tube_bank.toml against the measured tube bank (measured.csv): for each run its
superficial velocity U, the excess velocity U - U_mf over its spheres' Wen-Yu U_mf, each tube's mean
alpha and their mean, the mean's split by route (contact spots, Schluender's gas gap, gas lens, gas
convection), the measured alphas at that excess velocity and the deviation from their mean, and
Molerus, Burschka & Dietz's correlation at the run's U (eps_mf of the measured sand) beside them.

    python benchmarks/tube_bank/compare.py RUN_DIR[=LABEL] ... [--block 0.1] [--csv OUT.csv]

Prints a Markdown table; a run's tubes are averaged over heat.profile_start .. t_end (run.json's
`tube_mean_alpha`), ± the standard error of the tubes' mean from blocks of `--block` seconds
(`benchmarks/tube_heat/compare.py`'s block means of the time series).
"""

from __future__ import annotations

import csv
import importlib.util
import sys
from pathlib import Path

import tidem
from tidem.analytic.fluidized_bed_heat import molerus, wen_yu_minimum_fluidization

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("tube_heat_compare", HERE.parent / "tube_heat" / "compare.py")
tube_heat = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tube_heat)
ROUTES = ("contact_spot", "gas_gap", "gas_lens", "gas")
EPS_MF = 0.46  # the measured sand's voidage at minimum fluidization (measured.csv's sources)


def measured() -> list[dict]:
    with open(HERE / "measured.csv") as f:
        return [{k: (v if k == "source" else float(v or "nan")) for k, v in row.items()} for row in csv.DictReader(f)]


def run_row(run_dir: Path, label: str, points: list[dict], block: float) -> dict:
    """One run's figures against the measured points at its excess velocity."""
    run = tidem.read_run(run_dir)
    scene = run.summary["scene_echo"]
    p = tube_heat.bed_properties(scene)
    u_mf = wen_yu_minimum_fluidization(p["d"], p["rho_p"], p["rho_g"], p["mu"])
    alphas = run.summary["observables"]["tube_mean_alpha"]
    tubes = sorted(k for k in alphas if k.endswith("_mean_alpha_W_m2K"))
    mean = sum(alphas[k] for k in tubes) / len(tubes)
    split = {r: sum(alphas.get(k.replace("mean_alpha", f"{r}_alpha"), 0.0) for k in tubes) / len(tubes) for r in ROUTES}
    t = run.series["time_s"]
    late = t >= scene["heat"].get("profile_start", 0.0)
    series = sum(run.series[f"tubes{k}_alpha_W_m2K"][late] for k in range(len(tubes))) / len(tubes)
    _, se, _ = tube_heat.block_mean(t[late], series, block)
    here = [q for q in points if abs(q["excess_velocity_m_s"] - (p["U"] - u_mf)) < 0.05]
    ref = sum(q["alpha_W_m2K"] for q in here) / len(here) if here else float("nan")
    corr = molerus(p["U"], u_mf, EPS_MF, p["rho_p"], p["c_p"], p["rho_g"], p["mu"], p["k_g"], p["c_g"]).total
    return {"run": label, "U_m_s": p["U"], "excess_m_s": p["U"] - u_mf, "averaged_s": t[late][-1] - t[late][0],
            **{k.split("_mean")[0]: alphas[k] for k in tubes}, "tidem_alpha": mean, "standard_error": se,
            **{f"{r}_share": split[r] / mean for r in ROUTES}, "measured_alpha": ref,
            "measured_points": "; ".join(f"{q['source']} {q['alpha_W_m2K']:.1f}" for q in here),
            "deviation_pct": 100.0 * (mean / ref - 1.0), "molerus_alpha": corr}


def main(argv: list[str]) -> None:
    opts = {"--csv": None, "--block": "0.1"}
    for key in opts:
        if key in argv:
            i = argv.index(key)
            opts[key], argv = argv[i + 1], argv[:i] + argv[i + 2:]
    if not argv:
        sys.exit(__doc__)
    points = measured()
    rows = []
    for arg in argv:
        path, _, label = arg.partition("=")
        rows.append(run_row(Path(path), label or Path(path).name, points, float(opts["--block"])))
    tubes = [k for k in rows[0] if k.startswith("tube")]
    head = (["run", "U, m/s", "U - U_mf, m/s", "averaged, s"] + [f"{t} alpha" for t in tubes]
            + ["tidem alpha (mean)", "contact spot", "gas gap", "gas lens", "gas convection", "measured",
               "deviation", "Molerus"])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        cells = ([r["run"], f"{r['U_m_s']:.2f}", f"{r['excess_m_s']:.2f}", f"{r['averaged_s']:.2f}"]
                 + [f"{r[t]:.1f}" for t in tubes] + [f"{r['tidem_alpha']:.1f} ± {r['standard_error']:.1f}"]
                 + [f"{100 * r[f'{x}_share']:.0f} %" for x in ROUTES]
                 + [f"{r['measured_alpha']:.1f} ({r['measured_points']})", f"{r['deviation_pct']:+.1f} %",
                    f"{r['molerus_alpha']:.1f}"])
        print("| " + " | ".join(cells) + " |")
    if opts["--csv"] is not None:
        with open(opts["--csv"], "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main(sys.argv[1:])
