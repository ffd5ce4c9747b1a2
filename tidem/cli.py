"""Command-line interface: `tidem scene`, `tidem scenes`, `tidem check`, `tidem bench`, `tidem render`,
`tidem tradeoff`, `tidem sweep`.

Errors in a scene exit with code 2 and one message listing every problem; a run that goes
wrong (NaN, runaway overlap, capacity) exits with code 3 after saving what it finished;
Ctrl-C exits with 130 after the same; any other exception (a bug) exits with code 70 after one
line naming the log file with its traceback (`main`, `tidem.crash`).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Optional

import typer

from tidem.scene.errors import SceneError

EXIT_CODES = ("Exit codes: 0 done; 2 bad input (the message names the file, the key and the fix); 3 a run stopped "
              "(output so far kept); 70 internal error (a bug: one line names a log file with the traceback, in "
              "$TIDEM_LOG_DIR or the temporary folder's tidem-logs); 130 interrupted (output and checkpoint kept).")
app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help=f"tidem: hot granular flows in Taichi.\n\n{EXIT_CODES}")

Sets = Annotated[Optional[list[str]], typer.Option("--set", help="Override a scene key, e.g. --set outlet.speed=0.003")]


def main() -> None:
    """The `tidem` command: the app, with an unexpected exception turned into one line and a log
    file (exit 70, `tidem.crash`); Ctrl-C keeps its own handling (the run loop saves its output)."""
    try:
        app(prog_name="tidem")
    except Exception as exc:  # the last line of defence: no raw traceback reaches the terminal
        from tidem import crash

        typer.echo(crash.one_line(exc, crash.write_log(exc)), err=True)
        sys.exit(crash.INTERNAL_ERROR)


def _fail(message: str, code: int) -> None:
    typer.echo(message, err=True)
    raise typer.Exit(code)


def _load(path: Optional[str], sets: Optional[list[str]]):
    from tidem.scene.load import load

    try:
        return load(path, sets or [])
    except SceneError as exc:
        _fail(exc.render(), 2)


def _model(loaded, smoke=False, t_end=None):
    from tidem.model import build_model

    try:
        return build_model(loaded, smoke=smoke, t_end=t_end)
    except SceneError as exc:
        _fail(exc.render(), 2)


@app.command()
def scene(
    path: Annotated[Optional[str], typer.Argument(help="Scene file, or the name of a shipped scene (default: the default scene)")] = None,
    out: Annotated[Optional[Path], typer.Option(help="Output folder (default renders/<scene name>)")] = None,
    smoke: Annotated[bool, typer.Option(help="Run only output.smoke_steps steps of the scene (CI)")] = False,
    t_end: Annotated[Optional[float], typer.Option("--t-end", help="End time [s], overrides numerics.t_end")] = None,
    set_: Sets = None,
    arch: Annotated[str, typer.Option(help="Taichi backend: cpu, cuda, vulkan or auto")] = "cpu",
    quiet: Annotated[bool, typer.Option(help="No progress bar")] = False,
    no_render: Annotated[bool, typer.Option("--no-render", help="Skip frames and movie")] = False,
    view: Annotated[bool, typer.Option("--view", help="Show the run in a window while it goes on (space pauses)")] = False,
    resume: Annotated[Optional[Path], typer.Option(help="Continue the run in this folder from its checkpoint.npz")] = None,
):
    """Run a scene: progress bar, snapshots, time series, run.json, frames and an MP4 in the output folder."""
    if arch not in ("cpu", "cuda", "vulkan", "auto"):
        _fail(f"--arch {arch}: choose cpu, cuda, vulkan or auto", 2)
    if t_end is not None and not 0 < t_end < float("inf"):
        _fail(f"--t-end {t_end}: the end time must be a finite number > 0 s", 2)
    loaded = _load(path, set_)
    from tidem.runtime import BackendUnavailable, ensure_taichi

    try:
        ensure_taichi(arch, loaded.scene.numerics.precision)
    except BackendUnavailable as exc:
        _fail(f"--arch {arch}: {exc}; use --arch cpu", 2)
    except ValueError as exc:  # TIDEM_COMPILE
        _fail(str(exc), 2)
    model = _model(loaded, smoke=smoke, t_end=t_end)
    from tidem.run import run

    if resume is not None and out is not None and out.resolve() != resume.resolve():
        _fail(f"--out {out} and --resume {resume}: a resumed run writes into the folder it resumes; drop --out", 2)
    out_dir = resume or out or Path("renders") / model.name
    _writable(out_dir, "--resume" if resume is not None else "--out")
    checkpoint = _checkpoint(resume, loaded, model) if resume is not None else None
    typer.echo(f"tidem: {model.name}: {int(model.active0.sum())} particles"
               f"{f' (+{model.capacity - int(model.active0.sum())} to pour)' if model.pours else ''}, "
               f"dt = {model.dt:.3g} s, t_end = {model.t_end:.4g} s -> {out_dir}", err=True)
    live = _live_view(model) if view else None
    with _background(out_dir, no_render) as background:
        result = run(model, out_dir, progress=not quiet, on_snapshot=background, view=live, resume=checkpoint)
        if live is not None:
            live.close()
        s = result.summary
        typer.echo(f"{result.status}: {s['steps']} steps in {s['wall_s']:.1f} s "
                   f"({s['particle_steps_per_s']:.3g} particle-steps/s); output in {out_dir}", err=True)
        if background is not None and result.status != "interrupted":
            _finish_render(background, out_dir, model.name, quiet)
    if result.status == "failed":
        _fail(f"run stopped: {result.message}\nthe snapshots written before the failure are in {out_dir}", 3)
    if result.status == "interrupted":
        _fail(result.message + f"; finished output is in {out_dir}", 130)


def _writable(out_dir: Path, option: str) -> None:
    """Exit 2 naming the option unless `out_dir` is (or can be made) a folder this process can write in."""
    import tempfile

    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=out_dir).close()
    except FileExistsError:
        _fail(f"{option} {out_dir}: a file of that name exists; give a folder", 2)
    except OSError as exc:
        _fail(f"{option} {out_dir}: cannot write there ({exc.strerror or exc}); choose another output folder "
              f"with --out", 2)


def _checkpoint(run_dir: Path, loaded, model):
    """The checkpoint in run_dir, checked against the scene (exit 2 with the reason if not usable)."""
    from tidem import checkpoint

    try:
        meta, arrays = checkpoint.load(run_dir)
        checkpoint.check_scene(meta, loaded.raw, model.features.precision)
    except checkpoint.CheckpointError as exc:
        _fail(f"--resume {run_dir}: {exc}", 2)
    if meta["solver"]["t"] >= model.t_end * (1 - 1e-12):
        _fail(f"--resume {run_dir}: the checkpoint is at {checkpoint.describe(meta)}, already at or past the end time "
              f"{model.t_end:.6g} s; raise numerics.t_end (--t-end) to continue", 2)
    typer.echo(f"tidem: resuming from {checkpoint.describe(meta)}", err=True)
    return meta, arrays


def _live_view(model):
    """The live view window, or None (with one line saying why) where no display answers."""
    from tidem.render.live import LiveView, display_problem
    from tidem.render.settings import render_settings

    problem = display_problem()
    if problem:
        typer.echo(f"tidem: --view: {problem}; running without the live view", err=True)
        return None
    return LiveView(model, render_settings(model))


def _background(out_dir: Path, no_render: bool):
    """The background renderer of a run (a context manager yielding None when not rendering)."""
    import contextlib

    if no_render:
        return contextlib.nullcontext()
    from tidem.render.gl import RenderUnavailable, prepare_offscreen

    try:
        prepare_offscreen()
    except RenderUnavailable as exc:
        typer.echo(f"tidem: not rendering: {exc}", err=True)
        return contextlib.nullcontext()
    from tidem.render.background import BackgroundRenderer

    return BackgroundRenderer(out_dir)


def _report(quiet: bool):
    """Progress of the frames on stderr (a running count on a terminal, the last line otherwise)."""
    shown = [-1]

    def report(k, n):
        if not quiet and k != shown[0] and (k == n or sys.stderr.isatty()):
            typer.echo(f"\rrendering frame {k}/{n}", nl=k == n, err=True)
            shown[0] = k
    return report


def _finish_render(background, run_dir: Path, name: str, quiet: bool) -> None:
    """Wait for the frames still to render in the background, then the movie and plots."""
    if background.proc is None:
        typer.echo(f"tidem: nothing to render: {run_dir} has no snapshots", err=True)
        return
    try:
        error = background.finish(progress=_report(quiet))
    except KeyboardInterrupt:
        background.stop()
        _fail(f"interrupted while rendering; the finished frames are in {run_dir / 'frames'} "
              f"('tidem render {run_dir}' renders them all)", 130)
    if error:
        typer.echo(f"tidem: rendering failed: {error}", err=True)
        return
    _movie_and_plots(run_dir, name)


def _movie_and_plots(run_dir: Path, name: str, gif=None) -> None:
    import json

    from tidem.render.movie import write_movie
    from tidem.render.plots import plot_timeseries

    settings = json.loads((run_dir / "run.json").read_text()).get("render", {})
    movie = write_movie(run_dir, name, fps=settings.get("fps", 15),
                        gif=settings.get("gif", False) if gif is None else gif)
    plots = plot_timeseries(run_dir)
    typer.echo(f"frames in {run_dir / 'frames'}, movie {movie}"
               f"{f', plots in {plots[0].parent}' if plots else ''}", err=True)


def _render(run_dir: Path, name: str, field=None, clim=None, view=None, slice_thickness=None, gif=None) -> None:
    """Frames and movie of a run folder; a machine without OpenGL gets a message, not a crash."""
    from tidem.render.gl import RenderUnavailable, prepare_offscreen

    try:
        prepare_offscreen()
    except RenderUnavailable as exc:
        _fail(f"tidem render: {exc}", 2)
    from tidem.render.movie import render_frames, style_for

    try:
        style = style_for(run_dir, field, clim, view, slice_thickness)
        render_frames(run_dir, style, progress=_report(False))
    except (ValueError, KeyError) as exc:
        _fail(f"tidem render: {exc.args[0] if exc.args else exc}", 2)
    _movie_and_plots(run_dir, name, gif)


@app.command()
def render(
    run_dir: Annotated[Path, typer.Argument(help="A run folder (with run.json and snapshots.pvd)")],
    field: Annotated[Optional[str], typer.Option(help="speed, temperature, radius, group or contacts")] = None,
    range_: Annotated[Optional[str], typer.Option("--range", help="Colour range LOW,HIGH")] = None,
    view: Annotated[Optional[str], typer.Option(help="front, side, top or iso")] = None,
    slice_: Annotated[Optional[float], typer.Option("--slice", help="Show only a mid-depth slice this thick [m]")] = None,
    gif: Annotated[bool, typer.Option(help="Also write a GIF")] = False,
):
    """Re-render frames and the movie of a finished run from its snapshots, with other settings."""
    import json

    if not (run_dir / "run.json").exists() or not (run_dir / "snapshots.pvd").exists():
        _fail(f"{run_dir}: not a run folder (run.json and snapshots.pvd are missing)", 2)
    try:
        name = json.loads((run_dir / "run.json").read_text()).get("scene", run_dir.name)
    except (ValueError, AttributeError):
        _fail(f"{run_dir / 'run.json'}: not the JSON table a run writes; run the scene again to remake the folder", 2)
    clim = None
    if range_ is not None:
        try:
            lo, hi = (float(v) for v in range_.split(","))
        except ValueError:
            _fail(f"--range {range_}: expected two numbers LOW,HIGH, e.g. --range 0,0.5", 2)
        if hi <= lo:
            _fail(f"--range {range_}: HIGH must exceed LOW", 2)
        clim = (lo, hi)
    if view is not None and view not in ("front", "side", "top", "iso"):
        _fail(f"--view {view}: choose front, side, top or iso", 2)
    from tidem.render.movie import snapshots

    if not snapshots(run_dir):
        _fail(f"{run_dir}: the snapshot collection is empty; nothing to render", 2)
    _render(run_dir, name, field, clim, view, slice_, gif or None)


@app.command()
def scenes():
    """List the shipped scenes with a one-line description and the expected run time."""
    import tomllib

    from tidem.scene.load import DEFAULT_SCENE, shipped_scenes

    for name, path in shipped_scenes().items():
        raw = tomllib.loads(path.read_text())
        mark = " (default)" if name == DEFAULT_SCENE else ""
        typer.echo(f"{name}{mark}\n    {raw.get('description', '')}\n    run time: {raw.get('runtime', 'unknown')}")


@app.command()
def check(
    path: Annotated[Optional[str], typer.Argument(help="Scene file or shipped scene name")] = None,
    set_: Sets = None,
):
    """Validate a scene and print its derived numbers (particles, time steps, kernels, memory); a scene with
    errors, initial overlaps or more than the available memory is refused with exit code 2 (docs/errors.md)."""
    from tidem.memory import format_bytes

    loaded = _load(path, set_)
    model = _model(loaded)
    f = model.features
    mass = float(model.mass.sum())
    sc = model.scales
    lines = [
        f"scene: {model.name} ({loaded.source})",
        f"particles: {int(model.active0.sum())} at start, {model.capacity} in all, total mass {mass:.4g} kg",
        f"diameter: {2 * model.radius.min():.4g} .. {2 * model.radius.max():.4g} m",
        f"contact law: {loaded.scene.contact.model}; rolling resistance: {'on' if f.rolling else 'off'}",
        f"Rayleigh time {sc.rayleigh:.4g} s, contact time {sc.contact:.4g} s, stability limit {sc.limit:.4g} s"
        + (" (does not bind: every particle is fixed)" if model.fixed.all() else ""),
        f"time step: {model.dt:.4g} s ({model.t_end / model.dt:.3g} steps to t_end = {model.t_end:g} s)",
        f"walls: {', '.join(p['name'] for p in model.planes) or 'none'}; tubes: {len(model.tubes)}",
        f"grid: {'x'.join(map(str, model.grid.cells))} cells; neighbour capacity {model.max_neighbors}; skin {model.skin:.3g} m",
        f"kernels: {', '.join(f.kernels())}",
        f"memory (fields): {format_bytes(model.memory_bytes())}, {model.memory_bytes() / model.capacity:.0f} B/particle; "
        f"expected peak of a run {format_bytes(model.peak_memory_bytes())}",
    ]
    typer.echo("\n".join(lines))


@app.command()
def bench(
    sizes: Annotated[Optional[str], typer.Option(help="Comma-separated particle counts "
                                                 "(default 10000,50000,200000; with --render 2000,20000)")] = None,
    precision: Annotated[str, typer.Option(help="float32, float64 or both")] = "both",
    steps: Annotated[int, typer.Option(help="Timed steps per case (scaled down for large N)")] = 2000,
    threads: Annotated[int, typer.Option(help="CPU threads (with --render: llvmpipe threads)")] = 2,
    out: Annotated[Optional[Path], typer.Option(help="Write results as JSON here")] = None,
    bed: Annotated[Optional[Path], typer.Option(help="Use this bed instead: a LAMMPS/LIGGGHTS data file "
                                                "(id type diameter density x y z) or an .npz with 'x'")] = None,
    render: Annotated[bool, typer.Option("--render", help="Frames per second of the frame renderer instead "
                                         "(1280x720, speed and temperature colours)")] = False,
    profile: Annotated[Optional[str], typer.Option(help="Time a scene's steps by phase instead (a shipped scene "
                                                   "or a file; --steps timed steps after --warmup)")] = None,
    warmup: Annotated[int, typer.Option(help="With --profile: untimed steps first (compiles every kernel)")] = 200,
    resume: Annotated[Optional[Path], typer.Option(help="With --profile: start from the checkpoint of this run "
                                                   "folder (e.g. a bubbling bed rather than its first steps)")] = None,
    set_: Sets = None,
):
    """Particle-steps per second on the dense settled bed of the peer benchmark (Hertz + tangential history),
    with --render frames per second of the renderer, with --profile SCENE a scene's time per step by phase."""
    if profile is not None:
        _profile(profile, set_, steps, warmup, threads, out, resume)
        return
    try:
        counts = [int(v) for v in (sizes or ("2000,20000" if render else "10000,50000,200000")).split(",")]
    except ValueError:
        _fail(f"--sizes {sizes}: expected comma-separated particle counts, e.g. --sizes 2000,20000", 2)
    if render:
        from tidem.render.bench import run_render_bench
        from tidem.render.gl import RenderUnavailable

        try:
            run_render_bench(counts, threads, out)
        except RenderUnavailable as exc:
            _fail(f"tidem bench --render: {exc}", 2)
        return
    from tidem.bench import run_matrix

    if precision not in ("float32", "float64", "both"):
        _fail(f"--precision {precision}: choose float32, float64 or both", 2)
    if bed is not None and not bed.exists():
        _fail(f"--bed {bed}: no such file", 2)
    run_matrix(counts, ["float32", "float64"] if precision == "both" else [precision], steps, threads, out, bed)


def _profile(path: str, sets: Optional[list[str]], steps: int, warmup: int, threads: int, out: Optional[Path],
             resume: Optional[Path]) -> None:
    """`tidem bench --profile`: a scene's steps timed by phase (`tidem.bench.profile_scene`)."""
    import json

    from tidem.bench import profile_scene
    from tidem.phases import format_table
    from tidem.runtime import ensure_taichi
    from tidem.solver import RunError

    if steps < 1 or warmup < 0:
        _fail(f"--steps {steps} --warmup {warmup}: need at least one timed step and no negative warm-up", 2)
    loaded = _load(path, sets)
    ensure_taichi("cpu", loaded.scene.numerics.precision, threads)
    model = _model(loaded)
    start = _checkpoint(resume, loaded, model) if resume is not None else None
    try:
        result = profile_scene(loaded, steps, warmup, model, start)
    except SceneError as exc:
        _fail(exc.render(), 2)
    except RunError as exc:
        _fail(f"{loaded.source}: the run failed during profiling: {exc}", 1)
    typer.echo(f"{result['scene']}: {result['particles']} particles, {steps} steps after {warmup} warm-up, "
               f"{threads} threads, {result['particle_steps_per_s']:.3g} particle-steps/s")
    typer.echo(format_table(result["profile"]))
    if out is not None:
        out.write_text(json.dumps(result, indent=2))


Varies = Annotated[Optional[list[str]], typer.Option("--vary", help="KEY=V1,V2,... (repeatable; all combinations run)")]
Threads = Annotated[Optional[int], typer.Option(help="Taichi threads per variant (default: the worker's share of the cores)")]
Observables = Annotated[Optional[str], typer.Option(
    "--observables", help="NAME,NAME,... from the observables registry (default: the scene's `observables`)")]


def _with_observables(set_: list[str] | None, names: str | None) -> list[str]:
    """--observables a,b as the override observables = ["a", "b"] (validated like the scene)."""
    if names is None:
        return list(set_ or [])
    listed = ", ".join(f'"{n.strip()}"' for n in names.split(",") if n.strip())
    return list(set_ or []) + [f"observables=[{listed}]"]


def _variant_line(res: dict) -> None:
    figures = (f"{res['wall_s']:.1f} s, {res['particle_steps_per_s']:.3g} particle-steps/s"
               if res["status"] == "finished" else res["message"].splitlines()[0][:160])
    typer.echo(f"variant {res['index']:>2} [{res['status']}] {res['label']}: {figures}", err=True)


def _sweep(path, vary, set_, out, workers, scheduler, reference, with_error: bool, threads=None) -> None:
    from tidem import tradeoff as tr

    loaded = _load(path, set_)
    try:
        todo = tr.variants(tr.parse_vary(vary or []), set_ or [])
    except ValueError as exc:
        _fail(str(exc), 2)
    if with_error and len(todo) < 2:
        _fail("tidem tradeoff: give at least one --vary with two or more values", 2)
    if reference is not None and not 0 <= reference < len(todo):
        _fail(f"--reference {reference}: choose a variant from 0 to {len(todo) - 1}", 2)
    from tidem.scene.load import load

    for v in todo:  # every variant must be a valid scene before anything runs
        try:
            load(str(loaded.source), v.overrides)
        except SceneError as exc:
            _fail(f"variant {v.index} ({v.label}):\n{exc.render()}", 2)
    out_dir = out or Path("renders") / f"{loaded.name}_{'tradeoff' if with_error else 'sweep'}"
    _writable(out_dir, "--out")
    typer.echo(f"tidem: {len(todo)} variants of {loaded.name} -> {out_dir}", err=True)
    results = tr.run_all(str(loaded.source), todo, out_dir, workers, scheduler, on_done=_variant_line, threads=threads)
    results, ref = tr.with_errors(results, reference) if with_error else (results, -1)
    tr.write_report(results, ref, out_dir, with_error)
    typer.echo((out_dir / ("tradeoff.md" if with_error else "sweep.md")).read_text())


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
    """Run variants of a scene in parallel and report wall time, particle-steps/s and observables with their
    error against the reference variant (tradeoff.csv, tradeoff.md, tradeoff.png)."""
    set_ = _with_observables(set_, observables)
    loaded = _load(path, set_)
    if not loaded.scene.observables:
        _fail(f"tidem tradeoff: {loaded.name} declares no observables to compare; add `observables = [...]` to the "
              "scene or give --observables NAME,... (see docs/scenes.md#observables)", 2)
    if halve is not None:
        _halve(path, halve, tol, set_, out, threads)
        return
    _sweep(path, vary, set_, out, workers, scheduler, reference, with_error=True, threads=threads)


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
    _sweep(path, vary, _with_observables(set_, observables), out, workers, scheduler, None, with_error=False,
           threads=threads)


def _halve(path, key: str, tol: float, set_, out, threads=None) -> None:
    from tidem import tradeoff as tr
    from tidem.scene.load import load

    loaded = _load(path, set_)
    node = loaded.scene.model_dump()
    for part in key.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    if not isinstance(node, (int, float)) or isinstance(node, bool) or node <= 0:
        _fail(f"--halve {key}: needs a positive number in the scene (found {node!r})", 2)
    try:
        load(str(loaded.source), list(set_ or []) + [f"{key}={node / 2!r}"])
    except SceneError as exc:
        _fail(exc.render(), 2)
    out_dir = out or Path("renders") / f"{loaded.name}_halving"
    _writable(out_dir, "--out")
    runs, value = tr.halve(str(loaded.source), key, float(node), tol, out_dir, list(set_ or []), on_done=_variant_line,
                          threads=threads)
    tr.write_report(runs, -1, out_dir, with_error=False, stem="halving")
    if value is None:
        _fail(f"--halve {key}: successive results did not agree within {tol:g} after {len(runs)} runs; "
              f"see {out_dir}", 3)
    typer.echo(f"converged: {key} = {value:g} (halving once more changed every observable by less than {tol:g})")
