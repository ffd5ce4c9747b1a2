"""Mesh walls in the run folder: a static mesh written once, a moving one at each snapshot's
time (the points `MeshWall.points_at` gives), a heated one with its temperature, all listed in
meshes.pvd, and VTK (ParaView's reader, through pyvista) reads the same triangles."""

import numpy as np

from tidem.io.mesh_output import PVD_NAME, MeshOutput, mesh_file, mesh_geometry
from tidem.io.vtp import read_vtp_triangles, write_vtp_triangles
from tidem.walls.mesh_walls import MeshWall

CUBE_V = np.array([[x, y, z] for x in (0.0, 0.1) for y in (0.0, 0.1) for z in (0.0, 0.1)])
CUBE_T = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.int32)


def cube(k=0, **kw):
    return MeshWall(name=f"meshes[{k}]", vertices=CUBE_V.copy(), triangles=CUBE_T.copy(), material="steel", **kw)


def test_triangles_round_trip_and_vtk_reads_them(tmp_path):
    import pyvista as pv

    path = tmp_path / "m.vtp"
    write_vtp_triangles(path, CUBE_V, CUBE_T, {"temperature": np.full(8, 450.0)}, time=0.25)
    points, triangles, data = read_vtp_triangles(path)
    assert np.array_equal(points, CUBE_V) and np.array_equal(triangles, CUBE_T)
    assert np.array_equal(data["temperature"], np.full(8, 450.0))
    mesh = pv.read(path)
    assert mesh.n_cells == 12 and mesh.is_all_triangles
    assert np.array_equal(mesh.regular_faces, CUBE_T) and np.allclose(mesh.points, CUBE_V)
    assert np.allclose(mesh.point_data["temperature"], 450.0)
    assert np.isclose(mesh.area, 0.06) and np.isclose(mesh.volume, 1e-3)


def test_static_mesh_once_moving_mesh_per_snapshot_at_its_time(tmp_path):
    still = cube(0)
    turning = cube(1, center=(0.05, 0.05, 0.05), axis=(0.0, 1.0, 0.0), speed=2.0, velocity=(0.1, 0.0, 0.0),
                   temperature=500.0)
    entries = []
    out = MeshOutput(tmp_path, [still, turning], entries)
    assert sorted(p.name for p in (tmp_path / "meshes").iterdir()) == ["mesh0.vtp", "mesh1.vtp"]
    assert not (tmp_path / PVD_NAME).exists(), "no collection before the first snapshot"
    for k, t in enumerate((0.0, 0.3, 0.6)):
        entries.append((t, f"snapshots/snap_{k:05d}.vtp"))
        out.snapshot()
    names = sorted(p.name for p in (tmp_path / "meshes").iterdir())
    assert names == ["mesh0.vtp", "mesh1.vtp", "mesh1_00000.vtp", "mesh1_00001.vtp", "mesh1_00002.vtp"]
    for k, t in enumerate((0.0, 0.3, 0.6)):
        points, triangles, data = read_vtp_triangles(tmp_path / mesh_file(1, k))
        assert np.allclose(points, turning.points_at(t)) and np.array_equal(triangles, CUBE_T)
        assert np.array_equal(data["temperature"], np.full(8, 500.0))
    assert not np.allclose(read_vtp_triangles(tmp_path / mesh_file(1, 2))[0], CUBE_V), "it moved"
    points, _tri, data = read_vtp_triangles(tmp_path / mesh_file(0))
    assert np.array_equal(points, CUBE_V) and data == {}, "an adiabatic mesh has no temperature array"
    assert out.pvd_rows()[-2:] == [(0.6, 0, "meshes/mesh0.vtp"), (0.6, 1, "meshes/mesh1_00002.vtp")]
    geo = mesh_geometry([still, turning])
    assert geo[1]["file"] == "meshes/mesh1.vtp" and geo[1]["speed"] == 2.0 and geo[1]["T"] == 500.0


def test_paraview_reads_the_collection_as_one_block_per_mesh(tmp_path):
    import pyvista as pv

    turning = cube(1, center=(0.05, 0.05, 0.05), axis=(0.0, 0.0, 1.0), speed=1.0)
    entries = []
    out = MeshOutput(tmp_path, [cube(0), turning], entries)
    for k, t in enumerate((0.0, 0.5)):
        entries.append((t, f"snapshots/snap_{k:05d}.vtp"))
        out.snapshot()
    reader = pv.get_reader(tmp_path / PVD_NAME)
    assert reader.time_values == [0.0, 0.5]
    reader.set_active_time_value(0.5)
    blocks = reader.read()
    assert blocks.n_blocks == 2
    assert np.allclose(blocks[0].points, CUBE_V) and np.allclose(blocks[1].points, turning.points_at(0.5))


def test_resume_keeps_the_moving_mesh_files_of_kept_snapshots_only(tmp_path):
    turning = cube(0, velocity=(0.0, 0.0, 1.0))
    entries = []
    out = MeshOutput(tmp_path, [turning], entries)
    for k in range(4):
        entries.append((0.1 * k, f"snapshots/snap_{k:05d}.vtp"))
        out.snapshot()
    MeshOutput(tmp_path, [turning], entries[:2])  # resumed from a checkpoint after snapshot 1
    assert sorted(p.name for p in (tmp_path / "meshes").iterdir()) == ["mesh0.vtp", "mesh0_00000.vtp", "mesh0_00001.vtp"]
    assert (tmp_path / PVD_NAME).read_text().count("<DataSet") == 2
    MeshOutput(tmp_path, [], [])
    assert not (tmp_path / PVD_NAME).exists()


def test_a_run_writes_its_meshes_and_names_them_in_run_json(tmp_path):
    """tidem.runner.loop wires MeshOutput in: the folder, meshes.pvd beside snapshots.pvd, run.json."""
    import json

    from tests.conftest import make_scene
    from tidem.runner.loop import run
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    model = build_model(validate(make_scene(numerics={"t_end": 2e-5}, output={"snapshots": 2})))
    far = MeshWall(name="meshes[0]", vertices=CUBE_V + 0.5, triangles=CUBE_T, material="steel", velocity=(1.0, 0, 0))
    model.meshes = [far]  # far from the particle: the run's contacts never see it
    result = run(model, tmp_path, progress=False)
    assert result.status == "finished", result.message
    snaps = (tmp_path / "snapshots.pvd").read_text().count("<DataSet")
    assert snaps >= 2 and (tmp_path / PVD_NAME).read_text().count("<DataSet") == snaps
    last = snaps - 1
    t_last = float((tmp_path / "snapshots.pvd").read_text().split('timestep="')[-1].split('"')[0])
    assert np.allclose(read_vtp_triangles(tmp_path / mesh_file(0, last))[0], far.points_at(t_last))
    geo = json.loads((tmp_path / "run.json").read_text())["render_geometry"]["meshes"]
    assert geo == mesh_geometry([far])
