"""Mesh walls against analytic surfaces and laws (`kernels/mesh_contact.py`): a plane made of
irregular triangles against the analytic plane wall (float64, 1e-9; as one flat patch and as a
patch per triangle), edge and vertex strikes
(force along the line to the nearest point, energy kept with e = 1), a concave corner (both faces
felt), a ball rolling on a turntable (circles at 2 Omega / 7), a heated mesh plate against the
heated plane wall (1e-9)."""

import math

import numpy as np
import pytest
import pyvista as pv

from tests.conftest import make_scene

R = 0.005
SOFT = {"density": 2500.0, "youngs_modulus": 5e6, "poisson_ratio": 0.3, "restitution": 0.5, "friction": 0.3,
        "rolling_friction": 0.02}


def save_mesh(path, points, triangles):
    faces = np.hstack([np.full((len(triangles), 1), 3), np.asarray(triangles)]).ravel()
    pv.PolyData(np.asarray(points, float), faces).save(str(path))
    return str(path)


def irregular_square(path, half, n=15, seed=3, z=0.0):
    """A square [-half, half]^2 at height z triangulated from jittered points (Delaunay): irregular
    triangles of every orientation."""
    rng = np.random.default_rng(seed)
    g = np.linspace(-half, half, n)
    xx, yy = np.meshgrid(g, g)
    pts = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)
    inner = (np.abs(pts[:, 0]) < half) & (np.abs(pts[:, 1]) < half)
    pts[inner, :2] += rng.uniform(-0.3, 0.3, (inner.sum(), 2)) * (2 * half / (n - 1))
    tri = pv.PolyData(pts).delaunay_2d()
    faces = tri.faces.reshape(-1, 4)[:, 1:]
    pts[:, 2] = z
    return save_mesh(path, pts, faces), len(faces)


def bouncing_sphere(mesh_file=None, precision="float64"):
    """A sphere dropped with a tangential velocity and spin onto the floor z = 0: the box wall, or a mesh."""
    domain = {"min": [-0.1, -0.1, 0.0], "max": [0.1, 0.1, 0.1], "gravity": [0.0, 0.0, -9.81],
              "walls": ["z-"] if mesh_file is None else "none"}
    raw = make_scene(domain=domain, materials={"soft": SOFT},
                     particles=[{"name": "p", "material": "soft", "diameter": 2 * R, "positions": [[-0.07, -0.03, 0.02]],
                                 "velocities": [[0.35, 0.15, 0.0]]}],
                     numerics={"precision": precision, "t_end": 1.0})
    if mesh_file is not None:
        raw["meshes"] = [{"file": mesh_file}]
    return raw


@pytest.mark.parametrize("patches", ["one flat patch", "a patch per triangle"])
def test_plane_of_irregular_triangles_follows_the_analytic_plane(solver_for, tmp_path, monkeypatch, patches):
    """Both narrow phases: the flat patch's (the face under the centre alone) and, with every triangle a
    patch of its own, the general one (nearest points of all listed triangles, duplicates suppressed)."""
    if patches != "one flat patch":
        monkeypatch.setattr("tidem.walls.mesh_bins.flat_patches", lambda v, t: np.arange(len(t)))
    path, n_tri = irregular_square(tmp_path / "plane.stl", 0.1)
    assert n_tri >= 200
    wall = solver_for(bouncing_sphere())
    mesh = solver_for(bouncing_sphere(path))
    assert mesh.dt == wall.dt
    touched = several = 0
    for _ in range(50):
        wall.advance(100)
        mesh.advance(100)
        a = [wall.state.x[0], wall.state.v[0], wall.state.w[0]]
        b = [mesh.state.x[0], mesh.state.v[0], mesh.state.w[0]]
        for u, v in zip(a, b):
            u, v = u.to_numpy(), v.to_numpy()
            assert np.abs(u - v).max() <= 1e-9 * max(np.abs(u).max(), 1e-3), (u, v)
        touched += mesh.state.ovl[0] > 0
        if mesh.state.mc_n[0] > 1:  # the path taken where it lists several triangles
            several += 1
            assert (mesh.state.mc_flat[0] >= 0) == (patches == "one flat patch")
    assert several > 5
    x = mesh.state.x[0].to_numpy()
    assert touched > 20 and x[0] > 0.05  # rolled on the mesh across many triangles (about 10 along its path)
    assert abs(mesh.state.w[0].to_numpy()).max() > 1.0


def strike(solver_for, tmp_path, triangles, points, x0, v0):
    """One elastic frictionless strike; returns (largest angle between the force and the line from the
    nearest point to the centre, kinetic energy after / before)."""
    path = save_mesh(tmp_path / "t.stl", points, triangles)
    mat = {**SOFT, "restitution": 1.0, "friction": 0.0, "rolling_friction": 0.0}
    raw = make_scene(domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1]}, materials={"soft": mat},
                     particles=[{"name": "p", "material": "soft", "diameter": 2 * R, "positions": [x0],
                                 "velocities": [v0]}],
                     numerics={"precision": "float64", "t_end": 1.0, "dt_fraction": 0.02}, meshes=[{"file": path}])
    s = solver_for(raw)
    m = 2500 * 4 / 3 * math.pi * R**3
    e0 = 0.5 * m * np.dot(v0, v0)
    worst = 0.0
    tri = np.asarray(points, float)[np.asarray(triangles)]
    contact = False
    for _ in range(20000):
        s.step()
        f = s.state.f[0].to_numpy()
        if np.linalg.norm(f) > 0:
            contact = True
            x = s.state.x[0].to_numpy()
            p = min((closest_point(x, *t) for t in tri), key=lambda q: np.linalg.norm(q - x))
            line = x - p
            sin = np.linalg.norm(np.cross(f, line)) / (np.linalg.norm(f) * np.linalg.norm(line))
            assert f.dot(line) > 0  # pushes the centre away from the nearest point
            worst = max(worst, math.asin(min(1.0, sin)))
        elif contact:
            break
    assert contact
    v = s.state.v[0].to_numpy()
    return worst, 0.5 * m * v.dot(v) / e0


def closest_point(x, a, b, c):
    """Brute force: the nearest of a fine sample of the triangle's points and its edges' projections."""
    best = None
    for p, q in ((a, b), (b, c), (c, a)):
        t = np.clip(np.dot(x - p, q - p) / np.dot(q - p, q - p), 0.0, 1.0)
        cand = p + t * (q - p)
        if best is None or np.linalg.norm(cand - x) < np.linalg.norm(best - x):
            best = cand
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    proj = x - np.dot(x - a, n) * n
    bary = np.linalg.solve(np.stack([b - a, c - a, n], axis=1), proj - a)
    if bary[0] >= 0 and bary[1] >= 0 and bary[0] + bary[1] <= 1 and np.linalg.norm(proj - x) < np.linalg.norm(best - x):
        best = proj
    return best


def test_edge_strike_pushes_along_the_line_to_the_edge(solver_for, tmp_path):
    """A flat triangle hit edge-on at an angle: contact at its edge, force through the edge point."""
    pts = [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [0.0, 0.05, 0.0]]
    angle, ratio = strike(solver_for, tmp_path, [[0, 1, 2]], pts, [0.02, -R - 1e-4, 0.002], [0.0, 0.5, -0.1])
    assert angle < 1e-9
    assert ratio == pytest.approx(1.0, abs=1e-4)


def test_vertex_strike_pushes_along_the_line_to_the_vertex(solver_for, tmp_path):
    """A tetrahedron's apex struck off-axis: the force points from the apex through the centre."""
    pts = [[0.0, 0.0, 0.0], [0.04, 0.0, -0.03], [-0.02, 0.035, -0.03], [-0.02, -0.035, -0.03]]
    tris = [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]
    d = np.array([0.3, 0.2, 1.0])
    d /= np.linalg.norm(d)
    angle, ratio = strike(solver_for, tmp_path, tris, pts, list((R + 2e-4) * d), list(-0.4 * d + [0.05, 0, 0]))
    assert angle < 1e-9
    assert ratio == pytest.approx(1.0, abs=1e-4)


def test_sphere_in_a_concave_corner_feels_both_faces(solver_for, tmp_path):
    """Floor and wall of a mesh meeting at a right angle; gravity pushes the sphere into the corner along
    both: it rests on both faces, each overlap m g / k_n (linear law, k_n = E d; frictionless, so that
    the load's share of each face is determinate)."""
    pts = [[-0.05, -0.05, 0.0], [0.05, -0.05, 0.0], [0.05, 0.05, 0.0], [-0.05, 0.05, 0.0],
           [-0.05, -0.05, 0.05], [-0.05, 0.05, 0.05]]
    tris = [[0, 1, 2], [0, 2, 3], [0, 3, 5], [0, 5, 4]]
    path = save_mesh(tmp_path / "corner.stl", pts, tris)
    g = 9.81
    raw = make_scene(domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "gravity": [-g, 0.0, -g]},
                     materials={"soft": {**SOFT, "friction": 0.0, "rolling_friction": 0.0}},
                     particles=[{"name": "p", "material": "soft", "diameter": 2 * R, "positions": [[-0.05 + R + 1e-4, 0.01, R + 1e-4]]}],
                     contact={"model": "linear"}, numerics={"precision": "float64", "t_end": 1.0},
                     meshes=[{"file": path}])
    s = solver_for(raw)
    s.advance(20000)
    x = s.state.x[0].to_numpy()
    m = 2500 * 4 / 3 * math.pi * R**3
    expected = m * g / (5e6 * 2 * R)
    assert R - (x[2] - 0.0) == pytest.approx(expected, rel=1e-3)
    wall = s.model.meshes[0].vertices[:, 0].min()  # -0.05 as STL's float32 holds it
    assert R - (x[0] - wall) == pytest.approx(expected, rel=1e-3)
    assert int(s.state.ncontact[0]) == 2


def test_ball_on_a_turntable_circles_at_two_sevenths_of_its_rate(solver_for, tmp_path):
    """A ball rolling without slip on a table turning at Omega about z circles the axis at 2 Omega / 7
    (e.g. Weltner, Am. J. Phys. 55 (1987) 909). Started on that orbit, radius rho, with the spin of no slip."""
    path, _ = irregular_square(tmp_path / "table.stl", 0.12, n=9)
    omega, rho, r = 2.0, 0.05, 0.01
    mat = {**SOFT, "friction": 1.0, "rolling_friction": 0.0, "restitution": 0.3}
    m = 2500 * 4 / 3 * math.pi * r**3
    sink = m * 9.81 / (5e6 * 2 * r)
    raw = make_scene(domain={"min": [-0.15, -0.15, -0.02], "max": [0.15, 0.15, 0.1], "gravity": [0.0, 0.0, -9.81]},
                     materials={"soft": mat},
                     particles=[{"name": "p", "material": "soft", "diameter": 2 * r, "positions": [[rho, 0.0, r - sink]],
                                 "velocities": [[0.0, 2 * omega * rho / 7, 0.0]]}],
                     numerics={"precision": "float64", "t_end": 2.0},
                     meshes=[{"file": path, "rotation": {"center": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0],
                                                         "speed": omega}}])
    s = solver_for(raw)
    s.state.w[0] = [5 * omega * rho / (7 * r), 0.0, 0.0]
    steps = int(1.0 / s.dt)
    s.advance(steps)
    x = s.state.x[0].to_numpy()
    turned = math.atan2(x[1], x[0])
    assert turned == pytest.approx(2 * omega / 7 * s.t, rel=0.01)
    assert math.hypot(x[0], x[1]) == pytest.approx(rho, rel=0.01)


def heated_scene(mesh_file=None):
    """Two particles over a floor at 400 K: one resting on it (contact and Schluender gap), one held a
    tenth of its radius above it (gas lens)."""
    hot = {**SOFT, "conductivity": 1.0, "heat_capacity": 800.0}
    domain = {"min": [-0.05, -0.05, 0.0], "max": [0.05, 0.05, 0.05], "gravity": [0.0, 0.0, -9.81],
              "walls": ["z-"] if mesh_file is None else "none", "wall_temperature": None if mesh_file else 400.0}
    if mesh_file is not None:
        del domain["wall_temperature"]
    raw = make_scene(domain=domain, materials={"hot": hot},
                     particles=[{"name": "rest", "material": "hot", "diameter": 2 * R, "positions": [[0.01, 0.0, R]],
                                 "temperature": 300.0},
                                {"name": "held", "material": "hot", "diameter": 2 * R, "fixed": True,
                                 "positions": [[-0.02, 0.0, 1.1 * R]], "temperature": 300.0}],
                     heat={"fluid_layer": 0.4}, numerics={"precision": "float64", "t_end": 1.0})
    if mesh_file is not None:
        raw["meshes"] = [{"file": mesh_file, "temperature": 400.0}]
    return raw


def test_heated_mesh_plate_passes_the_heat_of_the_heated_plane(solver_for, tmp_path):
    path, _ = irregular_square(tmp_path / "plate.stl", 0.05, n=9)
    wall = solver_for(heated_scene())
    mesh = solver_for(heated_scene(path))
    wall.advance(3000)
    mesh.advance(3000)
    T_wall, T_mesh = wall.state.T.to_numpy(), mesh.state.T.to_numpy()
    assert (T_wall > 300.0 + 1e-3).all()
    np.testing.assert_allclose(T_mesh - 300.0, T_wall - 300.0, rtol=1e-9)
    q_wall = wall.heat_summary()["box_z-_heat_J"]
    q_mesh = mesh.heat_summary()["meshes0_heat_J"]
    assert q_mesh == pytest.approx(q_wall, rel=1e-9)


def test_sphere_set_on_a_belt_ends_rolling_at_two_sevenths_of_its_speed(solver_for, tmp_path):
    """A still mesh with a surface velocity U (a belt) drags a sphere set on it at rest until it rolls
    without slip: m v = J, I w = J r, v + w r = U give v = 2 U / 7."""
    path, _ = irregular_square(tmp_path / "belt.stl", 0.1, n=9)
    belt, r = 0.2, 0.01
    mat = {**SOFT, "friction": 0.5, "rolling_friction": 0.0, "restitution": 0.3}
    m = 2500 * 4 / 3 * math.pi * r**3
    sink = m * 9.81 / (5e6 * 2 * r)
    raw = make_scene(domain={"min": [-0.1, -0.1, -0.02], "max": [0.1, 0.1, 0.1], "gravity": [0.0, 0.0, -9.81]},
                     materials={"soft": mat},
                     particles=[{"name": "p", "material": "soft", "diameter": 2 * r, "positions": [[-0.05, 0.0, r - sink]]}],
                     numerics={"precision": "float64", "t_end": 1.0},
                     meshes=[{"file": path, "surface_velocity": [belt, 0.0, 0.0]}])
    s = solver_for(raw)
    s.advance(int(0.2 / s.dt))
    v, w = s.state.v[0].to_numpy(), s.state.w[0].to_numpy()
    assert v[0] == pytest.approx(2 * belt / 7, rel=0.01)
    assert v[0] - w[1] * r == pytest.approx(belt, rel=0.01)  # the contact point moves with the belt
