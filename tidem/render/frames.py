"""Frames: one PNG per snapshot, particles as shaded spheres coloured by a field.

Spheres are point sprites (VTK's point-Gaussian mapper with a per-point scale array and
`render_points_as_spheres`), about 10x faster than glyph meshes on a CPU renderer and
indistinguishable at video resolution. Particles under half a pixel in radius (fine powders,
the 10 um grains of the plasma scene) are drawn two pixels in radius so that they show; larger
ones keep their size. One colour
range is used for the whole movie, so colours mean the same in every frame. Tubes are drawn as cylinders, triangle-mesh
walls as surfaces with their front half cut away (`tidem.render.meshes`), the domain as an outline, and the simulated
time as a stamp.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from dataclasses import field as dc_field
from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp
from tidem.render.gl import prepare_offscreen
from tidem.render.meshes import add_meshes

FIELDS = {
    "speed": ("Speed [m/s]", "viridis"),
    "temperature": ("Temperature [K]", "inferno"),
    "radius": ("Radius [m]", "cividis"),
    "group": ("Group", "tab10"),
    "contacts": ("Contacts", "magma"),
}


@dataclass
class FrameStyle:
    """What a frame shows and how; built from the scene's [render] table and CLI options."""

    field: str
    clim: tuple[float, float]
    colormap: str
    size: tuple[int, int]
    view: str
    bounds: tuple[float, ...]  # xmin, xmax, ymin, ymax, zmin, zmax
    tubes: list[dict]
    periodic: tuple[bool, bool, bool] = (False, False, False)
    slice_thickness: float | None = None
    distributor: list[dict] = dc_field(default_factory=list)  # gas inlet parts: x, y ranges [m], velocity [m/s]
    meshes: list = dc_field(default_factory=list)  # tidem.walls.mesh_walls.MeshWall at t = 0 (tidem.render.meshes.load_meshes)


def field_values(field: str, data: dict) -> np.ndarray:
    if field == "speed":
        return np.linalg.norm(data["velocity"], axis=1)
    if field not in data:
        raise KeyError(f"the snapshots have no '{field}' array; available: speed, {', '.join(sorted(data))}")
    return np.asarray(data[field], dtype=float)


def distributor_boxes(style: FrameStyle) -> list[dict]:
    """A bar under the floor for each part of the gas distributor: grey for the background
    inflow, dark blue for nozzles faster than it, light for closed parts (velocity 0); 2 % of
    the domain height thick."""
    lo, hi = style.bounds[0::2], style.bounds[1::2]
    thick = 0.02 * (hi[2] - lo[2])
    base = min((p["velocity"] for p in style.distributor if p.get("background")), default=0.0)
    out = []
    for p in style.distributor:
        x = p.get("x") or (lo[0], hi[0])
        y = p.get("y") or (lo[1], hi[1])
        colour = "#b0b0b0" if p.get("background") else ("#1f3b8f" if p["velocity"] > base else "#e6e6e6")
        out.append({"bounds": (x[0], x[1], y[0], y[1], lo[2] - thick, lo[2]), "colour": colour})
    return out


def bar_labels(clim: tuple[float, float]) -> int:
    """Number of colour-bar labels: one per whole unit for spans of 2-10 units (a 5 K range
    reads 293, 294, ..., 298), five otherwise."""
    span = clim[1] - clim[0]
    whole = round(span)
    return whole + 1 if 2 <= whole <= 10 and abs(span - whole) < 1e-6 * max(1.0, span) else 5


def bar_format(clim: tuple[float, float]) -> str:
    """Colour-bar label format: as many decimals as tell neighbouring labels apart (298 ... 500 K,
    293.2, 293.6 ... 295.0 K, 0.00 ... 0.04 m/s); three significant digits for magnitudes below
    1e-3 or from 1e5 on."""
    top = max(abs(clim[0]), abs(clim[1]))
    step = (clim[1] - clim[0]) / max(bar_labels(clim) - 1, 1)
    if top < 1e-3 or top >= 1e5 or step <= 0:
        return "%.3g"
    return f"%.{max(0, -math.floor(math.log10(step)))}f"


def view_extent(view: str, bounds) -> tuple[float, float]:
    """Width and height of the domain as the camera sees it [m]."""
    return {"front": (bounds[1] - bounds[0], bounds[5] - bounds[4]),
            "side": (bounds[3] - bounds[2], bounds[5] - bounds[4]),
            "top": (bounds[1] - bounds[0], bounds[3] - bounds[2])}.get(view, (1.6, 1.0))


def pixel_size(style: "FrameStyle") -> float:
    """About one pixel of the frame in metres (the domain fills the height, or the width left
    beside the colour bar)."""
    if style.view not in ("front", "side", "top"):
        return 0.0
    ext = view_extent(style.view, style.bounds)
    return max(ext[0] / max(style.size[0] - 240, 1), ext[1] / style.size[1])


def frame_size(view: str, bounds, height: int = 720) -> tuple[int, int]:
    """Window size that fits the domain's projection, plus room for the colour bar (multiples of 16)."""
    ext = view_extent(view, bounds)
    aspect = ext[0] / ext[1]
    width = int(np.clip(height * aspect * 1.1 + 240, 480, 1920))
    return (width + 15) // 16 * 16, (height + 15) // 16 * 16


def tube_colour(tube: dict, style: FrameStyle):
    """A tube with a set temperature takes the colour map's colour for it (clipped to the
    range) when frames show temperature; others are grey."""
    if style.field != "temperature" or tube.get("T") is None:
        return "#9a9a9a"
    import matplotlib

    low, high = style.clim
    frac = min(max((tube["T"] - low) / (high - low), 0.0), 1.0)
    return matplotlib.colormaps[style.colormap](frac)[:3]


def tube_images(tube: dict, lo, hi, periodic) -> list[np.ndarray]:
    """Tube centre and its periodic images that reach into the box."""
    out = [np.array(tube["c"], dtype=float)]
    for a in range(3):
        if periodic[a] and tube["mask"][a]:
            length = hi[a] - lo[a]
            out += [c + s * length * np.eye(3)[a] for c in list(out) for s in (-1, 1)
                    if lo[a] - tube["r"] < c[a] + s * length < hi[a] + tube["r"]]
    return out


def place_camera(pl, style: FrameStyle) -> None:
    """Parallel projection that fits the domain in the left 80 % of the frame (the colour bar
    takes the rest)."""
    lo, hi = np.array(style.bounds[0::2]), np.array(style.bounds[1::2])
    centre = 0.5 * (lo + hi)
    axes = {"front": (0, 2, 1, -1), "side": (1, 2, 0, 1), "top": (0, 1, 2, 1)}
    if style.view not in axes:
        pl.view_isometric()
        pl.reset_camera(bounds=style.bounds)
        return
    h_ax, v_ax, d_ax, sign = axes[style.view]
    width, height = hi[h_ax] - lo[h_ax], hi[v_ax] - lo[v_ax]
    aspect = 0.8 * style.size[0] / style.size[1]
    half = 0.56 * max(height, width / aspect)
    focal = centre.copy()
    focal[h_ax] += 0.1 * (2 * half * style.size[0] / style.size[1])  # shift the domain left of the bar
    position = focal.copy()
    position[d_ax] += sign * 10 * max(hi - lo)
    up = np.zeros(3)
    up[v_ax] = 1.0
    pl.camera.position, pl.camera.focal_point, pl.camera.up = position, focal, up
    pl.enable_parallel_projection()
    pl.camera.parallel_scale = half
    pl.reset_camera_clipping_range()


def render_frame(snapshot: Path, time: float, style: FrameStyle, out_png: Path) -> None:
    """Render one snapshot to a PNG (written under a temporary name, then renamed)."""
    prepare_offscreen()
    import pyvista as pv

    points, data = read_vtp(snapshot)
    values = field_values(style.field, data)
    radius = np.asarray(data["radius"], dtype=float)
    if style.slice_thickness is not None and len(points):
        mid = 0.5 * (style.bounds[2] + style.bounds[3])
        keep = np.abs(points[:, 1] - mid) <= 0.5 * style.slice_thickness
        points, values, radius = points[keep], values[keep], radius[keep]
    title, _ = FIELDS.get(style.field, (style.field, "viridis"))
    pl = pv.Plotter(off_screen=True, window_size=list(style.size))
    pl.set_background("white")
    if len(points):
        cloud = pv.PolyData(np.ascontiguousarray(points, dtype=np.float32))
        cloud["values"] = values
        px = pixel_size(style)
        cloud["radius"] = np.where(radius < 0.5 * px, 2.0 * px, radius)
        actor = pl.add_mesh(
            cloud, scalars="values", style="points_gaussian", render_points_as_spheres=True, emissive=False,
            cmap=style.colormap, clim=style.clim,
            scalar_bar_args=dict(title=title, fmt=bar_format(style.clim), color="black", vertical=True, n_labels=bar_labels(style.clim),
                                 position_x=0.80, position_y=0.15, height=0.7, width=0.05,
                                 title_font_size=15, label_font_size=14),
        )
        actor.mapper.scale_array = "radius"
        actor.mapper.scale_factor = 1.0
    lo, hi = np.array(style.bounds[0::2]), np.array(style.bounds[1::2])
    for t in style.tubes:
        axis = np.asarray(t["mask"]) == 0.0
        length = float((hi - lo)[axis][0])
        for centre in tube_images(t, lo, hi, style.periodic):
            centre[axis] = 0.5 * (lo + hi)[axis]
            cyl = pv.Cylinder(center=centre, direction=axis.astype(float), radius=t["r"], height=length, resolution=64)
            pl.add_mesh(cyl.clip_box(style.bounds, invert=False), color=tube_colour(t, style), lighting=False)
    add_meshes(pl, style, time)
    for part in distributor_boxes(style):
        pl.add_mesh(pv.Box(bounds=part["bounds"]), color=part["colour"], lighting=False)
    pl.add_mesh(pv.Box(bounds=style.bounds).outline(), color="black", line_width=1)
    pl.add_text(f"t = {time:.4g} s", position=(12, style.size[1] - 34), font_size=12, color="black")
    place_camera(pl, style)
    tmp = Path(out_png).with_name("." + Path(out_png).name)  # a stopped render leaves no half-written frame
    pl.screenshot(str(tmp))
    pl.close()
    os.replace(tmp, out_png)
