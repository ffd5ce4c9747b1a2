"""Local averaging (source 3 eq. 34-36, `tidem/results/averaging.py`, `kernels/averaging.py`): each field
against a hand value on a tiny scene, the ring-sector angle convention, the output files of a
run, and the scene errors."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene
from tests.scene.test_bad_input import impact_scene, run_check
from tidem.io.vtp import read_vti
from tidem.render.plots import read_series
from tidem.results.averaging import CELLS_CSV, RINGS_CSV, VTI, cell_rows, ring_rows
from tidem.runner.loop import run
from tidem.scene.errors import SceneError
from tidem.scene.load import validate
from tidem.sim.model import build_model

A = 0.01  # lattice spacing and particle diameter [m]
STEEL = {"density": 7800.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3, "restitution": 1.0, "friction": 0.0,
         "conductivity": 16.0, "heat_capacity": 500.0}


def lattice(n=(4, 2, 4)):
    """Centres of a simple cubic lattice of spacing A from the origin, half a spacing in."""
    return [[A * (i + 0.5), A * (j + 0.5), A * (k + 0.5)]
            for i in range(n[0]) for j in range(n[1]) for k in range(n[2])]


def free_particles(positions, size=(0.04, 0.02, 0.04), periodic=(), velocities=None, fixed=False, **tables):
    """Touching or free spheres of diameter A without contacts or gravity in a box from the origin."""
    group = {"name": "p", "material": "steel", "diameter": {"value": A}, "positions": positions, "fixed": fixed}
    if velocities is not None:
        group["velocities"] = velocities
    return make_scene(domain={"min": [0.0, 0.0, 0.0], "max": list(size), "periodic": list(periodic)},
                      contact={"model": "none"}, particles=[group], numerics={"dt": 1e-3}, **tables)


def test_simple_cubic_lattice_gives_pi_over_6_in_every_cell(solver_for):
    """2 x 2 x 2 lattice sites per 2A cell (the whole depth): packing fraction pi/6 = 0.5236."""
    s = solver_for(free_particles(lattice(), fixed=True, averaging={"cell_size": [2 * A, 2 * A]}))
    for _ in range(3):
        s.sample_averages()
        s.step()
    rows = cell_rows(s.model, s)
    assert len(rows) == 4 and all(r["samples"] == 3 for r in rows)
    for r in rows:
        assert r["packing_fraction"] == pytest.approx(math.pi / 6, rel=1e-9)


def test_uniform_motion_is_every_occupied_cells_mean(solver_for):
    """64 spheres drifting at one velocity through a periodic box: cells gain and lose spheres,
    every occupied cell's number mean is the velocity and its flux / packing fraction too."""
    v = [0.1, -0.2, 0.05]
    raw = free_particles(lattice((4, 4, 4)), size=(0.04, 0.04, 0.04), periodic=("x", "y", "z"),
                         velocities=[v] * 64, averaging={"cell_size": [0.015, 0.015]})
    s = solver_for(raw)
    for _ in range(40):
        s.sample_averages()
        s.step()
    rows = [r for r in cell_rows(s.model, s) if r["packing_fraction"] > 0]
    assert len(rows) == 9  # 0.04 m / 0.015 m -> 3 x 3 cells of 0.0133 m
    for r in rows:
        for c, vc in zip("xyz", v):
            assert r[f"u_{c}"] == pytest.approx(vc, abs=1e-12)
            assert r[f"flux_{c}"] / r["packing_fraction"] == pytest.approx(vc, abs=1e-12)


def test_shear_field_gives_the_cell_centre_value(solver_for):
    """v_x = c z on a lattice symmetric within each cell: the number mean is c z_centre."""
    c = 3.0
    pos = lattice()
    raw = free_particles(pos, velocities=[[c * p[2], 0.0, 0.0] for p in pos], averaging={"cell_size": [2 * A, 2 * A]})
    s = solver_for(raw)
    s.sample_averages()
    for r in cell_rows(s.model, s):
        assert r["u_x"] == pytest.approx(c * r["z_m"], rel=1e-12)
        assert r["u_y"] == 0.0 and r["u_z"] == 0.0


R_TUBE, W = 0.01, 0.005
# (ring, angle from the top [deg]) of each particle; the last lies beyond the 3 rings
PLACED = [(0, 5.0), (1, 95.0), (2, 185.0), (0, 275.0), (3, 125.0)]


@pytest.mark.parametrize("axis", ["y", "x"])
def test_ring_sectors_place_particles_by_radius_and_angle(solver_for, axis):
    """omega = 0 on top, 90 deg on the +side (+x for a tube along y, +y along x), 180 below;
    velocities given as a e_r + b e_t + c e_axis come back as (u_r, u_t, u_axis) = (a, b, c), with
    e_r = sin(omega) side + cos(omega) z and e_t = cos(omega) side - sin(omega) z (towards
    increasing omega: downwards on the +side)."""
    d = 0.002
    a_ax = "xyz".index(axis)
    side = 0 if axis == "y" else 1
    centre = [0.05, 0.05, 0.05]
    centre[a_ax] = 0.0
    size = [0.1, 0.1, 0.1]
    size[a_ax] = 0.02
    pos, vel, expected = [], [], {}
    for n, (ring, angle) in enumerate(PLACED):
        w = math.radians(angle)
        r = R_TUBE + (ring + 0.5) * W
        e_r, e_t, e_ax = np.zeros(3), np.zeros(3), np.zeros(3)
        e_r[side], e_r[2] = math.sin(w), math.cos(w)
        e_t[side], e_t[2] = math.cos(w), -math.sin(w)
        e_ax[a_ax] = 1.0
        p = np.array(centre) + r * e_r
        p[a_ax] = 0.01
        u = (0.01 * (n + 1), -0.02 * (n + 1), 0.005)
        pos.append(p.tolist())
        vel.append((u[0] * e_r + u[1] * e_t + u[2] * e_ax).tolist())
        expected[(ring, int(angle // 10))] = u
    raw = make_scene(domain={"min": [0.0, 0.0, 0.0], "max": size},
                     particles=[{"name": "p", "material": "steel", "diameter": {"value": d}, "positions": pos,
                                 "velocities": vel}],
                     tubes=[{"center": centre, "axis": axis, "diameter": 2 * R_TUBE}],
                     averaging={"ring_width": W, "rings": 3, "ring_sectors": 36})
    s = solver_for(raw)
    s.sample_averages()
    rows = ring_rows(s.model, s)
    assert len(rows) == 3 * 36
    hit = {(r["ring"], int(r["angle_deg"] // 10)): r for r in rows if r["packing_fraction"] > 0}
    assert hit.keys() == {k for k in expected if k[0] < 3}
    v_sector = 0.5 * math.radians(10.0) * 0.02
    for key, r in hit.items():
        assert r["r_inner_m"] == pytest.approx(R_TUBE + key[0] * W, rel=1e-12)
        volume = v_sector * (r["r_outer_m"] ** 2 - r["r_inner_m"] ** 2)
        assert r["packing_fraction"] == pytest.approx(math.pi / 6 * d**3 / volume, rel=1e-12)
        assert (r["u_r"], r["u_t"], r["u_axis"]) == pytest.approx(expected[key], abs=1e-12)


def test_temperature_is_the_volume_weighted_mean(solver_for):
    """Spheres of 10 and 20 mm at 300 and 500 K in one cell: (1 x 300 + 8 x 500) / 9 = 477.78 K."""
    raw = make_scene(materials={"steel": STEEL},
                     particles=[{"name": "small", "material": "steel", "diameter": {"value": 0.01},
                                 "positions": [[-0.07, 0.0, -0.07]], "temperature": 300.0, "fixed": True},
                                {"name": "big", "material": "steel", "diameter": {"value": 0.02},
                                 "positions": [[-0.03, 0.0, -0.03]], "temperature": 500.0, "fixed": True}],
                     heat={}, averaging={"cell_size": [0.1, 0.1]})
    s = solver_for(raw)
    for _ in range(2):
        s.sample_averages()
        s.step()
    rows = cell_rows(s.model, s)
    full = [r for r in rows if r["packing_fraction"] > 0]
    assert [(r["i"], r["k"]) for r in full] == [(0, 0)]
    assert full[0]["temperature_K"] == pytest.approx((300.0 + 8 * 500.0) / 9, rel=1e-12)
    assert all(math.isnan(r["temperature_K"]) and math.isnan(r["u_x"]) for r in rows if r not in full)


def drift_run(tmp_path, averaging):
    """One sphere drifting at 1.5 m/s along x from x = 13.5 mm for 10 steps of 1 ms, with or
    without an [averaging] table."""
    tables = {"averaging": averaging} if averaging is not None else {}
    raw = free_particles([[0.0135, 0.01, 0.005]], velocities=[[1.5, 0.0, 0.0]], **tables)
    raw["numerics"]["t_end"] = 0.01
    model = build_model(validate(raw))
    assert run(model, tmp_path, progress=False).status == "finished"
    return model


def test_a_scene_without_averaging_builds_and_writes_none(tmp_path):
    model = drift_run(tmp_path, None)
    assert not model.features.averaging and model.averaging is None
    assert not list(tmp_path.glob("averages*"))
    assert not any("averaging" in k for k in model.features.kernels())


def test_a_run_writes_the_averages(tmp_path):
    """Samples at t = 3, 5, 7, 9 ms (start 2.5 ms, every 2 ms); the sphere (x = 13.5 mm + 1.5 m/s t)
    sits in cell 0 at 3 ms and in cell 1 (x >= 20 mm) at the other three; no tubes: no rings file."""
    from tidem.render.plots import plot_timeseries

    drift_run(tmp_path, {"start": 0.0025, "interval": 0.002, "cell_size": [0.02, 0.02]})
    cells = read_series(tmp_path / CELLS_CSV)
    assert not (tmp_path / RINGS_CSV).exists()
    assert set(cells["samples"]) == {4.0}
    volume = math.pi / 6 * A**3 / 0.02**3  # one sphere in a 20 x 20 x 20 mm cell
    bottom = cells["k"] == 0
    # the CSV holds 9 significant digits
    assert cells["packing_fraction"][bottom] == pytest.approx([volume / 4, 3 * volume / 4], rel=1e-8)
    assert cells["u_x"][bottom] == pytest.approx([1.5, 1.5], rel=1e-8)
    assert np.isnan(cells["u_x"][~bottom]).all() and (cells["packing_fraction"][~bottom] == 0).all()
    grid, fields = read_vti(tmp_path / VTI)
    assert grid["cells"] == (2, 1, 2)
    assert fields["packing_fraction"][:, 0, :].ravel() == pytest.approx(cells["packing_fraction"], rel=1e-8)
    assert (tmp_path / "plots" / "averages.png") in plot_timeseries(tmp_path)


@pytest.mark.parametrize("averaging, fragment", [
    ({"cell_size": [-0.01, 0.02]}, "averaging.cell_size[0]: must be > 0"),
    ({"cell_size": [0.005, 0.02]}, "averaging.cell_size: cells of 0.005 x 0.02 m"),
    ({"ring_width": 0.001}, "averaging.ring_width: 0.001 m is less than the largest particle diameter"),
    ({"rings": 2}, "averaging.rings: ring sectors are averaged around tubes and the scene has none"),
])
def test_bad_averaging_tables_are_named(averaging, fragment):
    with pytest.raises(SceneError) as err:
        validate(free_particles(lattice(), averaging=averaging))
    assert fragment in err.value.render()


def test_cell_smaller_than_a_particle_exits_2_naming_the_key(tmp_path):
    result = run_check(impact_scene(tmp_path, lambda r: r.update(averaging={"cell_size": [0.01, 0.01]})))
    assert result.exit_code == 2, result.output
    assert "averaging.cell_size" in result.output and "Traceback" not in result.output
