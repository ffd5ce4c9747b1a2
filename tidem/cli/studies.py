"""`tidem tradeoff` and `tidem sweep`: variants of a scene run in parallel (`tidem.studies.tradeoff`),
their wall time, particle-steps/s and observables tabulated, with errors against a reference
for a tradeoff and step halving until the observables agree (`--halve`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from tidem.cli.common import Sets, app, fail, load_scene, writable
from tidem.scene.errors import SceneError

Varies = Annotated[Optional[list[str]], typer.Option("--vary", help="KEY=V1,V2,... (repeatable; all combinations run)")]
Threads = Annotated[Optional[int], typer.Option(help="Taichi threads per variant (default: the worker's share of the cores)")]
Observables = Annotated[Optional[str], typer.Option(
    "--observables", help="NAME,NAME,... from the observables registry (default: the scene's `observables`)")]


def with_observables(set_: list[str] | None, names: str | None) -> list[str]:
    """--observables a,b as the override observables = ["a", "b"] (validated like the scene)."""
    if names is None:
        return list(set_ or [])
    listed = ", ".join(f'"{n.strip()}"' for n in names.split(",") if n.strip())
    return list(set_ or []) + [f"observables=[{listed}]"]


def variant_line(res: dict) -> None:
    figures = (f"{res['wall_s']:.1f} s, {res['particle_steps_per_s']:.3g} particle-steps/s"
               if res["status"] == "finished" else res["message"].splitlines()[0][:160])
    typer.echo(f"variant {res['index']:>2} [{res['status']}] {res['label']}: {figures}", err=True)


def run_variants(path, vary, set_, out, workers, scheduler, reference, with_error: bool, threads=None) -> None:
    from tidem.studies import tradeoff as tr
    from tidem.studies.seed_groups import seed_groups, write_groups

    loaded = load_scene(path, set_)
    try:
        todo = tr.variants(tr.parse_vary(vary or []), set_ or [])
    except ValueError as exc:
        fail(str(exc), 2)
    if with_error and len(todo) < 2:
        fail("tidem tradeoff: give at least one --vary with two or more values", 2)
    if reference is not None and not 0 <= reference < len(todo):
        fail(f"--reference {reference}: choose a variant from 0 to {len(todo) - 1}", 2)
    from tidem.scene.load import load

    for v in todo:  # every variant must be a valid scene before anything runs
        try:
            load(str(loaded.source), v.overrides)
        except SceneError as exc:
            fail(f"variant {v.index} ({v.label}):\n{exc.render()}", 2)
    out_dir = out or Path("renders") / f"{loaded.name}_{'tradeoff' if with_error else 'sweep'}"
    writable(out_dir, "--out")
    typer.echo(f"tidem: {len(todo)} variants of {loaded.name} -> {out_dir}", err=True)
    results = tr.run_all(str(loaded.source), todo, out_dir, workers, scheduler, on_done=variant_line, threads=threads)
    results, ref = tr.with_errors(results, reference) if with_error else (results, -1)
    tr.write_report(results, ref, out_dir, with_error)
    typer.echo((out_dir / ("tradeoff.md" if with_error else "sweep.md")).read_text())
    grouped = seed_groups(results, ref) if with_error else None
    if grouped is not None:  # seeds varied: each variant's realisations together
        write_groups(*grouped, out_dir)
        typer.echo((out_dir / "tradeoff_groups.md").read_text())


@app.command()
def tradeoff(
    path: Annotated[str, typer.Argument(help="Scene file or shipped scene name")],
    vary: Varies = None,
    set_: Sets = None,
    out: Annotated[Optional[Path], typer.Option(help="Output folder (default renders/<scene>_tradeoff)")] = None,
    workers: Annotated[Optional[int], typer.Option(help="Local Dask worker processes (default: one per core)")] = None,
    scheduler: Annotated[Optional[str], typer.Option(help="Address of an existing Dask scheduler")] = None,
    reference: Annotated[Optional[int], typer.Option(help="Variant the errors are measured against "
                                                     "(default: most steps, then slowest)")] = None,
    halve: Annotated[Optional[str], typer.Option(help="Halve this key until two runs agree within --tol")] = None,
    tol: Annotated[float, typer.Option(help="Relative tolerance of --halve")] = 0.01,
    threads: Threads = None,
    observables: Observables = None,
):
    """Run variants of a scene in parallel: wall time, particle-steps/s and observables against a reference.

    Each observable's error is against the reference variant (tradeoff.csv, tradeoff.md, tradeoff.png). With a
    varied seed (e.g. --vary particles[0].seed=1,2,3) the variants that differ only in it are also taken
    together: each observable's mean, the seeds' range and the deviation from the reference's group, and the
    speed-up (tradeoff_groups.csv, .md, .png)."""
    set_ = with_observables(set_, observables)
    loaded = load_scene(path, set_)
    if not loaded.scene.observables:
        fail(f"tidem tradeoff: {loaded.name} declares no observables to compare; add `observables = [...]` to the "
              "scene or give --observables NAME,... (see docs/scenes.md#observables)", 2)
    if halve is not None:
        halve_until_agreed(path, halve, tol, set_, out, threads)
        return
    run_variants(path, vary, set_, out, workers, scheduler, reference, with_error=True, threads=threads)


@app.command()
def sweep(
    path: Annotated[str, typer.Argument(help="Scene file or shipped scene name")],
    vary: Varies = None,
    set_: Sets = None,
    out: Annotated[Optional[Path], typer.Option(help="Output folder (default renders/<scene>_sweep)")] = None,
    workers: Annotated[Optional[int], typer.Option(help="Local Dask worker processes (default: one per core)")] = None,
    scheduler: Annotated[Optional[str], typer.Option(help="Address of an existing Dask scheduler")] = None,
    threads: Threads = None,
    observables: Observables = None,
):
    """A parameter study: one run folder per variant and one summary table (sweep.csv, sweep.md)."""
    run_variants(path, vary, with_observables(set_, observables), out, workers, scheduler, None, with_error=False,
           threads=threads)


def halve_until_agreed(path, key: str, tol: float, set_, out, threads=None) -> None:
    from tidem.scene.load import load
    from tidem.studies import tradeoff as tr

    loaded = load_scene(path, set_)
    node = loaded.scene.model_dump()
    for part in key.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    if not isinstance(node, (int, float)) or isinstance(node, bool) or node <= 0:
        fail(f"--halve {key}: needs a positive number in the scene (found {node!r})", 2)
    try:
        load(str(loaded.source), list(set_ or []) + [f"{key}={node / 2!r}"])
    except SceneError as exc:
        fail(exc.render(), 2)
    out_dir = out or Path("renders") / f"{loaded.name}_halving"
    writable(out_dir, "--out")
    runs, value = tr.halve(str(loaded.source), key, float(node), tol, out_dir, list(set_ or []), on_done=variant_line,
                          threads=threads)
    tr.write_report(runs, -1, out_dir, with_error=False, stem="halving")
    if value is None:
        fail(f"--halve {key}: successive results did not agree within {tol:g} after {len(runs)} runs; "
              f"see {out_dir}", 3)
    typer.echo(f"converged: {key} = {value:g} (halving once more changed every observable by less than {tol:g})")
