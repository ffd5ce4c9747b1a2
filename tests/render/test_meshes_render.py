"""Mesh walls in the frames: drawn grey, or in the colour map's colour of their temperature; a
closed vessel does not hide the bed (its front half is cut away); a moving mesh is drawn at the
frame's time; and a run folder's meshes reach the frames through run.json alone."""

import json

import numpy as np
import pytest

from tidem.io.mesh_output import MeshOutput, mesh_geometry
from tidem.io.vtp import write_pvd, write_vtp
from tidem.render.frames import FrameStyle, frame_size, render_frame
from tidem.render.gl import RenderUnavailable, prepare_offscreen
from tidem.render.meshes import mesh_surface
from tidem.walls.mesh_walls import MeshWall

try:
    prepare_offscreen()
except RenderUnavailable:  # pragma: no cover
    pytest.skip("no off-screen OpenGL library", allow_module_level=True)

BOUNDS = (0.0, 0.2, 0.0, 0.1, 0.0, 0.2)
CUBE_T = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], dtype=np.int32)


def box(lo, hi, **kw) -> MeshWall:
    """A closed box of 12 triangles."""
    v = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], float)
    return MeshWall(name="meshes[0]", vertices=v, triangles=CUBE_T.copy(), material="steel", **kw)


def plate(x0, **kw) -> MeshWall:
    """A 4 cm square in the x-z plane at the back of the domain, left edge at x0."""
    v = np.array([[x0, 0.08, 0.08], [x0 + 0.04, 0.08, 0.08], [x0 + 0.04, 0.08, 0.12], [x0, 0.08, 0.12]])
    return MeshWall(name="meshes[0]", vertices=v, triangles=np.array([[0, 1, 2], [0, 2, 3]]), material="steel", **kw)


def frame(tmp_path, meshes, field="speed", t=0.0, bed=True, view="front"):
    """Render a frame (a 4 x 4 x 2 block of particles in the domain centre) and return its RGB."""
    import imageio.v2 as imageio

    g = np.linspace(-0.03, 0.03, 4)
    points = np.array([[0.1 + x, 0.05 + y, 0.1 + z] for x in g for y in (-0.01, 0.01) for z in g]) if bed else np.zeros((0, 3))
    snap = tmp_path / "s.vtp"
    write_vtp(snap, points, {"radius": np.full(len(points), 0.008), "velocity": np.zeros((len(points), 3)),
                             "temperature": np.full(len(points), 300.0)})
    clim, cmap = ((300.0, 500.0), "inferno") if field == "temperature" else ((0.0, 1.0), "viridis")
    style = FrameStyle(field=field, clim=clim, colormap=cmap, size=frame_size(view, BOUNDS, 240), view=view,
                       bounds=BOUNDS, tubes=[], meshes=meshes)
    png = tmp_path / "f.png"
    render_frame(snap, t, style, png)
    return imageio.imread(png)[..., :3].astype(int)


def changed(a, b):
    """Pixels where two frames differ: [n, 2] (row, column)."""
    return np.argwhere(np.abs(a - b).sum(axis=2) > 30)


def test_a_plain_mesh_is_grey_and_a_heated_one_takes_its_temperature_colour(tmp_path):
    empty = frame(tmp_path, [], bed=False)
    grey = frame(tmp_path, [plate(0.08)], bed=False)
    where = changed(grey, empty)
    assert len(where) > 200, "the plate shows"
    r, g, b = grey[where[:, 0], where[:, 1]].mean(axis=0)
    assert max(r, g, b) - min(r, g, b) < 15 and 90 < r < 235, "grey, not white or coloured"
    hot = frame(tmp_path, [plate(0.08, temperature=450.0)], field="temperature", bed=False)
    r, g, b = hot[where[:, 0], where[:, 1]].mean(axis=0)
    assert r > g + 40 > b + 40, "450 K on 300-500 K of inferno is orange"
    adiabatic = frame(tmp_path, [plate(0.08)], field="temperature", bed=False)
    r, g, b = adiabatic[where[:, 0], where[:, 1]].mean(axis=0)
    assert max(r, g, b) - min(r, g, b) < 15, "a mesh without a temperature stays grey"


def test_a_closed_vessel_does_not_hide_the_bed(tmp_path):
    bare = frame(tmp_path, [])
    vessel = box((0.03, 0.01, 0.03), (0.17, 0.09, 0.17))
    inside = frame(tmp_path, [vessel])
    particles = changed(bare, frame(tmp_path, [], bed=False))
    assert len(particles) > 500
    hidden = changed(bare[particles[:, 0], particles[:, 1]][None], inside[particles[:, 0], particles[:, 1]][None])
    assert len(hidden) < 0.02 * len(particles), "the particles inside show unchanged"
    walls = changed(frame(tmp_path, [vessel], bed=False), frame(tmp_path, [], bed=False))
    assert len(walls) > 5 * len(particles) / 4, "the back of the vessel shows around them"
    surface = mesh_surface(vessel, 0.0, BOUNDS, "front")
    assert surface.bounds[3] <= 0.09 + 1e-9 and surface.bounds[2] == pytest.approx(0.05), "the back half only"


def test_a_moving_mesh_is_drawn_at_the_frames_time(tmp_path):
    moving = plate(0.02, velocity=(0.1, 0.0, 0.0))
    cols = [changed(frame(tmp_path, [moving], t=t, bed=False), frame(tmp_path, [], t=t, bed=False))[:, 1].mean()
            for t in (0.0, 1.0)]  # the same time stamp in both
    cols_still = changed(frame(tmp_path, [plate(0.12)], bed=False), frame(tmp_path, [], bed=False))[:, 1].mean()
    assert cols[1] > cols[0] + 50, "it moved 10 cm to the right"
    assert cols[1] == pytest.approx(cols_still, abs=2), "to where a plate at x0 + v t is drawn"


def test_run_folder_meshes_reach_the_frames_through_run_json(tmp_path):
    from tidem.render.movie import frame_path, render_frames, style_for

    drum = box((0.03, 0.01, 0.03), (0.17, 0.09, 0.17), center=(0.1, 0.05, 0.1), axis=(0.0, 1.0, 0.0), speed=1.0,
                temperature=450.0)
    entries = []
    out = MeshOutput(tmp_path, [drum], entries)
    (tmp_path / "snapshots").mkdir()
    for k in range(2):
        name = f"snapshots/snap_{k:05d}.vtp"
        write_vtp(tmp_path / name, np.zeros((0, 3)), {"radius": np.zeros(0), "velocity": np.zeros((0, 3)),
                                                      "temperature": np.zeros(0)}, time=0.5 * k)
        entries.append((0.5 * k, name))
        out.snapshot()
    write_pvd(tmp_path / "snapshots.pvd", entries)
    info = {"render": {"field": "temperature", "range": [300.0, 500.0], "view": "front", "height": 240},
            "render_geometry": {"bounds": list(BOUNDS), "periodic": [False] * 3, "tubes": [],
                                "meshes": mesh_geometry([drum])}}
    (tmp_path / "run.json").write_text(json.dumps(info))
    style = style_for(tmp_path)
    assert len(style.meshes) == 1 and style.meshes[0].moving and style.meshes[0].temperature == 450.0
    assert np.allclose(style.meshes[0].points_at(0.5), drum.points_at(0.5))
    render_frames(tmp_path, style)
    import imageio.v2 as imageio

    img = imageio.imread(frame_path(tmp_path, 1))[..., :3].astype(int)
    orange = (img[..., 0] > img[..., 1] + 40) & (img[..., 1] > img[..., 2] + 40)
    assert orange[:, : int(0.75 * img.shape[1])].sum() > 1000, "the heated drum is drawn in its colour"
    (tmp_path / "meshes" / "mesh0.vtp").unlink()
    with pytest.raises(ValueError, match="mesh0.vtp is missing"):
        style_for(tmp_path)


def test_colour_range_spans_the_meshes_temperature_and_speed():
    from tests.conftest import make_scene
    from tidem.render.settings import default_range
    from tidem.scene.load import validate
    from tidem.sim.model import build_model

    steel = {"density": 7800.0, "youngs_modulus": 2e9, "poisson_ratio": 0.3, "restitution": 0.5, "friction": 0.3,
             "conductivity": 16.0, "heat_capacity": 500.0}
    model = build_model(validate(make_scene(materials={"steel": steel}, heat={"initial_temperature": 300.0})))
    model.meshes = [box((-0.05, -0.05, -0.05), (0.05, 0.05, 0.05), temperature=650.0, center=(0.0, 0.0, 0.0),
                        axis=(0.0, 0.0, 1.0), speed=10.0)]
    assert default_range(model, "temperature") == (300.0, 650.0)
    assert default_range(model, "speed")[1] == pytest.approx(10.0 * 0.05 * np.sqrt(2))
