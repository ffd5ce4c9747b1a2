"""What `tidem scene` and the Python API's `tidem.run` share: the checks of a run's options,
Taichi's start, the model, the output folder (writable, room on its disk), the checkpoint to
resume from, and the run itself with the background renderer, then the movie and the plots.

Problems are exceptions whose text is what the CLI prints: `SceneError` (the scene file and its
overrides) and `InputError` (an option, the output folder, a checkpoint), both exit code 2 in
the CLI; `RenderInterrupted` (Ctrl-C while the frames are finished, exit 130). A run's own
outcome (finished, failed, interrupted) is in the `RunResult` that `execute` returns, and
`outcome_message` words a failed or interrupted one. Lines meant for the user (the run's size,
notes, rendering problems) go to the `say` callback.
"""

from __future__ import annotations

import contextlib
import errno
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

ARCHES = ("cpu", "cuda", "vulkan", "auto")
Say = Callable[[str], None]


class InputError(ValueError):
    """Bad input outside the scene file: an option, the output folder, a checkpoint."""


class OutputLost(RuntimeError):
    """The run could not write into its output folder any more (the folder removed, the disk
    full or read-only): `tidem scene` exits 74."""


class RenderInterrupted(KeyboardInterrupt):
    """Ctrl-C while the last frames were being rendered; the finished frames stay."""


def to_stderr(line: str) -> None:
    """The default `say`: one line on stderr."""
    print(line, file=sys.stderr)


def check_options(arch: str, t_end: float | None) -> None:
    """InputError unless `arch` is a backend name and `t_end` (if given) a finite time > 0."""
    if arch not in ARCHES:
        raise InputError(f"--arch {arch}: choose cpu, cuda, vulkan or auto")
    if t_end is not None and not 0 < t_end < float("inf"):
        raise InputError(f"--t-end {t_end}: the end time must be a finite number > 0 s")


def start_taichi(arch: str, precision: str, threads: int | None = None) -> None:
    """Start Taichi on `arch` (`tidem.runtime.startup.ensure_taichi`); InputError where the backend does
    not start here or TIDEM_COMPILE / TIDEM_BIND hold a value it does not know."""
    from tidem.runtime.startup import BackendUnavailable, ensure_taichi

    try:
        ensure_taichi(arch, precision, threads)
    except BackendUnavailable as exc:
        raise InputError(f"--arch {arch}: {exc}; use --arch cpu") from None
    except ValueError as exc:  # TIDEM_COMPILE or TIDEM_BIND
        raise InputError(str(exc)) from None


def writable(out_dir: Path, option: str) -> None:
    """InputError naming the option unless `out_dir` is (or can be made) a folder this process can write in."""
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=out_dir).close()
    except FileExistsError:
        raise InputError(f"{option} {out_dir}: a file of that name exists; give a folder") from None
    except OSError as exc:
        raise InputError(f"{option} {out_dir}: cannot write there ({exc.strerror or exc}); choose another output "
                         f"folder with --out") from None


def fits_on_disk(loaded, model, out_dir: Path, frames: bool) -> None:
    """InputError when the output folder's disk cannot hold what the run will write (`tidem.runner.output_size`)."""
    from tidem.runner.output_size import output_bytes
    from tidem.sim.memory import format_bytes

    n, need = output_bytes(model, frames)
    free = shutil.disk_usage(out_dir).free
    if need > free:
        key = "output.interval" if loaded.scene.output.interval else "output.snapshots"
        raise InputError(
            f"{loaded.source}: {key}: the run would write about {format_bytes(need)} ({n} snapshots"
            f"{' and frames' if frames else ''}), but {out_dir} has {format_bytes(free)} free; write fewer snapshots "
            f"(a smaller output.snapshots or a longer output.interval) or choose another folder with --out")


def load_checkpoint(run_dir: Path, loaded, model, say: Say = to_stderr):
    """The checkpoint in run_dir, checked against the scene; InputError with the reason if not usable."""
    from tidem.runner import checkpoint

    try:
        meta, arrays = checkpoint.load(run_dir)
        checkpoint.check_scene(meta, loaded.raw, model.features.precision)
    except checkpoint.CheckpointError as exc:
        raise InputError(f"--resume {run_dir}: {exc}") from None
    if meta["solver"]["t"] >= model.t_end * (1 - 1e-12):
        raise InputError(f"--resume {run_dir}: the checkpoint is at {checkpoint.describe(meta)}, already at or past "
                         f"the end time {model.t_end:.6g} s; raise numerics.t_end (--t-end) to continue")
    say(f"tidem: resuming from {checkpoint.describe(meta)}")
    return meta, arrays


def scene_notes(scene, prefix: str, say: Say = to_stderr) -> None:
    """Advice on a valid scene: passages too narrow for its coarse-grained parcels (`tidem.scene.passages`),
    temperatures that look like degrees Celsius (`tidem.scene.heat_checks.celsius_notes`)."""
    from tidem.scene.heat_checks import celsius_notes
    from tidem.scene.passages import narrow_passages

    for note in narrow_passages(scene) + celsius_notes(scene):
        say(prefix + note)


@dataclass
class Prepared:
    """A run ready to start: its scene, Model, output folder and the checkpoint to resume from."""

    loaded: object
    model: object
    out_dir: Path
    checkpoint: tuple | None


def prepare(loaded, out: Path | None = None, resume: Path | None = None, smoke: bool = False,
            t_end: float | None = None, arch: str = "cpu", frames: bool = True, say: Say = to_stderr) -> Prepared:
    """Check the options, start Taichi, build the model of a loaded scene and check its output
    folder (`out`, default renders/<scene name>; a resumed run writes into `resume`); says the
    run's size. Raises SceneError or InputError with the CLI's message."""
    from tidem.sim.model import build_model

    check_options(arch, t_end)
    start_taichi(arch, loaded.scene.numerics.precision)
    model = build_model(loaded, smoke=smoke, t_end=t_end)
    if resume is not None and out is not None and Path(out).resolve() != Path(resume).resolve():
        raise InputError(f"--out {out} and --resume {resume}: a resumed run writes into the folder it resumes; drop --out")
    out_dir = Path(resume or out or Path("renders") / model.name)
    writable(out_dir, "--resume" if resume is not None else "--out")
    if resume is None:
        fits_on_disk(loaded, model, out_dir, frames)
    checkpoint = load_checkpoint(out_dir, loaded, model, say) if resume is not None else None
    scene_notes(loaded.scene, "tidem: note: ", say)
    active = int(model.active0.sum())
    say(f"tidem: {model.name}: {active} particles{f' (+{model.capacity - active} to pour)' if model.pours else ''}, "
        f"dt = {model.dt:.3g} s, t_end = {model.t_end:.4g} s -> {out_dir}")
    return Prepared(loaded, model, out_dir, checkpoint)


def renderer(out_dir: Path, render: bool, say: Say = to_stderr):
    """The background renderer of a run (a context manager yielding None when not rendering, or
    where off-screen rendering is unavailable: then says why)."""
    if not render:
        return contextlib.nullcontext()
    from tidem.render.gl import RenderUnavailable, prepare_offscreen

    try:
        prepare_offscreen()
    except RenderUnavailable as exc:
        say(f"tidem: not rendering: {exc}")
        return contextlib.nullcontext()
    from tidem.render.background import BackgroundRenderer

    return BackgroundRenderer(out_dir)


def execute(prepared: Prepared, progress: bool = True, render: bool = True, plots: bool = True, view=None,
            frame_progress=None, say: Say = to_stderr, controls=None):
    """Run a prepared run (`tidem.runner.loop.run`) with the background renderer when `render`, then
    (unless interrupted) the last frames and the movie, and the plots when `plots`; returns the
    run loop's RunResult. `view` is a live view, `controls` the event queue of live controls
    (`tidem.runner.steering.Controls`), `frame_progress(done, total)` is called while the
    last frames render. Ctrl-C while they render raises RenderInterrupted."""
    from tidem.runner.loop import run

    out_dir, name = prepared.out_dir, prepared.model.name
    with renderer(out_dir, render, say) as background:
        try:
            result = run(prepared.model, out_dir, progress=progress, on_snapshot=background, view=view,
                         resume=prepared.checkpoint, controls=controls)
        except OSError as exc:
            inside = bool(exc.filename) and Path(exc.filename).resolve().is_relative_to(out_dir.resolve())
            if not out_dir.is_dir() or inside or exc.errno in (errno.ENOSPC, errno.EROFS, errno.EDQUOT):
                raise OutputLost(f"{out_dir}: the run could not write its output ({exc.strerror or exc}: "
                                 f"{exc.filename}); was the folder removed, or is the disk full or read-only? What "
                                 "was written before is kept where the folder still exists") from None
            raise
        if view is not None:
            view.close()
        s = result.summary
        say(f"{result.status}: {s['steps']} steps in {s['wall_s']:.1f} s "
            f"({s['particle_steps_per_s']:.3g} particle-steps/s); output in {out_dir}")
        if "above_open_top" in s:
            say("tidem: note: " + s["above_open_top"]["note"])
        if result.status == "interrupted":
            return result
        rendered = background is not None and finish_render(background, out_dir, frame_progress, say)
    if plots or rendered:
        movie_and_plots(out_dir, name, say, movie=rendered, plots=plots)
    return result


def finish_render(background, run_dir: Path, frame_progress=None, say: Say = to_stderr) -> bool:
    """Wait for the frames still to render in the background; True when they are all done (the
    movie can be made), False when there was nothing to render or rendering failed (said)."""
    if background.proc is None:
        say(f"tidem: nothing to render: {run_dir} has no snapshots")
        return False
    try:
        error = background.finish(progress=frame_progress)
    except KeyboardInterrupt:
        background.stop()
        raise RenderInterrupted(f"interrupted while rendering; the finished frames are in {run_dir / 'frames'} "
                                f"('tidem render {run_dir}' renders them all)") from None
    if error:
        say(f"tidem: rendering failed: {error}")
        return False
    return True


def movie_and_plots(run_dir: Path, name: str, say: Say = to_stderr, gif=None, movie: bool = True,
                    plots: bool = True) -> None:
    """The movie of the rendered frames (run.json's fps and GIF setting unless `gif` is given)
    and the plots (`tidem.render.plots`); says where they are."""
    import json

    parts = []
    if movie:
        from tidem.render.movie import write_movie

        settings = json.loads((run_dir / "run.json").read_text()).get("render", {})
        path = write_movie(run_dir, name, fps=settings.get("fps", 15),
                           gif=settings.get("gif", False) if gif is None else gif)
        parts.append(f"frames in {run_dir / 'frames'}, movie {path}")
    if plots:
        from tidem.render.plots import plot_timeseries

        written = plot_timeseries(run_dir)
        if written:
            parts.append(f"plots in {written[0].parent}")
    if parts:
        say(", ".join(parts))


def outcome_message(result) -> str | None:
    """What the CLI prints for a failed or an interrupted run (None for a finished one)."""
    if result.status == "failed":
        return f"run stopped: {result.message}\nthe snapshots written before the failure are in {result.out_dir}"
    if result.status == "interrupted":
        return result.message + f"; finished output is in {result.out_dir}"
    return None
