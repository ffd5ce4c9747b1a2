"""Gas convection from heated meshes (`tidem.gas.mesh_convection`, `gas.geometry.convection_walls`): the
surface a mesh shows the gas against its triangles' area, and a tube drawn as a mesh heating still
gas by Churchill-Bernstein as the analytic tube does (`tests/kernels/test_gas.py`), its heat kept."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
import pyvista as pv

from tests.conftest import make_scene
from tidem.gas.geometry import convection_walls, gas_walls, spans_period, tube_walls
from tidem.gas.mesh_convection import centroids, wetted_area
from tidem.heat.drum_heat import mesh_heat_rows
from tidem.kernels.gas_grid import GasGrid
from tidem.runner.check_report import mesh_convection_lines
from tidem.walls.mesh_walls import MeshWall

SAND = {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.9, "friction": 0.3,
        "conductivity": 3.0, "heat_capacity": 800.0}
GRID = GasGrid(lo=(0.0, 0.0, 0.0), cells=(20, 4, 20), h=(0.003,) * 3, periodic=(False, True, False))


def tube_mesh(centre=(0.03, 0.006, 0.03), diameter=0.024, facets=48) -> pv.PolyData:
    """An open 48-facet cylinder along y over the 12 mm period of GRID."""
    return pv.Cylinder(center=centre, direction=(0, 1, 0), radius=diameter / 2, height=0.012, resolution=facets,
                       capping=False).triangulate()


def wall(poly: pv.PolyData, temperature=400.0, length=0.024) -> MeshWall:
    return MeshWall(name="meshes[0]", vertices=np.asarray(poly.points, float),
                    triangles=np.asarray(poly.regular_faces, np.int32), material="steel", temperature=temperature,
                    convection_length=length)


def area_of(m: MeshWall) -> float:
    t = m.vertices[m.triangles]
    return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum())


def cut_of(meshes, tubes=()):
    return gas_walls(GRID, list(tubes), meshes)[2]


def test_sub_triangle_centroids_tile_the_triangle():
    uv = centroids(5)
    assert len(uv) == 25 and uv.mean(axis=0) == pytest.approx([1 / 3, 1 / 3], abs=1e-12)
    assert (uv > 0).all() and (uv.sum(axis=1) < 1).all()


def test_a_closed_tube_shows_the_gas_its_outside_and_a_sheet_both_its_sides():
    """The 48-facet tube's sides facing its sealed inside show nothing: the gas sees its lateral
    area once, all of it in fluid cells around the tube (cells cut so that the gas step leaves
    them out pass theirs on); a sheet in open gas shows both its sides."""
    m = wall(tube_mesh())
    cut = cut_of([m])
    tri = m.vertices[m.triangles]
    area = wetted_area(GRID, cut, tri, spans_period(GRID, [m]))
    assert area.sum() == pytest.approx(area_of(m), rel=1e-12)
    walls = convection_walls(GRID, [], [m], cut)
    assert walls["wall_A"].sum() == pytest.approx(area_of(m), rel=1e-12)
    held = walls["wall_A"] > 0
    assert not (held & cut.unreachable).any() and (walls["wall_T"][held] == 400.0).all()
    assert (walls["wall_D"][held] == 0.024).all() and (walls["wall_k"][held] == 0).all()
    centres = (np.indices(GRID.cells)[[0, 2]] + 0.5) * 0.003
    r = np.hypot(centres[0] - 0.03, centres[1] - 0.03)
    assert r[held].min() > 0.012 - 0.003 and r[held].max() < 0.012 + 2 * 0.003, "beside the tube"
    plate = pv.Plane(center=(0.03, 0.006, 0.02), direction=(0, 0, 1), i_size=0.04, j_size=0.012).triangulate()
    sheet = wall(plate)
    assert wetted_area(GRID, cut_of([sheet]), sheet.vertices[sheet.triangles],
                       spans_period(GRID, [sheet])).sum() == pytest.approx(2 * area_of(sheet), rel=1e-12)


def test_a_plate_thinner_than_a_sub_cell_shows_its_outside_once():
    """A closed plate 0.5 mm thick (sub-cells of 0.75 mm): a probe off a face towards the inside passes
    through the plate into the gas beyond, so only the side facing the plate's inside (`inward_sides`)
    keeps a face from being counted twice."""
    from tidem.gas.mesh_convection import inward_sides

    box = pv.Box(bounds=(0.01, 0.05, 0.003, 0.009, 0.03, 0.0305)).triangulate()
    plate = wall(box)
    cut = cut_of([plate])
    tri, clip = plate.vertices[plate.triangles], spans_period(GRID, [plate])
    sides = inward_sides(plate.vertices, plate.triangles)
    assert (sides != 0).all()
    assert wetted_area(GRID, cut, tri, clip, sides).sum() == pytest.approx(area_of(plate), rel=1e-12)
    assert wetted_area(GRID, cut, tri, clip).sum() > 1.3 * area_of(plate), "faces counted twice without it"


def test_a_mesh_keeps_its_area_beside_a_tube_and_the_tube_its_own():
    """Where a heated tube borders a cell, the cell is the tube's; the mesh's share there goes to its
    other cells, so both walls keep their whole areas."""
    tube = {"c": [0.03, 0.0, 0.012], "mask": [1.0, 0.0, 1.0], "r": 0.006, "T": 350.0}
    m = wall(tube_mesh(centre=(0.03, 0.006, 0.036)))
    walls = convection_walls(GRID, [tube], [m], cut_of([m], [tube]))
    alone = tube_walls(GRID, [tube])["wall_A"]
    on_tube = walls["wall_k"] == 0
    assert walls["wall_A"][on_tube & (walls["wall_A"] > 0)].sum() == pytest.approx(alone.sum(), rel=1e-12)
    assert walls["wall_A"][walls["wall_k"] == 1].sum() == pytest.approx(area_of(m), rel=1e-12)
    assert np.array_equal(walls["wall_A"][alone > 0], alone[alone > 0])


def mesh_in_still_gas(tmp_path, **gas):
    """`test_gas.tube_in_still_gas` with the 24 mm tube drawn as a 48-facet mesh."""
    path = tmp_path / "tube.stl"
    tube_mesh().save(str(path))
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.06, 0.012, 0.06], "periodic": ["y"], "walls": "auto",
                "gravity": [0, 0, 0]},
        materials={"sand": SAND},
        particles=[{"name": "p", "material": "sand", "diameter": {"value": 0.001}, "fixed": True,
                    "positions": [[0.004, 0.003, 0.004]], "temperature": 300.0}],
        meshes=[{"file": str(path), "material": "sand", "temperature": 400.0, "convection_length": 0.024}],
        heat={"initial_temperature": 300.0},
        gas={"cell_size": 0.003, "coupling_interval": 1, "initial_temperature": 300.0, **gas},
        numerics={"dt": 1e-3, "force_dt": True},
    )


def test_a_tube_drawn_as_a_mesh_heats_still_gas_by_churchill_bernstein_and_the_gas_keeps_it(tmp_path, solver_for):
    """Re = 0: Nu = 0.3, h = 0.3 k / L (L = convection_length) over the mesh's area; the heat the
    mesh gives equals the gas's (and particle's) heat gain, and the time series names it."""
    s = solver_for(mesh_in_still_gas(tmp_path))
    G = s.gas
    assert G.walls and G.heated_meshes == [0]

    def total():
        solid = float((s.model.heat_capacity * s.state.T.to_numpy()).sum())
        gas = G.G.eps.to_numpy() * G.G.T.to_numpy() * G.G.part.to_numpy()  # the gas part of each cell
        return solid + 1.2 * 1005.0 * G.gg.volume * float(gas.sum())

    s.step()
    area = area_of(s.model.meshes[0])
    assert area == pytest.approx(math.pi * 0.024 * 0.012, rel=2e-3), "the 48-gon's perimeter"
    first = float(G.G.wall_rate.to_numpy()[0])
    assert first == pytest.approx(0.3 * 0.026 / 0.024 * area * 100.0, rel=2e-3), "h A (T_w - T) at the start"
    before, given = total(), float(G.G.wall_energy.to_numpy()[0])
    for _ in range(200):
        s.step()
    assert G.G.T.to_numpy().max() > 300.5
    assert total() - before == pytest.approx(float(G.G.wall_energy.to_numpy()[0]) - given, rel=1e-9)
    assert G.summary()["meshes0_gas_heat_W"] == pytest.approx(float(G.G.wall_rate.to_numpy()[0]))
    (line,) = mesh_convection_lines(s.model)  # what `tidem check` says
    assert line.startswith("meshes[0]: gives heat to the gas (martin_nilles, length 0.024 m) over 0.0009") \
        and line.endswith("1.00 x its area (1: a closed body, 2: a sheet in the gas)"), line


def test_a_heated_mesh_reports_its_gas_share_of_alpha():
    """alpha = mean of (Q_particles + Q_gas) / (A (T_wall - T_bed)) over the second half, each share named;
    a wall temperature on a schedule is taken at each sample's time."""
    from tidem.scene.schedule import Schedule
    from tidem.walls.mesh_walls import MeshWall

    def mesh(**kw):
        return MeshWall(name="meshes[0]", vertices=np.zeros((3, 3)), triangles=np.array([[0, 1, 2]]), material="steel",
                        temperature=400.0, stats={"area": 0.5}, **kw)

    model = SimpleNamespace(scene=SimpleNamespace(heat=object()), grid=None, meshes=[mesh()])
    series = {"time_s": np.array([0.0, 1.0, 2.0, 3.0]), "T_mean_K": np.array([300.0, 300.0, 350.0, 350.0]),
              "meshes0_heat_W": np.array([9.0, 9.0, 100.0, 200.0]), "meshes0_gas_heat_W": np.array([1.0, 1.0, 5.0, 5.0])}
    (row,) = mesh_heat_rows(model, np.zeros((0, 3)), np.zeros(0), series)
    assert row["particles_alpha_W_m2K"] == pytest.approx((100.0 + 200.0) / 2 / (0.5 * 50.0))
    assert row["gas_alpha_W_m2K"] == pytest.approx(5.0 / (0.5 * 50.0)) and row["gas_heat_W"] == 5.0
    assert row["mean_alpha_W_m2K"] == pytest.approx(row["particles_alpha_W_m2K"] + row["gas_alpha_W_m2K"])
    model.meshes = [mesh(schedules={"temperature": Schedule(times=[0.0, 2.5], values=[400.0, 450.0], between="hold")})]
    (row,) = mesh_heat_rows(model, np.zeros((0, 3)), np.zeros(0), series)
    assert row["particles_alpha_W_m2K"] == pytest.approx((100.0 / (0.5 * 50.0) + 200.0 / (0.5 * 100.0)) / 2)
