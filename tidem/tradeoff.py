"""Speed against accuracy, measured: run variants of a scene in parallel (Dask) and report wall
time, particle-steps/s and scalar observables with their error against a reference variant.

A variant is a list of `KEY=VALUE` overrides (the same as `--set`), one value per `--vary`
key (the Cartesian product of all `--vary` lists). Each variant runs in a Dask worker
process, in its own run folder (`variant_NN/`, frames off), with the worker's share of the
cores as Taichi threads. The reference is the variant given by `--reference` (default: the
one that paid most for accuracy: the most time steps, then the longest wall time).

Scalar observables (`scalar_observables`), from each run's run.json and timeseries.csv:
  tube_heat_W        time-mean heat flow from each heated tube over the second half of the run
  tube_mean_alpha    mean heat-transfer coefficient of each heated tube [W/(m^2 K)]
  mean_temperature_K particle mean temperature at the end
  pressure_drop_Pa   time-mean gas pressure drop over the second half of the run
  bed_height_m       99th percentile of particle heights in the last snapshot
  kinetic_energy_J   kinetic energy at the end
  contact_time_s     mean first-contact duration over particles that touched
  GROUP_KEY          every number of run.json observables.reactions[GROUP] (e.g.
                     powder_fraction_sublimated, char_T_mean_K)
Relative error = |value - reference| / |reference| (absolute when the reference is 0).
"""

from __future__ import annotations

import csv
import itertools
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class Variant:
    index: int
    overrides: list[str]

    @property
    def label(self) -> str:
        return ", ".join(self.overrides) or "(scene as is)"


def parse_vary(items: list[str]) -> list[tuple[str, list[str]]]:
    """'KEY=v1,v2' -> (KEY, ['v1', 'v2']); raises ValueError with the fix."""
    out = []
    for item in items:
        key, sep, values = item.partition("=")
        vals = [v.strip() for v in values.split(",") if v.strip()]
        if not sep or not key.strip() or not vals:
            raise ValueError(f"--vary {item!r}: write KEY=VALUE1,VALUE2,... e.g. --vary numerics.dt_fraction=0.1,0.2")
        out.append((key.strip(), vals))
    return out


def variants(vary: list[tuple[str, list[str]]], fixed: list[str] = ()) -> list[Variant]:
    combos = itertools.product(*[[f"{k}={v}" for v in vals] for k, vals in vary]) if vary else [()]
    return [Variant(i, list(fixed) + list(c)) for i, c in enumerate(combos)]


def _series(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        return {}
    return {k: np.array([float(r[k]) if r.get(k) not in (None, "") else np.nan for r in rows]) for k in rows[0]}


def scalar_observables(run_dir: Path) -> dict[str, float]:
    """The registry above, for one finished run folder (only what the run has)."""
    run = json.loads((run_dir / "run.json").read_text())
    series = _series(run_dir / "timeseries.csv") if (run_dir / "timeseries.csv").exists() else {}
    out: dict[str, float] = {}
    if series:
        t = series["time_s"]
        late = t >= 0.5 * t[-1]
        for key, values in series.items():
            if key.startswith("tubes") and key.endswith("_heat_W"):
                out[key.replace("_heat_W", "_heat_W_mean")] = float(np.nanmean(values[late]))
        if "gas_pressure_drop_Pa" in series:
            out["pressure_drop_Pa"] = float(np.nanmean(series["gas_pressure_drop_Pa"][late]))
        if "T_mean_K" in series:
            out["mean_temperature_K"] = float(series["T_mean_K"][-1])
        out["kinetic_energy_J"] = float(series["kinetic_energy_J"][-1])
    obs = run.get("observables", {})
    for row in obs.get("tube_mean_alpha", []):
        out[f"tube{row['tube']}_mean_alpha_W_m2K"] = float(row["mean_alpha_W_m2K"])
    for group, figures in obs.get("reactions", {}).items():
        for key, value in figures.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                out[f"{group}_{key}"] = float(value)
    times = [r["contact_time_s"] for r in obs.get("contact_time", []) if r.get("contact_time_s")]
    if times:
        out["contact_time_s"] = float(np.mean(times))
    snaps = sorted((run_dir / "snapshots").glob("*.vtp"))
    if snaps:
        from tidem.io.vtp import read_vtp

        out["bed_height_m"] = float(np.percentile(read_vtp(snaps[-1])[0][:, 2], 99))
    return out


def run_variant(scene: str, overrides: list[str], out_dir: str, threads: int) -> dict:
    """Run one variant (in a Dask worker process); return its figures or its error."""
    from tidem.model import build_model
    from tidem.run import run
    from tidem.runtime import ensure_taichi
    from tidem.scene.errors import SceneError
    from tidem.scene.load import load

    try:
        loaded = load(scene, overrides)
        ensure_taichi("cpu", loaded.scene.numerics.precision, threads)
        model = build_model(loaded)
    except SceneError as exc:
        return {"status": "bad scene", "message": exc.render()}
    result = run(model, Path(out_dir), progress=False)
    s = result.summary
    return {"status": result.status, "message": result.message, "wall_s": s["wall_s"],
            "particle_steps_per_s": s["particle_steps_per_s"], "steps": s["steps"], "dt_s": s["dt_s"],
            "observables": scalar_observables(Path(out_dir)) if result.status == "finished" else {}}


def run_all(scene: str, todo: list[Variant], out_dir: Path, workers: int | None = None,
            scheduler: str | None = None, on_done=None) -> list[dict]:
    """Run every variant on a Dask cluster (local processes unless `scheduler` is given)."""
    from dask.distributed import Client, LocalCluster, as_completed

    cores = os.cpu_count() or 1
    workers = workers or max(1, min(len(todo), cores))
    threads = max(1, cores // workers)
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    else:
        client = Client(scheduler)
    results: list[dict | None] = [None] * len(todo)
    try:
        futures = {client.submit(run_variant, scene, v.overrides, str(out_dir / f"variant_{v.index:02d}"), threads,
                                 pure=False): v for v in todo}
        for fut in as_completed(futures):
            v = futures[fut]
            res = fut.result()
            res.update(index=v.index, label=v.label, overrides=v.overrides)
            results[v.index] = res
            if on_done is not None:
                on_done(res)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return results


def with_errors(results: list[dict], reference: int | None = None) -> tuple[list[dict], int]:
    """Add `error_<observable>` to each finished result against the reference variant."""
    done = [r for r in results if r["status"] == "finished"]
    if not done:
        return results, -1
    ref = max(done, key=lambda r: (r["steps"], r["wall_s"])) if reference is None else results[reference]
    for r in done:
        for key, value in r["observables"].items():
            base = ref["observables"].get(key)
            if base is None:
                continue
            r.setdefault("errors", {})[key] = abs(value - base) / abs(base) if base != 0 else abs(value)
    return results, ref["index"]


def write_report(results: list[dict], ref: int, out_dir: Path, with_error: bool = True, stem: str | None = None) -> None:
    """tradeoff.csv (or sweep.csv), a Markdown table, and the error-against-time plot."""
    stem = stem or ("tradeoff" if with_error else "sweep")
    keys = sorted({k for r in results for k in r.get("observables", {})})
    head = ["variant", "overrides", "status", "wall_s", "particle_steps_per_s", "dt_s"] + keys
    if with_error:
        head += [f"error_{k}" for k in keys]
    rows = []
    for r in results:
        row = [r["index"], "; ".join(r["overrides"]), r["status"], r.get("wall_s", ""),
               r.get("particle_steps_per_s", ""), r.get("dt_s", "")]
        row += [r.get("observables", {}).get(k, "") for k in keys]
        if with_error:
            row += [r.get("errors", {}).get(k, "") for k in keys]
        rows.append(row)
    with open(out_dir / f"{stem}.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        w.writerows(rows)

    def fmt(v):
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    note = f"\nReference (errors against): variant {ref}.\n" if with_error else "\n"
    (out_dir / f"{stem}.md").write_text("\n".join(lines) + "\n" + note)
    if with_error:
        plot_front(results, keys, out_dir / "tradeoff.png")


def plot_front(results: list[dict], keys: list[str], path: Path) -> None:
    """Relative error of each observable against wall time (log-log): the Pareto front."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    for key in keys:
        pts = [(r["wall_s"], max(r["errors"][key], 1e-16)) for r in results
               if r["status"] == "finished" and key in r.get("errors", {})]
        if pts:
            t, e = zip(*sorted(pts))
            ax.plot(t, e, "o-", label=key)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("relative error against the reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def agree(a: dict, b: dict, tol: float) -> bool:
    """Every observable of both runs agrees within the relative tolerance."""
    keys = set(a) & set(b)
    return bool(keys) and all(abs(a[k] - b[k]) <= tol * max(abs(b[k]), 1e-300) for k in keys)


def halve(scene: str, key: str, start: float, tol: float, out_dir: Path, fixed: list[str] = (),
          max_halvings: int = 6, on_done=None) -> tuple[list[dict], float | None]:
    """Halve `key` from `start` until two successive runs agree within `tol` (source 2's
    step-halving loop); return the runs and the value it converged at (None if it did not)."""
    runs: list[dict] = []
    value = start
    for i in range(max_halvings + 1):
        overrides = list(fixed) + [f"{key}={value!r}"]
        res = run_variant(scene, overrides, str(out_dir / f"halving_{i:02d}"), os.cpu_count() or 1)
        res.update(index=i, label=", ".join(overrides), overrides=overrides)
        runs.append(res)
        if on_done is not None:
            on_done(res)
        if res["status"] != "finished":
            return runs, None
        if i > 0 and agree(res["observables"], runs[-2]["observables"], tol):
            return runs, float(value * 2)
        value = value / 2
    return runs, None
