"""Command-line interface: `tidem scene`, `tidem scenes`, `tidem check`, `tidem bench`, `tidem render`,
`tidem tradeoff`, `tidem sweep`.

Errors in a scene exit with code 2 and one message listing every problem; a run that goes
wrong (NaN, runaway overlap, capacity) exits with code 3 after saving what it finished;
Ctrl-C exits with 130 after the same; any other exception (a bug) exits with code 70 after one
line naming the log file with its traceback (`main`, `tidem.cli.crash`).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Optional

import typer

from tidem.cli.common import Sets, app, build_or_exit, fail, load_scene, start_taichi
from tidem.scene.errors import SceneError

SERVE_PORT = 8050  # `--serve` alone


def serve_port_given(args: list[str]) -> list[str]:
    """The arguments with `--serve` followed by no port given SERVE_PORT (a Typer option has no optional value)."""
    return [f"--serve={SERVE_PORT}" if a == "--serve" and (i + 1 == len(args) or not args[i + 1].isdigit()) else a
            for i, a in enumerate(args)]


def main() -> None:
    """The `tidem` command: the app, with an unexpected exception turned into one line and a log
    file (exit 70, `tidem.cli.crash`); Ctrl-C keeps its own handling (the run loop saves its output)."""
    try:
        app(args=serve_port_given(sys.argv[1:]), prog_name="tidem")
    except Exception as exc:  # the last line of defence: no raw traceback reaches the terminal
        from tidem.cli import crash

        typer.echo(crash.one_line(exc, crash.write_log(exc)), err=True)
        sys.exit(crash.INTERNAL_ERROR)


@app.command()
def scene(
    path: Annotated[Optional[str], typer.Argument(help="Scene file, or the name of a shipped scene (default: the default scene)")] = None,
    out: Annotated[Optional[Path], typer.Option(help="Output folder (default renders/<scene name>)")] = None,
    smoke: Annotated[bool, typer.Option(help="Run only output.smoke_steps steps of the scene (CI)")] = False,
    t_end: Annotated[Optional[float], typer.Option("--t-end", help="End time in s, overrides numerics.t_end")] = None,
    set_: Sets = None,
    arch: Annotated[str, typer.Option(help="Taichi backend: cpu, cuda, vulkan or auto")] = "cpu",
    quiet: Annotated[bool, typer.Option(help="No progress bar")] = False,
    no_render: Annotated[bool, typer.Option("--no-render", help="Skip frames and movie")] = False,
    view: Annotated[bool, typer.Option("--view", help="Show and steer the run in a window while it goes on "
                                                   "(space pauses; sliders and keys: docs/steering.md)")] = False,
    serve: Annotated[Optional[int], typer.Option(
        "--serve", metavar="[PORT]", help=f"Serve the live view and its controls to a browser on localhost:PORT "
                                          f"(--serve alone: {SERVE_PORT}; 0: a free port); for a machine without a "
                                          "display")] = None,
    resume: Annotated[Optional[Path], typer.Option(help="Continue the run in this folder from its checkpoint.npz")] = None,
):
    """Run a scene: progress bar, snapshots, time series, run.json, frames and an MP4 in the output folder."""
    from tidem.runner import launch
    from tidem.scene.load import load

    try:
        launch.check_options(arch, t_end)
        loaded = load(path, set_ or [])
        prepared = launch.prepare(loaded, out, resume, smoke, t_end, arch, frames=not no_render, say=_say)
    except SceneError as exc:
        fail(exc.render(), 2)
    except launch.InputError as exc:
        fail(str(exc), 2)
    views = ([_live_view(prepared.model)] if view else []) + ([_served_view(prepared.model, serve)] if serve is not None
                                                             else [])
    views = [v for v in views if v is not None]
    if len(views) > 1:
        from tidem.render.serve import Views

        views = [Views(views)]
    live = views[0] if views else None
    try:
        result = launch.execute(prepared, progress=not quiet, render=not no_render, view=live,
                                frame_progress=_report(quiet), say=_say)
    except launch.RenderInterrupted as exc:
        fail(str(exc), 130)
    except launch.OutputLost as exc:
        fail(str(exc), 74)
    message = launch.outcome_message(result)
    if message is not None:
        fail(message, 3 if result.status == "failed" else 130)


def _say(line: str) -> None:
    typer.echo(line, err=True)


def _live_view(model):
    """The live view window, or None (with one line saying why) where no display answers."""
    from tidem.render.live import LiveView, display_problem
    from tidem.render.settings import render_settings

    problem = display_problem()
    if problem is None:
        try:
            return LiveView(model, render_settings(model))
        except RuntimeError as exc:  # Taichi's window creation (the display went away, no GL visual)
            problem = f"the window could not be opened ({str(exc).splitlines()[0][:120]})"
    typer.echo(f"tidem: --view: {problem}; running without the live view", err=True)
    return None


def _served_view(model, port: int):
    """The browser view on localhost:`port` (says its address), or exit 2 where the port cannot be served."""
    from tidem.render.serve import BrowserView, ServeError
    from tidem.render.settings import render_settings

    if not 0 <= port <= 65535:
        fail(f"--serve {port}: a port is 0-65535 (0: a free one)", 2)
    try:
        view = BrowserView(model, render_settings(model), port)
    except ServeError as exc:
        fail(str(exc), 2)
    typer.echo(f"tidem: serving the live view at {view.url} (over SSH: ssh -L {view.port}:localhost:{view.port} HOST)",
               err=True)
    return view


def _report(quiet: bool):
    """Progress of the frames on stderr (a running count on a terminal, the last line otherwise)."""
    shown = [-1]

    def report(k, n):
        if not quiet and k != shown[0] and (k == n or sys.stderr.isatty()):
            typer.echo(f"\rrendering frame {k}/{n}", nl=k == n, err=True)
            shown[0] = k
    return report


def _render(run_dir: Path, name: str, field=None, clim=None, view=None, slice_thickness=None, gif=None) -> None:
    """Frames and movie of a run folder; a machine without OpenGL gets a message, not a crash."""
    from tidem.render.gl import RenderUnavailable, prepare_offscreen
    from tidem.runner.launch import movie_and_plots

    try:
        prepare_offscreen()
    except RenderUnavailable as exc:
        fail(f"tidem render: {exc}", 2)
    from tidem.render.movie import render_frames, style_for

    try:
        style = style_for(run_dir, field, clim, view, slice_thickness)
        render_frames(run_dir, style, progress=_report(False))
    except (ValueError, KeyError) as exc:
        fail(f"tidem render: {exc.args[0] if exc.args else exc}", 2)
    movie_and_plots(run_dir, name, _say, gif)


@app.command()
def render(
    run_dir: Annotated[Path, typer.Argument(help="A run folder (with run.json and snapshots.pvd)")],
    field: Annotated[Optional[str], typer.Option(help="speed, temperature, radius, group or contacts")] = None,
    range_: Annotated[Optional[str], typer.Option("--range", help="Colour range LOW,HIGH")] = None,
    view: Annotated[Optional[str], typer.Option(help="front, side, top or iso")] = None,
    slice_: Annotated[Optional[float], typer.Option("--slice", help="Show only a mid-depth slice this thick, in m")] = None,
    gif: Annotated[bool, typer.Option(help="Also write a GIF")] = False,
):
    """Re-render frames and the movie of a finished run from its snapshots, with other settings."""
    import json

    if not (run_dir / "run.json").exists() or not (run_dir / "snapshots.pvd").exists():
        fail(f"{run_dir}: not a run folder (run.json and snapshots.pvd are missing)", 2)
    try:
        name = json.loads((run_dir / "run.json").read_text()).get("scene", run_dir.name)
    except (ValueError, AttributeError):
        fail(f"{run_dir / 'run.json'}: not the JSON table a run writes; run the scene again to remake the folder", 2)
    clim = None
    if range_ is not None:
        try:
            lo, hi = (float(v) for v in range_.split(","))
        except ValueError:
            fail(f"--range {range_}: expected two numbers LOW,HIGH, e.g. --range 0,0.5", 2)
        if hi <= lo:
            fail(f"--range {range_}: HIGH must exceed LOW", 2)
        clim = (lo, hi)
    if view is not None and view not in ("front", "side", "top", "iso"):
        fail(f"--view {view}: choose front, side, top or iso", 2)
    from tidem.render.movie import snapshots

    if not snapshots(run_dir):
        fail(f"{run_dir}: the snapshot collection is empty; nothing to render", 2)
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
    """Validate a scene and print its derived numbers (particles, time steps, kernels, memory).

    A scene with errors, initial overlaps or more than the available memory is refused with exit code 2 (docs/errors.md)."""
    import numpy as np

    from tidem.runner.check_report import (cut_walls_text, gas_line, gas_notes, mesh_convection_lines, output_notes,
                                           parcel_restitution_text)
    from tidem.runner.output_size import output_bytes
    from tidem.scene.schedule import scheduled_keys, summary_line
    from tidem.scene.schema import MAX_CONDUCTION_INTERVAL
    from tidem.sim.memory import format_bytes
    from tidem.walls.mesh_walls import report_lines

    loaded = load_scene(path, set_)
    model = build_or_exit(loaded)
    f = model.features
    mass = float(model.mass.sum())
    snapshots, with_frames = output_bytes(model, frames=True)
    without = output_bytes(model, frames=False)[1]
    sc = model.scales
    lines = [
        f"scene: {model.name} ({loaded.source})",
        f"particles: {int(model.active0.sum())} at start, {model.capacity} in all, total mass {mass:.4g} kg",
        *[f"particles[{g}]: {n} lattice sites left empty in pockets a grain could not reach from the "
          "domain's top (skip_pockets)" for g, n in model.pocket_sites.items()],
        f"{'parcel diameter' if f.coarse_grain else 'diameter'}: {2 * model.radius.min():.4g} .. "
        f"{2 * model.radius.max():.4g} m" + (f" (grains {2 * float((model.radius / model.coarse_grain).min()):.4g} .. "
                                               f"{2 * float((model.radius / model.coarse_grain).max()):.4g} m)"
                                               if f.coarse_grain else ""),
        *([f"coarse graining: parcels of k^3 grains, k = {', '.join(f'{k:g}' for k in np.unique(model.coarse_grain))}; "
           f"{float((model.coarse_grain**3).sum()):.0f} grains"] if f.coarse_grain else []),
        f"contact law: {loaded.scene.contact.model}; rolling resistance: {'on' if f.rolling else 'off'}"
        + parcel_restitution_text(loaded.scene),
        f"Rayleigh time {sc.rayleigh:.4g} s, contact time {sc.contact:.4g} s, stability limit {sc.limit:.4g} s"
        + (" (does not bind: every particle is fixed)" if model.fixed.all() else "")
        + ("" if f.contacts else " (does not bind: no contacts)"),
        f"time step: {model.dt:.4g} s ({model.t_end / model.dt:.3g} steps to t_end = {model.t_end:g} s); "
        f"precision: {loaded.scene.numerics.precision}",
        *([f"conduction: every {loaded.scene.heat.conduction_interval} step(s); explicit limit {model.thermal_limit:.4g} s "
           f"(heat.conduction_interval up to {min(int(model.thermal_limit / model.dt), MAX_CONDUCTION_INTERVAL)})"] if model.thermal_limit else []),
        f"walls: {', '.join(p['name'] for p in model.planes) or 'none'}; tubes: {len(model.tubes)}",
        *[summary_line(key, plan) for key, plan in scheduled_keys(loaded.scene)],
        *([gas_line(model)] if f.gas else []),
        *report_lines(model.meshes, model.mesh_table, 2 * float(model.radius.min())),
        *(model.gas_cut.report_lines(cut_walls_text(model)) if model.gas_cut is not None else []),
        *(mesh_convection_lines(model) if f.gas and f.heat else []),
        (f"grid: {'x'.join(map(str, model.grid.cells))} cells; neighbour capacity {model.max_neighbors}; "
         f"skin {model.skin:.3g} m" if f.contacts else "grid: none (no contacts, no neighbour search)"),
        f"kernels: {', '.join(f.kernels())}",
        f"memory (fields): {format_bytes(model.memory_bytes())}, {model.memory_bytes() / model.capacity:.0f} B/particle; "
        f"expected peak of a run {format_bytes(model.peak_memory_bytes())}",
        f"output: {snapshots} snapshots, about {format_bytes(with_frames)} on disk with frames "
        f"({format_bytes(without)} with --no-render)",
    ]
    if f.gas:
        lines += gas_notes(model)
    lines += output_notes(model, snapshots)
    typer.echo("\n".join(lines))
    from tidem.runner.launch import scene_notes

    scene_notes(loaded.scene, "note: ", typer.echo)


@app.command()
def bench(
    sizes: Annotated[Optional[str], typer.Option(help="Comma-separated particle counts "
                                                 "(default 10000,50000,200000; with --render 2000,20000)")] = None,
    precision: Annotated[str, typer.Option(help="float32, float64, mixed (float32 contact history), both "
                                                "(float32 and float64) or all")] = "both",
    steps: Annotated[int, typer.Option(help="Timed steps per case (scaled down for large N)")] = 2000,
    threads: Annotated[int, typer.Option(help="CPU threads (with --render: llvmpipe threads)")] = 2,
    arch: Annotated[str, typer.Option(help="Taichi backend of the steps: cpu, cuda or vulkan")] = "cpu",
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
    fused: Annotated[bool, typer.Option("--fused", help="With --profile: the contact passes and the kick in one "
                                        "launch, as a run takes them (default: apart, to tell them apart)")] = False,
    set_: Sets = None,
):
    """Particle-steps per second on the peer benchmark's settled bed; --render, --profile SCENE.

    The bed is dense and settled (Hertz with tangential history); --render: the renderer's frames per second.

    --profile SCENE: a scene's time per step by phase."""
    if arch not in ("cpu", "cuda", "vulkan"):
        fail(f"--arch {arch}: choose cpu, cuda or vulkan", 2)
    if profile is not None:
        _profile(profile, set_, steps, warmup, threads, out, resume, arch, fused)
        return
    try:
        counts = [int(v) for v in (sizes or ("2000,20000" if render else "10000,50000,200000")).split(",")]
    except ValueError:
        fail(f"--sizes {sizes}: expected comma-separated particle counts, e.g. --sizes 2000,20000", 2)
    if render:
        from tidem.render.bench import run_render_bench
        from tidem.render.gl import RenderUnavailable

        try:
            run_render_bench(counts, threads, out)
        except RenderUnavailable as exc:
            fail(f"tidem bench --render: {exc}", 2)
        return
    from tidem.studies.bench import run_matrix

    runs = {"float32": ["float32"], "float64": ["float64"], "mixed": ["mixed"], "both": ["float32", "float64"],
            "all": ["float32", "mixed", "float64"]}
    if precision not in runs:
        fail(f"--precision {precision}: choose float32, float64, mixed, both or all", 2)
    if bed is not None and not bed.exists():
        fail(f"--bed {bed}: no such file", 2)
    run_matrix(counts, runs[precision], steps, threads, out, bed, arch)


def _profile(path: str, sets: Optional[list[str]], steps: int, warmup: int, threads: int, out: Optional[Path],
             resume: Optional[Path], arch: str, fused: bool = False) -> None:
    """`tidem bench --profile`: a scene's steps timed by phase (`tidem.studies.bench.profile_scene`)."""
    import json

    from tidem.runtime.phases import format_table
    from tidem.sim.solver import RunError
    from tidem.studies.bench import profile_scene

    if steps < 1 or warmup < 0:
        fail(f"--steps {steps} --warmup {warmup}: need at least one timed step and no negative warm-up", 2)
    loaded = load_scene(path, sets)
    start_taichi(arch, loaded.scene.numerics.precision, threads)
    model = build_or_exit(loaded)
    start = None
    if resume is not None:
        from tidem.runner.launch import InputError, load_checkpoint

        try:
            start = load_checkpoint(resume, loaded, model, _say)
        except InputError as exc:
            fail(str(exc), 2)
    try:
        result = profile_scene(loaded, steps, warmup, model, start, split=not fused)
    except SceneError as exc:
        fail(exc.render(), 2)
    except RunError as exc:
        fail(f"{loaded.source}: the run failed during profiling: {exc}", 1)
    where = f"{threads} threads" if arch == "cpu" else arch
    typer.echo(f"{result['scene']}: {result['particles']} particles, {steps} steps after {warmup} warm-up, "
               f"{where}, {result['particle_steps_per_s']:.3g} particle-steps/s")
    typer.echo(format_table(result["profile"]))
    if out is not None:
        out.write_text(json.dumps(result, indent=2))


from tidem.cli import studies  # noqa: E402,F401  tradeoff and sweep, registered last to be listed after the others
