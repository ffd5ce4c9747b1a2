"""Render a run folder: every snapshot to `frames/frame_NNNNN.png`, then `<scene>.mp4`
(H.264, yuv420p, through the ffmpeg that imageio-ffmpeg ships) and optionally a GIF.

The colour range is fixed for the whole movie: the range stored in run.json (the scene's
`render.range` or its default, see `tidem.render.settings`); for another field than the
run's, or a run.json without a range, it is taken from all snapshots (0 to the largest 99th
percentile for speed, min to max otherwise).
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp
from tidem.render.frames import FIELDS, FrameStyle, field_values, frame_size, render_frame
from tidem.render.meshes import load_meshes


def snapshots(run_dir: Path) -> list[tuple[float, Path]]:
    """(time, file) of every snapshot listed in snapshots.pvd."""
    pvd = Path(run_dir) / "snapshots.pvd"
    if not pvd.exists():
        return []
    root = ET.parse(pvd).getroot()
    return [(float(d.get("timestep")), Path(run_dir) / d.get("file")) for d in root.iter("DataSet")]


def auto_range(field: str, snaps: list[tuple[float, Path]]) -> tuple[float, float]:
    lo, hi = np.inf, -np.inf
    for _t, f in snaps:
        _p, data = read_vtp(f)
        v = field_values(field, data)
        if len(v) == 0:
            continue
        if field == "speed":
            lo, hi = 0.0, max(hi, float(np.percentile(v, 99)))
        else:
            lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    if not np.isfinite(lo) or hi <= lo:
        return (lo if np.isfinite(lo) else 0.0), (lo if np.isfinite(lo) else 0.0) + 1.0
    return lo, hi


def style_for(run_dir: Path, field: str | None = None, clim=None, view: str | None = None,
              slice_thickness: float | None = None) -> FrameStyle:
    """Frame style from the run's run.json (geometry and [render] table) and overrides; the mesh
    walls are read from the run folder here, once for all frames."""
    info = json.loads((Path(run_dir) / "run.json").read_text())
    geo = info["render_geometry"]
    settings = info.get("render", {})
    run_field = settings.get("field") or "speed"
    field = field or run_field
    if field not in FIELDS:
        raise ValueError(f"--field {field}: choose one of {', '.join(FIELDS)}")
    view = view or settings.get("view", "front")
    stored = settings.get("range") if field == run_field else None
    clim = clim or stored or auto_range(field, snapshots(run_dir))
    bounds = tuple(geo["bounds"])
    return FrameStyle(field=field, clim=tuple(clim), colormap=settings.get("colormap") or FIELDS[field][1],
                      size=frame_size(view, bounds, settings.get("height", 720)), view=view, bounds=bounds,
                      tubes=geo["tubes"], periodic=tuple(geo["periodic"]), distributor=geo.get("distributor", []),
                      meshes=load_meshes(run_dir, geo.get("meshes", [])),
                      slice_thickness=slice_thickness if slice_thickness is not None else settings.get("slice"))


def frame_path(run_dir: Path, k: int) -> Path:
    """The PNG of snapshot number k."""
    return Path(run_dir) / "frames" / f"frame_{k:05d}.png"


def clear_frames(run_dir: Path) -> None:
    """Remove the frames of an earlier rendering (and half-written ones of a stopped one)."""
    frames_dir = Path(run_dir) / "frames"
    frames_dir.mkdir(exist_ok=True)
    for old in [*frames_dir.glob("frame_*.png"), *frames_dir.glob(".frame_*.png")]:
        old.unlink()


def render_frames(run_dir: Path, style: FrameStyle, progress=None) -> None:
    """Render every snapshot of a run folder to its frame, replacing earlier frames."""
    clear_frames(run_dir)
    snaps = snapshots(run_dir)
    for k, (t, f) in enumerate(snaps):
        render_frame(f, t, style, frame_path(run_dir, k))
        if progress:
            progress(k + 1, len(snaps))


def write_movie(run_dir: Path, name: str, fps: int = 15, gif: bool = False) -> Path:
    """Encode the frames of a run folder as `<name>.mp4` (and `<name>.gif`); returns the MP4 path."""
    import imageio.v2 as imageio

    run_dir = Path(run_dir)
    paths = sorted((run_dir / "frames").glob("frame_*.png"))
    movie = run_dir / f"{name}.mp4"
    with imageio.get_writer(movie, fps=fps, codec="libx264", pixelformat="yuv420p", macro_block_size=16) as w:
        for p in paths:
            w.append_data(imageio.imread(p))
    if gif:
        imageio.mimsave(run_dir / f"{name}.gif", [imageio.imread(p) for p in paths], duration=1.0 / fps, loop=0)
    return movie
