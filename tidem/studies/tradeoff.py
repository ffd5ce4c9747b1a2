"""Speed against accuracy, measured: run variants of a scene in parallel (Dask) and report wall
time, particle-steps/s and scalar observables with their error against a reference variant.

A variant is a list of `KEY=VALUE` overrides (the same as `--set`), one value per `--vary`
key (the Cartesian product of all `--vary` lists). Each variant runs in a Dask worker
process, in its own run folder (`variant_NN/`, frames off), with the worker's share of the
cores as Taichi threads. The reference is the variant given by `--reference` (default: the
one that paid most for accuracy: the most time steps, then the longest wall time).

Observables: the scene's declared ones (`observables = [...]`, or `--observables` as an
override), computed by each run from the registry in `tidem.results.observables` and read back from
its run.json, one column per value (e.g. `bed_height_m`, `tubes1_heat_W`).
Reaction figures (run.json `reactions`) join as GROUP_KEY columns (e.g.
powder_fraction_sublimated, char_T_mean_K).
Relative error = |value - reference| / |reference| (absolute when the reference is 0).
"""

from __future__ import annotations

import csv
import itertools
import os
from dataclasses import dataclass
from pathlib import Path

from tidem.results.observables import flatten


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


def run_variant(scene: str, overrides: list[str], out_dir: str, threads: int) -> dict:
    """Run one variant (in a Dask worker process); return its figures or its error."""
    from tidem.runner.loop import run
    from tidem.runtime.startup import restart
    from tidem.scene.errors import SceneError
    from tidem.scene.load import load
    from tidem.sim.model import build_model

    try:
        loaded = load(scene, overrides)
        restart("cpu", loaded.scene.numerics.precision, threads)  # a fresh program: a variant of a structure
        # run before (another seed, a rerun of the study) finds its kernels in the cache
        model = build_model(loaded)
    except SceneError as exc:
        return {"status": "bad scene", "message": exc.render()}
    result = run(model, Path(out_dir), progress=False)
    s = result.summary
    return {"status": result.status, "message": result.message, "wall_s": s["wall_s"],
            "particle_steps_per_s": s["particle_steps_per_s"], "steps": s["steps"], "dt_s": s["dt_s"],
            "observables": flatten(s.get("observables", {})) if result.status == "finished" else {}}


def run_all(scene: str, todo: list[Variant], out_dir: Path, workers: int | None = None,
            scheduler: str | None = None, on_done=None, threads: int | None = None) -> list[dict]:
    """Run every variant on a Dask cluster (local processes unless `scheduler` is given), each
    with `threads` Taichi threads (default: the worker's share of the cores)."""
    from dask.distributed import Client, LocalCluster, as_completed

    cores = os.cpu_count() or 1
    workers = workers or max(1, min(len(todo), cores))
    threads = threads or max(1, cores // workers)
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
          max_halvings: int = 6, on_done=None, threads: int | None = None) -> tuple[list[dict], float | None]:
    """Halve `key` from `start` until two successive runs agree within `tol` (source 2's
    step-halving loop); return the runs and the value it converged at (None if it did not)."""
    runs: list[dict] = []
    value = start
    for i in range(max_halvings + 1):
        overrides = list(fixed) + [f"{key}={value!r}"]
        res = run_variant(scene, overrides, str(out_dir / f"halving_{i:02d}"), threads or os.cpu_count() or 1)
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
