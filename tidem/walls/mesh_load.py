"""Read a scene's `[[meshes]]` (triangle-mesh walls from CAD files) into `MeshWall`s.

Each file (STL ASCII or binary, which pyvista reads once `tidem.walls.mesh_files` has checked a
binary file's length, or OBJ and PLY, which that module reads) is taken relative to the scene
file's folder, its points are transformed as x' = R_z R_y R_x (scale x) + offset (`rotate` in
degrees, first about x, then y, then z), coincident vertices are welded (STL stores none of the
connectivity) within 1e-9 of the mesh's bounding-box diagonal, and triangles with a non-finite
coordinate or zero area are counted and refused. Nothing here raises for a bad file: every
problem comes back as a 'meshes[k].file: ...' message naming the fix, like the scene's other
messages (`tidem.scene.checks`).

`tube_mesh_overlaps` refuses tubes that cut a mesh; the geometry (distances, inside tests, the
facet sag) lives in `tidem.walls.mesh_geometry` and is re-exported here.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from tidem.scene.schedule import is_scheduled, start
from tidem.walls.mesh_files import quiet_native_stderr, read_obj, read_ply, stl_problem
from tidem.walls.mesh_geometry import facet_sag, triangle_areas, weld
from tidem.walls.mesh_walls import MeshWall

SUFFIXES = (".stl", ".obj", ".ply")
WELD_TOL = 1e-9  # of the bounding-box diagonal
_REPAIR = "repair the mesh in your CAD tool (or a mesh repair tool) and export it again"


def rotation_matrix(degrees) -> np.ndarray:
    """R = R_z(c) R_y(b) R_x(a) for `rotate = [a, b, c]` in degrees: first about x, then y, then z."""
    a, b, c = np.radians(np.asarray(degrees, float))
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx


def transform(points: np.ndarray, scale: float = 1.0, rotate=(0.0, 0.0, 0.0), offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Scene coordinates of file points: R (scale x) + offset [m] (see `rotation_matrix`)."""
    return (scale * np.asarray(points, float)) @ rotation_matrix(rotate).T + np.asarray(offset, float)


def read_triangles(path: Path) -> tuple[np.ndarray, np.ndarray] | str:
    """(points [P, 3], triangles [T, 3]) as stored in the file, or what is wrong with it (text).

    STL is read without the reader's own merging (so that degenerate triangles are seen and
    counted, not silently dropped); polygons of OBJ and PLY files are split into triangles.
    VTK's error output is silenced: the caller reports the problem in one line."""
    import pyvista as pv
    from vtkmodules.vtkCommonCore import vtkObject

    if path.suffix.lower() not in SUFFIXES:
        return (f"'{path.name}' is not an STL, OBJ or PLY file; export the part from your CAD tool as STL "
                "(ASCII or binary)")
    if path.suffix.lower() in (".obj", ".ply"):
        return (read_obj if path.suffix.lower() == ".obj" else read_ply)(path)
    if path.suffix.lower() == ".stl" and (problem := stl_problem(path)):
        return problem
    shown = vtkObject.GetGlobalWarningDisplay()
    vtkObject.GlobalWarningDisplayOff()
    try:
        with warnings.catch_warnings(), quiet_native_stderr():
            warnings.simplefilter("ignore")
            reader = pv.get_reader(str(path))
            if path.suffix.lower() == ".stl":
                reader.reader.SetMerging(0)
            mesh = reader.read()
            if isinstance(mesh, pv.MultiBlock):
                mesh = mesh.combine().extract_surface()
            if not isinstance(mesh, pv.PolyData):
                return f"'{path.name}' holds no surface mesh; export the part's surface as STL"
            if mesh.GetNumberOfPolys() + mesh.GetNumberOfStrips() == 0:
                what = ("it holds a point cloud" if mesh.n_points else
                        f"no triangles found: it is not a valid {path.suffix[1:].upper()} file")
                return (f"'{path.name}' is not a triangle surface mesh ({what}); export the part's surface as STL "
                        "(ASCII or binary)")
            if mesh.GetNumberOfLines() or mesh.GetNumberOfVerts():  # keep the surface cells only
                mesh = pv.PolyData(mesh.points, faces=mesh.faces if mesh.GetNumberOfPolys() else None,
                                   strips=mesh.strips if mesh.GetNumberOfStrips() else None)
            if not mesh.is_all_triangles:
                mesh = mesh.triangulate()
            return np.asarray(mesh.points, float), np.asarray(mesh.regular_faces, np.int64).reshape(-1, 3)
    except Exception as exc:  # noqa: BLE001 - any reader failure is a bad file, reported in one line
        return f"cannot read '{path.name}' ({type(exc).__name__}: {exc}); export it again as STL"
    finally:
        vtkObject.SetGlobalWarningDisplay(shown)


def _fixed_surfaces(scene, default_material: str, k: int, m) -> dict:
    """The MeshWall keywords that come from the scene table (not the file)."""
    rot = m.rotation
    axis = (0.0, 0.0, 1.0)
    if rot is not None:
        a = np.asarray(rot.axis, float)
        axis = tuple(float(c) for c in a / np.linalg.norm(a))
    keys = {"temperature": m.temperature, "speed": rot.speed if rot else 0.0, "velocity": m.velocity}
    return dict(name=f"meshes[{k}]", material=m.material or default_material, friction=m.friction,
                temperature=start(m.temperature), convection_length=m.convection_length,
                center=tuple(rot.center) if rot else (0.0, 0.0, 0.0), axis=axis,
                speed=float(start(keys["speed"])), velocity=tuple(float(c) for c in start(m.velocity)),
                surface_velocity=tuple(m.surface_velocity),
                schedules={key: value for key, value in keys.items() if is_scheduled(value)})


def load_mesh(scene, scene_path, default_material: str, k: int) -> tuple[MeshWall | None, list[str]]:
    """meshes[k] of the scene read, transformed, welded and checked (see the module docstring)."""
    m = scene.meshes[k]
    key = f"meshes[{k}].file"
    folder = Path(scene_path).parent if scene_path is not None else Path(".")
    path = Path(m.file) if Path(m.file).is_absolute() else folder / m.file
    if path.is_dir():
        return None, [f"{key}: '{m.file}' is a folder ({path.resolve()}); name the mesh file in it (STL, OBJ or PLY)"]
    if not path.is_file():
        return None, [f"{key}: no such file '{m.file}' (looked for {path.resolve()}); give the path relative to the scene "
                      "file's folder"]
    try:
        with open(path, "rb") as fh:
            fh.read(1)
    except OSError as exc:
        return None, [f"{key}: cannot read '{m.file}': {exc.strerror or exc}; check its permissions"]
    got = read_triangles(path)
    if isinstance(got, str):
        return None, [f"{key}: {got}"]
    points, tri = got
    if not len(tri):
        return None, [f"{key}: '{m.file}' holds no triangles; export the part's surface as STL"]
    x = transform(points, m.scale, m.rotate, m.offset)
    finite = np.all(np.isfinite(x[tri]), axis=(1, 2))
    errs: list[str] = []
    good = x[tri[finite]].reshape(-1, 3)
    diag = float(np.linalg.norm(good.max(axis=0) - good.min(axis=0))) if len(good) else 0.0
    vertices, triangles, merged = weld(x, tri[finite], WELD_TOL * diag)
    a, b, c = (vertices[triangles[:, j]] for j in range(3))
    twice = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                      np.linalg.norm(a - c, axis=1)], axis=0)
    flat = twice <= 1e-12 * longest**2  # zero area: a vertex repeated (after welding) or three in a line
    n_nan, n_flat, n_all = int((~finite).sum()), int(flat.sum()), len(tri)
    if n_nan + n_flat == n_all:
        return None, [f"{key}: every one of the {n_all} triangles of '{m.file}' is degenerate (zero area or "
                      f"non-finite coordinates), so there is no surface; {_REPAIR}"]
    if n_nan:
        errs.append(f"{key}: {n_nan} of {n_all} triangles of '{m.file}' have non-finite (NaN or inf) coordinates; "
                    f"{_REPAIR}")
    if n_flat:
        errs.append(f"{key}: {n_flat} of {n_all} triangles of '{m.file}' have zero area (a repeated vertex or "
                    f"three vertices in a line, after welding vertices within {WELD_TOL:g} of the mesh's size); {_REPAIR}")
    triangles = triangles[~flat]
    used = np.unique(triangles)
    vertices, triangles = vertices[used], np.searchsorted(used, triangles).astype(np.int32)
    wall = MeshWall(vertices=vertices, triangles=triangles, source=str(path), **_fixed_surfaces(
        scene, default_material, k, m))
    wall.stats = dict(triangles=len(triangles), vertices=len(vertices), welded=int(merged),
                      area=float(triangle_areas(vertices, triangles).sum()), sag=facet_sag(vertices, triangles),
                      dropped_nonfinite=n_nan, dropped_zero_area=n_flat,
                      bounds=[vertices.min(axis=0).tolist(), vertices.max(axis=0).tolist()])
    outside = _outside_domain(scene, wall)
    if outside:
        errs.append(f"{key}: {outside}")
    return wall, errs


def _outside_domain(scene, wall: MeshWall) -> str:
    """Why the mesh is wholly outside the domain box, or '' (a translating mesh may enter later and
    is not refused; a rotating one is judged by the ball it sweeps about its rotation centre)."""
    if wall.translates:
        return ""
    lo, hi = wall.vertices.min(axis=0), wall.vertices.max(axis=0)
    if wall.rotates:
        c = np.asarray(wall.center, float)
        reach = float(np.max(np.linalg.norm(wall.vertices - c, axis=1)))
        lo, hi = c - reach, c + reach
    dom = scene.domain
    if np.all(hi >= np.asarray(dom.min)) and np.all(lo <= np.asarray(dom.max)):
        return ""
    return (f"the mesh spans {np.round(lo, 6).tolist()}..{np.round(hi, 6).tolist()} m (after scale, rotate and "
            f"offset), wholly outside the domain {list(dom.min)}..{list(dom.max)}; check 'scale' (a drawing in "
            "mm needs scale = 0.001), 'rotate' and 'offset'")


def load_mesh_walls(scene, scene_path, default_material: str) -> tuple[list[MeshWall], list[str]]:
    """Every [[meshes]] entry of the scene as a MeshWall, and the messages of the problems found
    (an empty list when all is well). Never raises for bad input: a file that cannot be used
    gives a message and no MeshWall."""
    walls: list[MeshWall] = []
    errs: list[str] = []
    for k in range(len(getattr(scene, "meshes", []))):
        try:
            wall, found = load_mesh(scene, scene_path, default_material, k)
        except (OSError, ValueError, MemoryError) as exc:
            wall, found = None, [f"meshes[{k}].file: cannot use '{scene.meshes[k].file}' ({exc}); export it again "
                                 "as STL"]
        errs += found
        if wall is not None:
            walls.append(wall)
    return walls, errs


def tube_mesh_overlaps(scene, meshes: list[MeshWall]) -> list[str]:
    """Messages for tubes whose solid cross-section a mesh enters inside the domain (at t = 0).

    A tube is an infinite cylinder along x or y, so a triangle cuts it exactly where the
    triangle's projection onto the cross-section plane comes closer than the radius to the
    projected axis point (2-D point-triangle distance: zero inside the projection, else the
    distance to its nearest edge). Only triangles reaching into the domain's range along the
    tube axis count (each whole, a slight overestimate for one that straddles the domain's
    end); on a periodic axis across the tube, the images one period away count too."""
    errs: list[str] = []
    dom = scene.domain
    for i, t in enumerate(scene.tubes):
        along = "xyz".index(t.axis)
        across = [a for a in range(3) if a != along]
        r = 0.5 * t.diameter
        centres = [np.array([t.center[a] for a in across], float)]
        for j, a in enumerate(across):
            if "xyz"[a] in dom.periodic:
                length = dom.max[a] - dom.min[a]
                centres += [cc + s * length * np.eye(2)[j] for cc in list(centres) for s in (-1.0, 1.0)]
        for mesh in meshes:
            tri = mesh.vertices[mesh.triangles]  # [T, 3, 3]
            reach = (tri[:, :, along].max(axis=1) >= dom.min[along]) & (tri[:, :, along].min(axis=1) <= dom.max[along])
            flat = tri[reach][:, :, across]
            if not len(flat):
                continue
            gap = min(float(_distance_2d(cc, flat).min()) for cc in centres)
            if gap < r * (1 - 1e-9):
                errs.append(f"tubes[{i}] and {mesh.name}: the mesh comes within {gap:.4g} m of the tube's axis, inside "
                            f"its radius {r:g} m, so they overlap; move the tube (center) or the mesh (offset)")
    return errs


def _distance_2d(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance of the 2-D point p to each 2-D triangle tri [T, 3, 2]: 0 inside (or on) it,
    else the distance to its nearest edge."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]

    def cross(u, v):
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]

    s1, s2, s3 = cross(b - a, p - a), cross(c - b, p - b), cross(a - c, p - c)
    area = cross(b - a, c - a)
    inside = (area != 0) & (((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0)))
    best = np.full(len(tri), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        e = v - u
        den = np.einsum("ij,ij->i", e, e)
        s = np.clip(np.einsum("ij,ij->i", p - u, e) / np.where(den > 0, den, 1.0), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(p - u - s[:, None] * e, axis=1))
    return np.where(inside, 0.0, best)
