"""Triangle-mesh walls (hoppers, drums, cones) in the frames.

The renderer learns the meshes from the run folder alone: run.json's `render_geometry.meshes`
(`tidem.io.mesh_output.mesh_geometry`) names each mesh's file at t = 0 and its rigid motion, and
`load_meshes` turns them back into `tidem.walls.mesh_walls.MeshWall`s, read once per rendering; a moving
mesh is moved to each frame's time with `MeshWall.points_at`.

A closed vessel or a drum would hide the bed, so the half of each mesh in front of the bed is
cut away: the mesh is clipped by the plane through the domain centre facing the camera and only
the part behind it is drawn (for a drum seen along its axis, its back end cap and the back half
of its shell; for a hopper seen from the front, its back half), and the line of the cut is drawn
too, so that a wall seen edge-on still shows (a drum seen along its axis, a slot's floor plate from
the front). Triangles wholly outside the
domain box are not drawn. The rest is drawn as a lit surface: metallic grey, or with a fixed
temperature and frames coloured by temperature, the colour map's colour for it on the
particles' range (clipped to it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp_triangles
from tidem.scene.schedule import Schedule, VectorSchedule
from tidem.walls.mesh_walls import MeshWall

GREY = "#b8bcc2"  # brushed steel
EDGE = "#5a5f66"  # the cut's edge of an unheated mesh
TOWARDS_CAMERA = {"front": (0.0, -1.0, 0.0), "side": (1.0, 0.0, 0.0), "top": (0.0, 0.0, 1.0)}
ISOMETRIC = (1.0, 1.0, 1.0)  # pyvista's view_isometric


def load_meshes(run_dir: Path, geometry: list[dict]) -> list[MeshWall]:
    """The meshes of a run folder from run.json's `render_geometry.meshes` and their t = 0 files."""
    out = []
    for g in geometry:
        path = Path(run_dir) / g["file"]
        if not path.is_file():
            raise ValueError(f"{path} is missing: the run folder lacks the mesh file of {g['name']}")
        points, triangles, _data = read_vtp_triangles(path)
        out.append(MeshWall(name=g["name"], vertices=np.array(points, dtype=float), triangles=np.array(triangles),
                            material="", temperature=g.get("T"), center=tuple(g["center"]), axis=tuple(g["axis"]),
                            speed=g["speed"], velocity=tuple(g["velocity"]), source=g.get("source", ""),
                            schedules=read_schedules(g.get("schedules", {}))))
    return out


def read_schedules(tables: dict) -> dict:
    """A mesh's schedules as run.json holds them (temperature, speed: numbers; velocity: vectors)."""
    return {key: (VectorSchedule if key == "velocity" else Schedule).model_validate(table) for key, table in tables.items()}


def towards_camera(view: str) -> np.ndarray:
    """Unit vector from the scene towards the camera of a frame view (`frames.place_camera`)."""
    d = np.array(TOWARDS_CAMERA.get(view, ISOMETRIC))
    return d / np.linalg.norm(d)


def in_domain(points: np.ndarray, triangles: np.ndarray, bounds) -> np.ndarray:
    """Mask of the triangles that touch the domain box."""
    lo, hi = np.asarray(bounds[0::2], float), np.asarray(bounds[1::2], float)
    corners = points[triangles]  # [T, 3, 3]
    return np.all(corners.min(axis=1) <= hi, axis=1) & np.all(corners.max(axis=1) >= lo, axis=1)


def mesh_colour(temperature: float | None, style):
    """The colour map's colour of a fixed-temperature mesh when the frames show temperature
    (clipped to the range), grey otherwise. `style` is a `tidem.render.frames.FrameStyle`."""
    if style.field != "temperature" or temperature is None:
        return GREY
    import matplotlib

    low, high = style.clim
    frac = min(max((temperature - low) / (high - low), 0.0), 1.0) if high > low else 0.5
    return matplotlib.colormaps[style.colormap](frac)[:3]


def mesh_surface(mesh: MeshWall, time: float, bounds, view: str, cut: bool = False):
    """The pyvista PolyData drawn for a mesh at `time`: its triangles in the domain box, cut by
    the plane through the domain centre facing the camera, the part behind it kept (the cut runs
    through triangles, so its edge is smooth); None when nothing of it shows. `cut`: the line
    where that plane cuts the mesh instead (a drum seen along its axis shows as this line only)."""
    import pyvista as pv

    points = mesh.points_at(time) if mesh.moving else mesh.vertices
    tri = np.asarray(mesh.triangles)
    tri = tri[in_domain(points, tri, bounds)]
    if not len(tri):
        return None
    faces = np.hstack([np.full((len(tri), 1), 3, dtype=np.int64), tri.astype(np.int64)]).ravel()
    surface = pv.PolyData(np.ascontiguousarray(points, dtype=np.float64), faces)
    centre = 0.5 * (np.asarray(bounds[0::2], float) + np.asarray(bounds[1::2], float))
    if cut:
        line = surface.slice(normal=towards_camera(view), origin=centre)
        return line if line.n_points else None
    behind = surface.clip(normal=towards_camera(view), origin=centre, invert=True)
    return behind if behind.n_cells else None


def add_meshes(pl, style, time: float) -> None:
    """Draw `style.meshes` at `time` into the plotter `pl` (a `tidem.render.frames.FrameStyle`)."""
    for mesh in style.meshes:
        surface = mesh_surface(mesh, time, style.bounds, style.view)
        if surface is None:
            continue
        heated = style.field == "temperature" and mesh.temperature is not None
        pl.add_mesh(surface, color=mesh_colour(mesh.temperature_at(time), style), smooth_shading=True,
                    split_sharp_edges=True, ambient=0.45 if heated else 0.3, diffuse=0.6,
                    specular=0.15 if heated else 0.5, specular_power=30.0)
        line = mesh_surface(mesh, time, style.bounds, style.view, cut=True)
        if line is not None:  # the cut's edge: the outline of a wall seen edge-on (a drum along its axis)
            pl.add_mesh(line, color=EDGE, line_width=6)
            if heated:  # its temperature's colour inside the dark edge
                pl.add_mesh(line, color=mesh_colour(mesh.temperature_at(time), style), line_width=3)
