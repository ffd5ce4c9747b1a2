"""Frames show real content: size, colours at the right end of the colour map, tubes."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.io.vtp import write_vtp
from tidem.render.frames import FrameStyle, bar_format, frame_size, render_frame
from tidem.render.gl import RenderUnavailable, prepare_offscreen

try:
    prepare_offscreen()
except RenderUnavailable:  # pragma: no cover
    pytest.skip("no off-screen OpenGL library", allow_module_level=True)

BOUNDS = (0.0, 0.2, 0.0, 0.02, 0.0, 0.1)


def coloured(img, region):
    """Pixels of a region that are neither background white nor near-black edges."""
    sub = img[region].reshape(-1, img.shape[2])[:, :3].astype(float)
    keep = (sub.sum(axis=1) < 700) & (sub.max(axis=1) > 60)
    return sub[keep]


def test_slow_and_fast_particles_take_the_two_ends_of_the_colour_map(tmp_path):
    import imageio.v2 as imageio

    snap = tmp_path / "s.vtp"
    write_vtp(snap, np.array([[0.05, 0.01, 0.05], [0.15, 0.01, 0.05]]),
              {"radius": np.array([0.02, 0.02]), "velocity": np.array([[0.0, 0, 0], [1.0, 0, 0]])})
    style = FrameStyle(field="speed", clim=(0.0, 1.0), colormap="viridis", size=frame_size("front", BOUNDS),
                       view="front", bounds=BOUNDS, tubes=[])
    png = tmp_path / "f.png"
    render_frame(snap, 0.0, style, png)
    img = imageio.imread(png)
    assert img.shape[:2] == (style.size[1], style.size[0])
    plot_w = int(0.8 * img.shape[1])
    slow = coloured(img, np.s_[:, : plot_w // 2])
    fast = coloured(img, np.s_[:, plot_w // 2: plot_w])
    assert len(slow) > 500 and len(fast) > 500
    r, g, b = slow.mean(axis=0)
    assert b > g and b > r, "the slow particle is at the dark purple end of viridis"
    r, g, b = fast.mean(axis=0)
    assert g > b and r > b, "the fast particle is at the yellow end of viridis"


def test_powder_finer_than_a_pixel_is_drawn_and_labels_are_whole_kelvin(tmp_path):
    """A 10 um grain in a 0.2 m frame (0.14 mm per pixel) shows as a dot of a few pixels
    across (drawn 2 pixels in radius; at its own size it does not show at all); a 300-9000 K
    bar is labelled 300 ... 9000, not 9e+03."""
    import imageio.v2 as imageio

    style = FrameStyle(field="speed", clim=(0.0, 1.0), colormap="viridis", size=frame_size("front", BOUNDS),
                       view="front", bounds=BOUNDS, tubes=[])
    dark = []
    for name, radius in (("dust", 5e-6), ("none", None)):
        snap = tmp_path / f"{name}.vtp"
        points = np.array([[0.1, 0.01, 0.05]]) if radius else np.zeros((0, 3))
        write_vtp(snap, points, {"radius": np.array([radius] if radius else []), "velocity": np.zeros((len(points), 3))})
        render_frame(snap, 0.0, style, tmp_path / f"{name}.png")
        img = imageio.imread(tmp_path / f"{name}.png")[:, : int(0.8 * style.size[0]), :3].astype(int)
        dark.append(int((img.sum(axis=2) < 700).sum()))
    assert dark[0] - dark[1] >= 9
    assert bar_format((300.0, 9000.0)) == "%.0f" and bar_format((298.0, 500.0)) == "%.0f"
    assert bar_format((0.0, 0.04)) == "%.2f" and bar_format((293.15, 295.0)) == "%.1f"
    assert bar_format((0.0, 2e-5)) == "%.3g"


def test_scene_run_writes_frames_and_movie(tmp_path):
    out = tmp_path / "run"
    result = CliRunner().invoke(app, ["scene", "sphere_impact", "--out", str(out), "--quiet",
                                      "--set", "output.snapshots=4"])
    assert result.exit_code == 0, result.output
    frames = sorted((out / "frames").glob("frame_*.png"))
    assert len(frames) == (out / "snapshots.pvd").read_text().count("<DataSet")
    movie = out / "sphere_impact.mp4"
    assert movie.stat().st_size > 1000
    import imageio.v2 as imageio

    reader = imageio.get_reader(movie)
    assert reader.count_frames() == len(frames)
    for plot in ("energy.png", "timeseries.png"):
        assert (out / "plots" / plot).stat().st_size > 10000
    # the frames rendered in the background during the run are those of `tidem render`
    during = {p.name: p.read_bytes() for p in frames}
    result = CliRunner().invoke(app, ["render", str(out)])
    assert result.exit_code == 0, result.output
    assert {p.name: p.read_bytes() for p in sorted((out / "frames").glob("frame_*.png"))} == during
    # re-render with another field and range, without re-running
    result = CliRunner().invoke(app, ["render", str(out), "--field", "contacts", "--range", "0,1"])
    assert result.exit_code == 0, result.output
    assert json.loads((out / "run.json").read_text())["status"] == "finished"


def test_hot_and_cold_particles_take_the_two_ends_of_the_temperature_map(tmp_path):
    import imageio.v2 as imageio

    snap = tmp_path / "t.vtp"
    write_vtp(snap, np.array([[0.05, 0.01, 0.05], [0.15, 0.01, 0.05]]),
              {"radius": np.array([0.02, 0.02]), "velocity": np.zeros((2, 3)), "temperature": np.array([300.0, 900.0])})
    style = FrameStyle(field="temperature", clim=(300.0, 900.0), colormap="inferno",
                       size=frame_size("front", BOUNDS), view="front", bounds=BOUNDS, tubes=[])
    render_frame(snap, 0.0, style, tmp_path / "t.png")
    img = imageio.imread(tmp_path / "t.png")[:, :, :3].astype(float)
    write_vtp(snap, np.array([[0.15, 0.01, 0.05]]),
              {"radius": np.array([0.02]), "velocity": np.zeros((1, 3)), "temperature": np.array([900.0])})
    render_frame(snap, 0.0, style, tmp_path / "hot_only.png")
    ref = imageio.imread(tmp_path / "hot_only.png")[:, :, :3].astype(float)
    plot_w = int(0.8 * img.shape[1])

    def dark(a):
        return int((a[:, : plot_w // 2].sum(axis=2) < 150).sum())

    # inferno: the cold end is near black, the hot end pale yellow
    assert dark(img) - dark(ref) > 500, "the cold particle adds near-black pixels"
    hot = img[:, plot_w // 2: plot_w].reshape(-1, 3)
    hot = hot[(hot[:, 0] > 200) & (hot[:, 1] > 150) & (hot[:, 2] < 200)]
    assert len(hot) > 500, "yellow pixels of the hot particle"


def test_render_refuses_bad_options(tmp_path):
    result = CliRunner().invoke(app, ["render", str(tmp_path)])
    assert result.exit_code == 2 and "not a run folder" in result.output
    (tmp_path / "run.json").write_text("{}")
    (tmp_path / "snapshots.pvd").write_text('<?xml version="1.0"?><VTKFile type="Collection"><Collection/></VTKFile>')
    result = CliRunner().invoke(app, ["render", str(tmp_path)])
    assert result.exit_code == 2 and "empty" in result.output


def test_heated_tube_takes_its_temperature_colour(tmp_path):
    """A tube at the top of the range is drawn in the hot end of the map; grey for speed."""
    import imageio.v2 as imageio

    snap = tmp_path / "t.vtp"
    write_vtp(snap, np.array([[0.02, 0.01, 0.02]]),
              {"radius": np.array([0.005]), "velocity": np.zeros((1, 3)), "temperature": np.array([300.0])})
    tube = {"c": [0.1, 0.0, 0.05], "mask": [1.0, 0.0, 1.0], "r": 0.03, "T": 900.0}
    counts = {}
    for field in ("temperature", "speed"):
        style = FrameStyle(field=field, clim=(300.0, 900.0), colormap="inferno",
                           size=frame_size("front", BOUNDS), view="front", bounds=BOUNDS, tubes=[tube])
        render_frame(snap, 0.0, style, tmp_path / f"{field}.png")
        img = imageio.imread(tmp_path / f"{field}.png")[:, :, :3].astype(float)
        img = img[:, : int(0.8 * img.shape[1])].reshape(-1, 3)  # the plot, not the colour bar
        counts[field] = int(((img[:, 0] > 200) & (img[:, 1] > 150) & (img[:, 2] < 200)).sum())
    assert counts["temperature"] > 2000, "pale-yellow (hot) tube pixels"
    assert counts["speed"] < 100, "a grey tube when frames show speed"


def test_distributor_nozzle_is_drawn_under_its_part_of_the_floor(tmp_path):
    import imageio.v2 as imageio

    snap = tmp_path / "s.vtp"
    write_vtp(snap, np.array([[0.1, 0.01, 0.05]]), {"radius": np.array([0.005]), "velocity": np.zeros((1, 3))})
    style = FrameStyle(field="speed", clim=(0.0, 1.0), colormap="viridis", size=frame_size("front", BOUNDS),
                       view="front", bounds=BOUNDS, tubes=[],
                       distributor=[{"background": True, "velocity": 0.3},
                                    {"x": [0.15, 0.2], "y": None, "velocity": 1.2}])
    png = tmp_path / "f.png"
    render_frame(snap, 0.0, style, png)
    rgb = imageio.imread(png)[:, :, :3].astype(int)
    grey = np.argwhere(np.abs(rgb - [176, 176, 176]).sum(axis=2) < 12)
    blue = np.argwhere(np.abs(rgb - [31, 59, 143]).sum(axis=2) < 12)
    assert len(blue) > 100
    grey = grey[np.isin(grey[:, 0], blue[:, 0])]  # the bar's rows
    assert len(grey) > 200
    left, right = grey[:, 1].min(), max(grey[:, 1].max(), blue[:, 1].max())
    assert blue[:, 1].min() > left + 0.7 * (right - left), "the nozzle sits at the right quarter of the floor"
    assert abs(blue[:, 0].mean() - grey[:, 0].mean()) < 3, "on the same bar below the floor"
