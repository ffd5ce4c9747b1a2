"""[[meshes]]: reading STL/OBJ/PLY files into MeshWalls (transform, welding, statistics, one
clear message per bad file), the mesh geometry (distances, inside tests, facet sag), the tube
overlap refusals and the placement around meshes. Plain numpy and pyvista, no kernels."""

import struct

import numpy as np
import pytest
import pyvista as pv
import tomli_w

import tidem.walls.mesh_geometry as geometry
from tidem.particles.placement import clear_of_obstacles, lattice_sites, place_groups
from tidem.scene.errors import SceneError
from tidem.scene.load import resolve, validate
from tidem.walls.mesh_geometry import (facet_sag, flat_patches, inside_closed_mesh, inside_periodic_mesh,
                                       point_mesh_distance, weld)
from tidem.walls.mesh_load import load_mesh_walls, rotation_matrix, tube_mesh_overlaps


def raw_scene(**extra) -> dict:
    """A small valid scene: a 1 m box, one sand particle near the top, plus `extra` tables."""
    raw = {
        "domain": {"min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]},
        "materials": {"sand": {"density": 2600.0, "youngs_modulus": 1e7},
                      "steel": {"density": 7800.0, "youngs_modulus": 2e11}},
        "particles": [{"name": "bed", "material": "sand", "diameter": 0.02, "positions": [[0.0, 0.0, 0.45]]}],
    }
    raw.update(extra)
    return raw


def cube_file(tmp_path, name="cube.stl", binary=True, size=0.2, center=(0.0, 0.0, 0.0)):
    """A closed cube of edge `size` (12 triangles) saved as `name`."""
    mesh = pv.Cube(center=center, x_length=size, y_length=size, z_length=size).triangulate()
    path = tmp_path / name
    mesh.save(path, binary=binary) if name.endswith((".stl", ".ply")) else mesh.save(path)
    return path


def load_walls(tmp_path, **mesh):
    """load_mesh_walls for a scene with one [[meshes]] table (file relative to tmp_path)."""
    scene = validate(raw_scene(meshes=[mesh])).scene
    return load_mesh_walls(scene, tmp_path / "scene.toml", "sand")


def write_stl(path, triangles):
    """An ASCII STL of the given triangles [[p0, p1, p2], ...] (written by hand, so NaN and
    degenerate triangles survive as written)."""
    lines = ["solid t"]
    for tri in triangles:
        lines += ["facet normal 0 0 1", "outer loop", *[f"vertex {p[0]} {p[1]} {p[2]}" for p in tri], "endloop",
                  "endfacet"]
    path.write_text("\n".join(lines + ["endsolid t"]) + "\n")
    return path


# reading, transform, welding ------------------------------------------------------------------

@pytest.mark.parametrize("binary", [False, True])
def test_stl_cube_is_welded_and_measured(tmp_path, binary):
    cube_file(tmp_path, binary=binary)
    walls, errs = load_walls(tmp_path, file="cube.stl", material="steel")
    assert errs == []
    (w,) = walls
    assert w.name == "meshes[0]" and w.material == "steel" and w.source.endswith("cube.stl")
    assert w.stats["triangles"] == 12 and w.stats["vertices"] == 8 and w.stats["welded"] == 36 - 8
    assert w.stats["area"] == pytest.approx(6 * 0.04)
    assert w.stats["sag"] == 0.0  # flat faces; the 90 degree edges are corners, not facets
    assert w.triangles.dtype == np.int32 and w.triangles.shape == (12, 3)


def test_scale_rotate_offset(tmp_path):
    write_stl(tmp_path / "tri.stl", [[(0, 100, 0), (100, 100, 0), (0, 100, 100)]])
    walls, errs = load_walls(tmp_path, file="tri.stl", scale=0.001, rotate=[90.0, 90.0, 0.0], offset=[0.1, 0.0, 0.0])
    assert errs == []
    # (0, 0.1, 0): about x by 90 -> (0, 0, 0.1), then about y by 90 -> (0.1, 0, 0), then + offset
    got = {tuple(np.round(v, 12)) for v in walls[0].vertices}
    expected = {tuple(np.round(rotation_matrix([90, 90, 0]) @ np.array(p) * 1e-3 + [0.1, 0, 0], 12))
                for p in [(0, 100, 0), (100, 100, 0), (0, 100, 100)]}
    assert got == expected
    assert (0.2, 0.0, 0.0) in got


def test_rotation_order_is_x_then_y_then_z():
    r = rotation_matrix([90.0, 90.0, 0.0])
    assert np.allclose(r @ [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])  # y -> z (about x) -> x (about y)
    assert np.allclose(rotation_matrix([0.0, 0.0, 90.0]) @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])


def test_obj_quads_are_triangulated(tmp_path):
    pv.Plane(i_resolution=2, j_resolution=2, i_size=0.2, j_size=0.2).save(tmp_path / "plane.obj")
    walls, errs = load_walls(tmp_path, file="plane.obj")
    assert errs == [] and walls[0].stats["triangles"] == 8 and walls[0].stats["vertices"] == 9
    assert walls[0].stats["area"] == pytest.approx(0.04)


def test_motion_keys_reach_the_mesh_wall(tmp_path):
    cube_file(tmp_path)
    walls, errs = load_walls(tmp_path, file="cube.stl", friction=0.3, velocity=[0.0, 0.0, 0.1],
                             surface_velocity=[0.5, 0.0, 0.0],
                             rotation={"center": [0.0, 0.0, 0.0], "axis": [0.0, 2.0, 0.0], "speed": 1.5})
    w = walls[0]
    assert errs == [] and w.material == "sand" and w.friction == 0.3
    assert w.axis == (0.0, 1.0, 0.0) and w.speed == 1.5 and w.velocity == (0.0, 0.0, 0.1)
    assert w.surface_velocity == (0.5, 0.0, 0.0) and w.moving


def test_weld_joins_points_across_a_cell_boundary():
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0 - 1e-12, 1e-12, 0.0], [1.0, 1.0, 0.0]])
    t = np.array([[0, 1, 2], [3, 4, 2]])
    vw, tw, merged = weld(v, t, 1e-9)
    assert merged == 1 and len(vw) == 4 and tw[1, 0] == tw[0, 1]


# bad files: one message each, naming the key ----------------------------------------------------

def one_message(tmp_path, **mesh):
    walls, errs = load_walls(tmp_path, **mesh)
    assert len(errs) == 1, errs
    assert errs[0].startswith("meshes[0].file: ")
    return errs[0]


def test_missing_file(tmp_path):
    assert "no such file 'nope.stl'" in one_message(tmp_path, file="nope.stl")
    (tmp_path / "parts").mkdir()
    assert "'parts' is a folder" in one_message(tmp_path, file="parts")


def test_text_file_that_is_not_stl(tmp_path):
    (tmp_path / "notes.stl").write_text("these are my notes\n")
    msg = one_message(tmp_path, file="notes.stl")
    assert "is not a triangle surface mesh (no triangles found: it is not a valid STL file)" in msg


def test_point_cloud(tmp_path):
    pv.PolyData(np.random.default_rng(0).random((20, 3)) * 0.1).save(tmp_path / "cloud.ply")
    assert "not a triangle surface mesh (it holds a point cloud)" in one_message(tmp_path, file="cloud.ply")


def test_cad_format_is_refused_with_the_fix(tmp_path):
    (tmp_path / "part.step").write_text("ISO-10303-21;\n")
    assert "export the part from your CAD tool as STL" in one_message(tmp_path, file="part.step")


@pytest.mark.parametrize("name, binary", [("cube.ply", True), ("cube.ply", False), ("cube.obj", False)])
def test_ply_and_obj_cubes_read_as_the_stl_cube(tmp_path, name, binary):
    """OBJ and PLY are read by tidem itself (`tidem.walls.mesh_files`): the same 12 triangles and 8
    welded vertices as the STL cube."""
    cube_file(tmp_path, name=name, binary=binary)
    walls, errs = load_walls(tmp_path, file=name)
    assert errs == [] and walls[0].stats["triangles"] == 12 and walls[0].stats["vertices"] == 8
    assert walls[0].stats["area"] == pytest.approx(6 * 0.04)


def binary_stl(triangles: int, stored: int, extra: bytes = b"") -> bytes:
    """A binary STL of `stored` triangles whose header counts `triangles` (with bytes appended)."""
    tri = struct.pack("<12f", 0, 0, 1, 0, 0, 0, 0.1, 0, 0, 0, 0.1, 0) + b"\0\0"
    return b"solid written by a CAD tool".ljust(80) + struct.pack("<I", triangles) + tri * stored + extra


PLY_HEAD = ("ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n")
BAD_FILES = [
    ("face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "line 4: a face refers to vertex 9, but the file has 3 vertices"),
    ("back.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -7\n", "line 4: a face refers to vertex -7"),
    ("word.obj", "v 0 0 0\nv x 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: a vertex coordinate is not a number"),
    ("two.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "line 2: a vertex needs x, y and z"),
    ("edge.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: a face needs at least 3 vertices"),
    ("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4: vertex index 0 (OBJ counts from 1)"),
    ("empty.obj", "# nothing\n", "not a triangle surface mesh (no vertices and no faces"),
    ("binary.obj", b"\x00\x01\x02garbage", "is not a text OBJ file"),
    ("cut.stl", binary_stl(2, 2)[:-20], "binary STL whose header counts 2 triangles (184 bytes), but the file has "
                                        "164 bytes (truncated)"),
    ("promise.stl", binary_stl(5, 2), "header counts 5 triangles (334 bytes), but the file has 184 bytes (truncated)"),
    ("padded.stl", binary_stl(2, 2, b"\0" * 13), "(data after the last triangle)"),
    ("tiny.stl", b"\x00\x01abc", "too short for an STL file (5 bytes"),
    ("few.ply", PLY_HEAD.format(fmt="ascii", nv=10) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
     "ends within its vertex (fewer values than the header declares)"),
    ("more.ply", PLY_HEAD.format(fmt="ascii", nv=3) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n7\n",
     "holds 1 values more than its header declares"),
    ("index.ply", PLY_HEAD.format(fmt="ascii", nv=3) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
     "has a face that refers to vertex 7, but the file has 3 vertices"),
    ("cut.ply", PLY_HEAD.format(fmt="binary_little_endian", nv=3).encode() + b"\x00\x01",
     "ends within its vertex element (truncated"),
    ("head.ply", "plyx\ngarbage\n", "is not a PLY file"),
    ("format.ply", "ply\nformat utf8 1.0\nend_header\n", "has no known format line"),
    ("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n1\n",
     "header line 4: a property of an unknown type"),
]


@pytest.mark.parametrize("name, content, message", BAD_FILES, ids=[row[0] for row in BAD_FILES])
def test_a_malformed_truncated_or_inconsistent_file_is_one_message(tmp_path, name, content, message):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    assert message in one_message(tmp_path, file=name)


def test_no_reader_line_reaches_the_terminal(tmp_path):
    """`tidem check` on a broken ASCII STL (which VTK reads and complains of on the error stream) and a
    truncated binary PLY: exit 2 and nothing on stderr but tidem's two lines."""
    import subprocess
    import sys

    (tmp_path / "broken.stl").write_text("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\nendsolid x\n")
    for name in ("broken.stl", "cut.ply"):
        if name == "cut.ply":
            (tmp_path / name).write_bytes(PLY_HEAD.format(fmt="binary_little_endian", nv=3).encode() + b"\x00")
        scene = raw_scene(meshes=[{"file": name}])
        (tmp_path / "scene.toml").write_text(tomli_w.dumps(scene))
        done = subprocess.run([sys.executable, "-m", "tidem", "check", str(tmp_path / "scene.toml")],
                              capture_output=True, text=True)
        lines = [ln for ln in done.stderr.splitlines() if not ln.startswith("[Taichi]")]
        assert done.returncode == 2 and len(lines) == 2, done.stderr
        assert lines[0].endswith("1 error in the scene") and lines[1].startswith(f"  meshes[0].file: '{name}'")


def test_nan_triangles_are_counted(tmp_path):
    good = [[(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)], [(0.1, 0, 0), (0.1, 0.1, 0), (0, 0.1, 0)]]
    write_stl(tmp_path / "nan.stl", good + [[(0, 0, 0), ("nan", 0, 0), (0, 0.1, 0.1)]] * 2)
    msg = one_message(tmp_path, file="nan.stl")
    assert "2 of 4 triangles" in msg and "NaN" in msg and "repair the mesh in your CAD tool" in msg


def test_zero_area_triangles_are_counted(tmp_path):
    good = [[(0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)]]
    write_stl(tmp_path / "flat.stl", good + [[(0, 0, 0), (0.05, 0, 0), (0.1, 0, 0)], [(0, 0, 0), (0, 0, 0), (0, 0.1, 0)]])
    msg = one_message(tmp_path, file="flat.stl")
    assert "2 of 3 triangles" in msg and "zero area" in msg and "repair the mesh" in msg


def test_all_triangles_degenerate(tmp_path):
    write_stl(tmp_path / "line.stl", [[(0, 0, 0), (0.05, 0, 0), (0.1, 0, 0)], [(0, 0, 0), ("nan", 0, 0), (1, 1, 0)]])
    assert "every one of the 2 triangles" in one_message(tmp_path, file="line.stl")


def test_mesh_outside_the_domain(tmp_path):
    cube_file(tmp_path, size=20.0, center=(100.0, 0.0, 0.0))  # a drawing in mm read as m
    msg = one_message(tmp_path, file="cube.stl")
    assert "wholly outside the domain" in msg and "scale = 0.001" in msg
    walls, errs = load_walls(tmp_path, file="cube.stl", scale=0.001)
    assert errs == []


def test_bad_mesh_tables_are_refused_by_the_schema():
    def messages(mesh, **extra):
        with pytest.raises(SceneError) as exc:
            validate(raw_scene(meshes=[mesh], **extra))
        return exc.value.messages

    assert messages({"file": "a.stl", "scale": 0.0}) == ["meshes[0].scale: must be > 0 (got 0.0)"]
    (msg,) = messages({"file": "a.stl", "rotation": {"center": [0, 0, 0], "axis": [0, 0, 0], "speed": 1.0}})
    assert msg.startswith("meshes[0]: rotation.axis must not be the zero vector")
    assert messages({"file": "a.stl", "material": "stele"}) == [
        "meshes[0].material: no material named 'stele'; defined: sand, steel"]
    assert messages({"file": "a.stl", "temperature": 353.15})[0].startswith(
        "meshes[0].temperature: temperatures need a [heat] table")
    validate(raw_scene(meshes=[{"file": "a.stl", "surface_velocity": [0.1, 0, 0]}], gas={"cell_size": 0.1}))
    (msg,) = messages({"file": "a.stl", "velocity": [0, 0, 0.1]}, gas={"cell_size": 0.1})
    assert msg.startswith("meshes[0]: a moving mesh in a scene with [gas] is not supported")
    msg = messages({"file": "a.stl", "temperature": 353.15}, gas={"cell_size": 0.1},
                   heat={"initial_temperature": 293.15})[0]
    assert msg == ("meshes[0].convection_length: a heated mesh gives heat to the gas by gas.tube_convection = "
                   "\"martin_nilles\", whose bare-surface part needs the length across the flow [m]: set it (the "
                   "outer diameter of a tube drawn as a mesh), or set gas.tube_convection = \"none\"")
    for mesh, gas in (({"file": "a.stl", "temperature": 353.15, "convection_length": 0.03}, {"cell_size": 0.1}),
                      ({"file": "a.stl", "temperature": 353.15}, {"cell_size": 0.1, "tube_convection": "none"})):
        assert not any(m.startswith("meshes") for m in messages(mesh, gas=gas, heat={"initial_temperature": 293.15}))
    assert messages({"file": "a.stl", "convection_length": -0.03}) == [
        "meshes[0].convection_length: must be > 0 (got -0.03)"]
    assert any(m.startswith("meshes: contact.model = 'none'")
               for m in messages({"file": "a.stl"}, contact={"model": "none"}))


# geometry ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("capping", [False, True])
def test_sag_of_a_24_facet_cylinder(capping):
    r = 0.1
    cyl = pv.Cylinder(radius=r, height=0.3, resolution=24, capping=capping).triangulate()
    sag = facet_sag(np.asarray(cyl.points, float), cyl.regular_faces)
    assert sag == pytest.approx(r * (1 - np.cos(np.pi / 24)), rel=0.1)


def test_sag_does_not_depend_on_the_winding():
    cyl = pv.Cylinder(radius=1.0, height=1.0, resolution=24, capping=False).triangulate()
    v, t = np.asarray(cyl.points, float), cyl.regular_faces.copy()
    t[::3] = t[::3, ::-1]
    assert facet_sag(v, t) == pytest.approx(1 - np.cos(np.pi / 24), rel=0.1)


def cube_mesh(h=0.5):
    cube = pv.Cube(x_length=2 * h, y_length=2 * h, z_length=2 * h).triangulate().clean()
    return np.asarray(cube.points, float), cube.regular_faces


def test_point_mesh_distance_on_a_cube(monkeypatch):
    v, t = cube_mesh()
    p = np.random.default_rng(1).uniform(-1.5, 1.5, (400, 3))
    q = np.abs(p) - 0.5
    exact = np.where(np.all(q <= 0, axis=1), -q.max(axis=1), np.linalg.norm(np.maximum(q, 0), axis=1))
    assert np.allclose(point_mesh_distance(p, v, t), exact, atol=1e-12)
    monkeypatch.setattr(geometry, "PAIRS", 7)  # tiny chunks: the same answer
    assert np.allclose(point_mesh_distance(p, v, t), exact, atol=1e-12)
    near = point_mesh_distance(p, v, t, within=0.2)
    assert np.allclose(near[exact < 0.2], exact[exact < 0.2]) and np.all(near[exact >= 0.2] >= 0.2 - 1e-12)


def test_point_triangle_distance_regions():
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    t = np.array([[0, 1, 2]])
    p = np.array([[0.2, 0.2, 0.3], [-1.0, -1.0, 0.0], [0.5, -2.0, 1.0], [1.0, 1.0, 0.0], [0.1, 0.1, 0.0]])
    expected = [0.3, np.sqrt(2.0), np.sqrt(5.0), np.sqrt(0.5), 0.0]
    assert np.allclose(point_mesh_distance(p, v, t), expected)
    brute = np.array([[a, b, 0.0] for a in np.linspace(0, 1, 401) for b in np.linspace(0, 1, 401) if a + b <= 1])
    q = np.random.default_rng(2).uniform(-1, 2, (20, 3))
    approx = np.linalg.norm(q[:, None] - brute[None], axis=2).min(axis=1)
    assert np.allclose(point_mesh_distance(q, v, t), approx, atol=3e-3)


def test_inside_a_closed_cube_whatever_the_winding():
    v, t = cube_mesh()
    p = np.random.default_rng(3).uniform(-1.0, 1.0, (500, 3))
    p = p[np.abs(np.abs(p).max(axis=1) - 0.5) > 1e-3]  # not on the surface
    truth = np.all(np.abs(p) < 0.5, axis=1)
    assert np.array_equal(inside_closed_mesh(p, v, t), truth)
    t2 = t.copy()
    t2[::2] = t2[::2, ::-1]
    assert np.array_equal(inside_closed_mesh(p, v, t2), truth)
    assert inside_closed_mesh(np.array([[0.0, 0.0, 0.0]]), v, t)[0]  # rays through edges and vertices


def test_inside_a_rotated_cube_in_small_chunks(monkeypatch):
    v, t = cube_mesh()
    r = rotation_matrix([30.0, 20.0, 10.0])
    p = np.random.default_rng(5).uniform(-1.0, 1.0, (300, 3))
    local = p @ r  # the points in the cube's frame
    keep = np.abs(np.abs(local).max(axis=1) - 0.5) > 1e-3
    monkeypatch.setattr(geometry, "PAIRS", 5)
    assert np.array_equal(inside_closed_mesh(p[keep], v @ r.T, t), np.all(np.abs(local[keep]) < 0.5, axis=1))


def test_inside_an_open_drum_along_a_slanted_axis():
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    drum = pv.Cylinder(radius=0.1, height=0.4, direction=axis, resolution=48, capping=False).triangulate()
    p = np.random.default_rng(6).uniform(-0.12, 0.12, (300, 3))
    rho = np.linalg.norm(np.cross(p, axis), axis=1)
    keep = np.abs(rho - 0.1) > 0.005
    got = inside_periodic_mesh(p[keep], np.asarray(drum.points, float), drum.regular_faces, axis)
    assert np.array_equal(got, rho[keep] < 0.1)


def test_inside_an_open_drum():
    drum = pv.Cylinder(radius=0.1, height=0.2, direction=(0, 1, 0), resolution=48, capping=False).triangulate()
    v, t = np.asarray(drum.points, float), drum.regular_faces
    p = np.random.default_rng(4).uniform(-0.15, 0.15, (400, 3))
    p[:, 1] *= 0.5  # within the drum's length
    rho = np.hypot(p[:, 0], p[:, 2])
    keep = np.abs(rho - 0.1) > 0.005  # clear of the facets
    assert np.array_equal(inside_periodic_mesh(p[keep], v, t, "y"), rho[keep] < 0.1)
    assert not inside_periodic_mesh(np.array([[0.0, 0.15, 0.0]]), v, t, "y")[0]  # beyond the drum's end


# tubes ------------------------------------------------------------------------------------------

def tube(center, axis="y", diameter=0.1):
    return {"center": list(center), "axis": axis, "diameter": diameter}


def test_two_tubes_at_one_centre_are_refused():
    with pytest.raises(SceneError) as exc:
        validate(raw_scene(tubes=[tube([0, 0, 0]), tube([0, 0, 0])]))
    (msg,) = exc.value.messages
    assert msg.startswith("tubes[0] and tubes[1] overlap") and "move one" in msg


def test_tube_overlaps():
    def refused(*tubes, **domain):
        raw = raw_scene(tubes=list(tubes))
        raw["domain"].update(domain)
        try:
            validate(raw)
        except SceneError as exc:
            return [m for m in exc.messages if "overlap" in m]
        return []

    assert refused(tube([0, 0, 0]), tube([0.06, 0, 0.05]))  # axes 0.078 m apart, radii 0.05 m each
    assert not refused(tube([0, 0, 0]), tube([0.12, 0, 0.0]))
    assert not refused(tube([0, 0, 0]), tube([0.0, 0.3, 0.2], "x"), tube([0.0, 0, 0.35], "x"))
    assert refused(tube([0, 0, 0]), tube([0.0, 0.3, 0.05], "x"))  # x and y tubes cross
    assert refused(tube([-0.47, 0, 0]), tube([0.47, 0, 0]), periodic=["x"])  # 0.06 apart across the period
    assert not refused(tube([-0.3, 0, 0]), tube([0.3, 0, 0]), periodic=["x"])


def test_tube_through_a_mesh_is_refused(tmp_path):
    pv.Plane(i_size=0.4, j_size=0.4).triangulate().save(tmp_path / "plate.stl")  # z = 0, |x|, |y| <= 0.2
    tubes = [tube([0.0, 0.0, 0.03]), tube([0.0, 0.0, 0.2], diameter=0.1), tube([0.0, 0.0, -0.08], "x")]
    scene = validate(raw_scene(tubes=tubes, meshes=[{"file": "plate.stl"}])).scene
    walls, errs = load_mesh_walls(scene, tmp_path / "scene.toml", "sand")
    assert errs == []
    msgs = tube_mesh_overlaps(scene, walls)
    assert len(msgs) == 1 and msgs[0].startswith("tubes[0] and meshes[0]") and "0.03 m" in msgs[0]


# placement --------------------------------------------------------------------------------------

def test_lattice_sites_skip_the_mesh_and_positions_in_it_are_refused(tmp_path):
    pv.Plane(i_size=1.0, j_size=1.0).triangulate().save(tmp_path / "plate.stl")  # z = 0 across the box
    region = {"name": "bed", "material": "sand", "diameter": 0.1,
              "region": {"min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}}
    scene = validate(raw_scene(particles=[region], meshes=[{"file": "plate.stl"}])).scene
    walls, errs = load_mesh_walls(scene, tmp_path / "scene.toml", "sand")
    args = ([], [], [1.0, 1.0, 1.0], [False] * 3)
    free, _ = place_groups(scene, *args)
    placed, errs = place_groups(scene, *args, meshes=walls)
    assert errs == [] and 0 < len(placed.x0) < len(free.x0)
    assert np.all(np.abs(placed.x0[:, 2]) > 0.05 * 0.99)
    sites = np.array([[0.0, 0.0, 0.01], [0.0, 0.0, 0.3]])
    assert clear_of_obstacles(sites, 0.05, [], [], [1.0] * 3, [False] * 3,
                              [(w.vertices, w.triangles) for w in walls]).tolist() == [False, True]

    given = {"name": "bed", "material": "sand", "diameter": 0.1, "positions": [[0.0, 0.0, 0.2], [0.1, 0.0, 0.01]]}
    scene = validate(raw_scene(particles=[given], meshes=[{"file": "plate.stl"}])).scene
    placed, errs = place_groups(scene, *args, meshes=walls)
    assert placed is None and len(errs) == 1
    assert errs[0].startswith("particles[0].positions[1]: overlaps meshes[0] by 80 % of its radius")


def test_open_axis_of_closed_open_and_holed_meshes():
    cube = pv.Cube().triangulate()
    assert geometry.open_axis(np.asarray(cube.points), cube.regular_faces) is None
    drum = pv.Cylinder(direction=(0, 1, 0), capping=False).triangulate()
    assert geometry.open_axis(np.asarray(drum.points), drum.regular_faces) == 1
    plate = pv.Plane().triangulate()  # open along its edges in x and in y: no inside
    assert geometry.open_axis(np.asarray(plate.points), plate.regular_faces) == -1
    # moving_bed_hopper's wedge: two sheets along y, each rim vertex at an end of y, but the rims along y
    # run from one end to the other: no inside when strict (a fill's bodies), open along y else (inside_mesh)
    hopper = pv.read(str(resolve("moving_bed_hopper").parent / "wedge_hopper.stl")).clean()
    assert geometry.open_axis(np.asarray(hopper.points), hopper.regular_faces, strict=True) == -1
    assert geometry.open_axis(np.asarray(hopper.points), hopper.regular_faces) == 1
    assert geometry.open_axis(np.asarray(drum.points), drum.regular_faces, strict=True) == 1


def test_a_fill_skips_the_inside_of_the_bodies_it_surrounds(tmp_path):
    """A region filled around a closed cube and around a tube open at its ends (spanning the box along
    y) leaves their insides empty; a region drawn inside a closed vessel (a bounding box of at least half
    the region's) is kept; given positions inside a body are refused, one alone too."""
    cube_file(tmp_path, size=0.4, center=(-0.2, 0.0, 0.0))
    pv.Cylinder(center=(0.25, 0.0, 0.0), direction=(0, 1, 0), radius=0.15, height=1.0, resolution=48,
                capping=False).triangulate().save(tmp_path / "tube.stl")
    fill = {"name": "bed", "material": "sand", "diameter": 0.05,
            "region": {"min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}}
    scene = validate(raw_scene(particles=[fill], meshes=[{"file": "cube.stl"}, {"file": "tube.stl"}])).scene
    walls, errs = load_mesh_walls(scene, tmp_path / "scene.toml", "sand")
    placed, errs = place_groups(scene, [], [], [1.0, 1.0, 1.0], [False] * 3, meshes=walls)
    x = placed.x0
    assert errs == [] and len(x) > 1000
    assert not (np.abs(x - [-0.2, 0.0, 0.0]) < 0.2).all(axis=1).any(), "none in the cube"
    assert not (np.hypot(x[:, 0] - 0.25, x[:, 2]) < 0.15).any(), "none in the tube"
    vessel = {**fill, "region": {"min": [-0.35, -0.15, -0.15], "max": [-0.05, 0.15, 0.15]}}
    scene = validate(raw_scene(particles=[vessel], meshes=[{"file": "cube.stl"}])).scene
    placed, errs = place_groups(scene, [], [], [1.0, 1.0, 1.0], [False] * 3, meshes=walls[:1])
    sites = lattice_sites(*vessel["region"].values(), 1.02 * 0.05, "cubic")
    clear = clear_of_obstacles(sites, 0.51 * 0.05, [], [], [1.0] * 3, [False] * 3, [(walls[0].vertices, walls[0].triangles)])
    assert errs == [] and len(placed.x0) == clear.sum() == 5**3, "the cube as the vessel of its region: every site kept"
    given = {"name": "bed", "material": "sand", "diameter": 0.05,
             "positions": [[-0.2, 0.0, 0.0], [0.25, 0.3, 0.0], [0.0, 0.3, 0.3], [0.3, 0.3, 0.4]]}
    scene = validate(raw_scene(particles=[given], meshes=[{"file": "cube.stl"}, {"file": "tube.stl"}])).scene
    placed, errs = place_groups(scene, [], [], [1.0, 1.0, 1.0], [False] * 3, meshes=walls)
    assert placed is None and errs == [
        "particles[0].positions[0]: [-0.2, 0.0, 0.0] lies inside a body drawn as a mesh (a closed mesh, or a tube open at "
        "its ends, around it); "
        "move it out (2 particles of this group lie inside one)",
        "particles[0].positions[1]: [0.25, 0.3, 0.0] lies inside a body drawn as a mesh (a closed mesh, or a tube open at "
        "its ends, around it); "
        "move it out"]
    alone = {**given, "positions": [[0.25, 0.3, 0.0]]}  # one particle, inside the tube: still refused
    scene = validate(raw_scene(particles=[alone], meshes=[{"file": "cube.stl"}, {"file": "tube.stl"}])).scene
    assert place_groups(scene, [], [], [1.0, 1.0, 1.0], [False] * 3, meshes=walls)[0] is None


def test_fill_inside_a_drum(tmp_path):
    """A region larger than the drum, limited to its inside: every particle inside, clear of the wall."""
    pv.Cylinder(radius=0.3, height=1.0, direction=(0, 1, 0), resolution=64, capping=False).triangulate().save(
        tmp_path / "drum.stl")
    group = {"name": "bed", "material": "sand", "diameter": 0.04,
             "region": {"min": [-0.45, -0.45, -0.45], "max": [0.45, 0.45, 0.0]}, "inside_mesh": 0}
    scene = validate(raw_scene(particles=[group], meshes=[{"file": "drum.stl"}])).scene
    walls, errs = load_mesh_walls(scene, tmp_path / "scene.toml", "sand")
    placed, errors = place_groups(scene, [], [], [1.0, 1.0, 1.0], (False, False, False), walls)
    assert errs == [] and errors == []
    rho = np.hypot(placed.x0[:, 0], placed.x0[:, 2])
    assert len(rho) > 100 and (rho < 0.3 - 0.02).all()


def test_inside_mesh_needs_a_mesh_with_an_inside(tmp_path):
    pv.Plane(i_size=0.8, j_size=0.8).triangulate().save(tmp_path / "plate.stl")
    group = {"name": "bed", "material": "sand", "diameter": 0.04,
             "region": {"min": [-0.4, -0.4, 0.05], "max": [0.4, 0.4, 0.3]}, "inside_mesh": 0}
    scene = validate(raw_scene(particles=[group], meshes=[{"file": "plate.stl"}])).scene
    walls, _ = load_mesh_walls(scene, tmp_path / "scene.toml", "sand")
    placed, errors = place_groups(scene, [], [], [1.0, 1.0, 1.0], (False, False, False), walls)
    assert placed is None and len(errors) == 1 and errors[0].startswith("particles[0].inside_mesh: meshes[0] has no inside")
    with pytest.raises(SceneError, match=r"particles\[0\].inside_mesh: there is no meshes\[1\]"):
        validate(raw_scene(particles=[{**group, "inside_mesh": 1}], meshes=[{"file": "plate.stl"}]))


def test_flat_patches_join_a_plane_and_keep_the_facets_of_a_curve():
    """A plane of many triangles is one patch; a box has one patch a face; a 24-facet cylinder's mantle
    keeps its facets apart (they turn by 15 degrees), each facet's two triangles joined; a gently
    curved sheet (0.05 mrad a column of triangles, 2 mrad over the sheet) whose patch would spread past FLAT_SPREAD is left in single triangles."""
    plane = pv.Plane(i_resolution=30, j_resolution=30).triangulate()
    assert set(flat_patches(np.asarray(plane.points, float), plane.regular_faces)) == {0}
    box = pv.Box().triangulate()
    assert len(set(flat_patches(np.asarray(box.points, float), box.regular_faces))) == 6
    n = 24
    ang = np.arange(n) * 2 * np.pi / n
    ring = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    v = np.vstack([np.c_[ring, np.zeros(n)], np.c_[ring, np.ones(n)]])
    t = np.array([(i, (i + 1) % n, n + i) for i in range(n)] + [((i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)])
    patch = flat_patches(v, t)
    assert len(set(patch)) == n and all(patch[i] == patch[n + i] for i in range(n))
    x = np.linspace(0.0, 1.0, 41)
    xx, yy = np.meshgrid(x, x)
    bent = np.c_[xx.ravel(), yy.ravel(), 1e-3 * xx.ravel() ** 2]  # slope turning 0.05 mrad a column
    sheet = pv.PolyData(bent).delaunay_2d()
    assert len(set(flat_patches(bent, sheet.regular_faces))) == sheet.n_cells


def test_a_step_that_could_carry_a_particle_through_a_sheet_is_refused_unless_nothing_moves(tmp_path):
    """A 1 mm grain over a sheet, the time step forced to 5e-4 s: the grain's impact speed (a fall across the
    1 m box, 4.43 m/s) closes 2.2 mm a step, more than 0.2 of its radius, so the step is refused with the
    step that would do (0.2 x 0.5 mm / 4.43 m/s);
    with the grain fixed it never moves and the step stands, unless the mesh itself turns fast enough."""
    from tidem.sim.model import build_model

    path = write_stl(tmp_path / "sheet.stl", [[[-0.4, -0.4, 0.0], [0.4, -0.4, 0.0], [0.4, 0.4, 0.0]]])
    raw = raw_scene(meshes=[{"file": str(path), "material": "steel"}], numerics={"dt": 5e-4, "force_dt": True})
    raw["particles"][0].update(diameter=0.001, positions=[[0.0, 0.0, 0.1]])
    raw["domain"]["walls"] = "none"
    with pytest.raises(SceneError) as exc:
        build_model(validate(raw))
    (msg,) = exc.value.messages
    assert msg.startswith("meshes[0]: a particle could close 0.00221 m on it in one step of 0.0005 s") and \
        msg.endswith("lower numerics.dt_fraction (or numerics.dt) to below 2.26e-05 s")
    raw["particles"][0]["fixed"] = True
    build_model(validate(raw))
    raw["meshes"][0]["rotation"] = {"center": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0], "speed": 1.0}
    with pytest.raises(SceneError, match=r"lower rotation.speed or velocity \(the mesh's fastest point moves at 0.566 m/s"):
        build_model(validate(raw))
