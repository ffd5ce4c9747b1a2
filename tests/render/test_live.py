"""The live view under Xvfb: a screenshot of the X screen shows the particles in their
colours at their places; keys and sliders put events in the run's queue; without a display the run
goes on headless.

Xvfb (Debian's `xvfb`) is required in CI (TIDEM_REQUIRE_XVFB=1, set by .ci/run); a local run
without it skips these tests with a reason.
"""

import ctypes
import os
import shutil
import subprocess

import numpy as np
import pytest
from typer.testing import CliRunner

from tests.conftest import make_scene
from tidem.cli.commands import app

STEEL = {"density": 7800.0, "youngs_modulus": 2e9, "poisson_ratio": 0.3, "restitution": 0.5, "friction": 0.3,
         "conductivity": 16.0, "heat_capacity": 500.0}
SCREEN = (1280, 1024)


@pytest.fixture(scope="module")
def xvfb():
    """A private Xvfb server; yields its display name."""
    if shutil.which("Xvfb") is None:
        if os.environ.get("TIDEM_REQUIRE_XVFB"):
            pytest.fail("Xvfb is required here (apt-get install -y --no-install-recommends xvfb xauth)")
        pytest.skip("Xvfb is not installed (apt-get install -y --no-install-recommends xvfb xauth)")
    # Each xdist worker starts at a display number of its own: with -displayfd alone, two
    # workers raced for :0 as one server shut down while the other started (CI, 2026-11-25).
    # -noreset: by default the server resets when its last client leaves, and a window opened
    # during that reset fails ("Taichi fails to create a window", CI, 2026-11-25, under load).
    worker = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0").removeprefix("gw") or 0)
    for number in range(90 + 10 * worker, 100 + 10 * worker):
        r, w = os.pipe()
        server = subprocess.Popen(["Xvfb", f":{number}", "-displayfd", str(w), "-screen", "0",
                                   f"{SCREEN[0]}x{SCREEN[1]}x24", "-nolisten", "tcp", "-noreset"],
                                  pass_fds=(w,), stderr=subprocess.DEVNULL)
        os.close(w)
        with os.fdopen(r) as fh:
            ready = fh.readline().strip()  # the number once it serves; empty if it quit (display taken)
        if ready:
            break
        server.wait()
    else:
        pytest.fail("no free X display number for Xvfb in :90-:99 (+10 per xdist worker)")
    yield f":{number}"
    server.terminate()
    server.wait()


class XImage(ctypes.Structure):
    _fields_ = [("width", ctypes.c_int), ("height", ctypes.c_int), ("xoffset", ctypes.c_int),
                ("format", ctypes.c_int), ("data", ctypes.c_void_p), ("byte_order", ctypes.c_int),
                ("bitmap_unit", ctypes.c_int), ("bitmap_bit_order", ctypes.c_int), ("bitmap_pad", ctypes.c_int),
                ("depth", ctypes.c_int), ("bytes_per_line", ctypes.c_int), ("bits_per_pixel", ctypes.c_int)]


def screenshot(display: str) -> np.ndarray:
    """The whole X screen as an RGB array (XGetImage of the root window, 24-bit TrueColor)."""
    x11 = ctypes.CDLL("libX11.so.6")
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XDefaultRootWindow.restype = ctypes.c_ulong
    x11.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
    x11.XGetImage.restype = ctypes.POINTER(XImage)
    x11.XGetImage.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_int, ctypes.c_uint,
                              ctypes.c_uint, ctypes.c_ulong, ctypes.c_int]
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    d = x11.XOpenDisplay(display.encode())
    w, h = SCREEN
    img = x11.XGetImage(d, x11.XDefaultRootWindow(d), 0, 0, w, h, 0xFFFFFFFF, 2).contents  # ZPixmap
    raw = np.ctypeslib.as_array(ctypes.cast(img.data, ctypes.POINTER(ctypes.c_uint8)), shape=(h * img.bytes_per_line,))
    rgb = raw.reshape(h, img.bytes_per_line)[:, : 4 * w].reshape(h, w, 4)[:, :, 2::-1].copy()  # BGRX -> RGB
    x11.XCloseDisplay(d)
    return rgb


def two_spheres():
    """A cold (300 K) sphere left, a hot (900 K) one right, seen from the front."""
    d = {"distribution": "mono", "value": 0.02}
    return make_scene(materials={"steel": STEEL}, heat={},
                      particles=[{"name": "cold", "material": "steel", "diameter": d, "temperature": 300.0,
                                  "positions": [[-0.05, 0.0, 0.03]], "fixed": True},
                                 {"name": "hot", "material": "steel", "diameter": d, "temperature": 900.0,
                                  "positions": [[0.05, 0.0, -0.03]], "fixed": True}])


def test_window_shows_hot_and_cold_particles_in_place(xvfb, monkeypatch, solver_for):
    monkeypatch.setenv("DISPLAY", xvfb)
    from tidem.render.live import LiveView
    from tidem.render.settings import render_settings

    solver = solver_for(two_spheres())
    view = LiveView(solver.model, render_settings(solver.model))
    try:
        view.update(solver)
        img = screenshot(xvfb)
    finally:
        view.close()
    white = np.argwhere(img.sum(axis=2) == 765)
    top, left = white.min(axis=0)  # the window: white on the black root
    w, h = view.res
    assert white.max(axis=0).tolist() == [top + h - 1, left + w - 1]
    centres = view.to_window(np.array([[-0.05, 0.0, 0.03], [0.05, 0.0, -0.03]]))
    (cx, cy), (hx, hy) = [(int(left + u * w), int(top + (1 - v) * h)) for u, v in centres]
    r = int(0.6 * 0.01 * view.scale)
    cold = img[cy - r: cy + r, cx - r: cx + r].reshape(-1, 3).astype(int)
    hot = img[hy - r: hy + r, hx - r: hx + r].reshape(-1, 3).astype(int)
    assert (cold.sum(axis=1) < 60).all(), "inferno's cold end is near black"
    assert ((hot[:, 0] > 230) & (hot[:, 1] > 230) & (hot[:, 2] > 120) & (hot[:, 2] < 200)).all(), \
        "inferno's hot end is pale yellow"
    between = img[(cy + hy) // 2, (cx + hx) // 2]
    assert between.tolist() == [255, 255, 255], "background between the spheres"


def test_keys_and_sliders_put_events_in_the_run_queue(xvfb, monkeypatch, solver_for, tmp_path):
    """Space pauses (again: resumes), n steps, f and v show the next field and view, s the next slice, + raises the picked
    control by a twentieth of its slider's span: each an event in the run's queue
    (`tidem.runner.controls`), which the run loop applies (tests/runner/test_steering.py)."""
    monkeypatch.setenv("DISPLAY", xvfb)
    import taichi as ti

    from tidem.render.live import LiveView
    from tidem.render.settings import render_settings
    from tidem.runner.controls import Controls
    from tidem.runner.steering import Steering

    raw = two_spheres()
    raw["domain"].update(walls=["z-"], wall_temperature=350.0)
    solver = solver_for(raw)
    controls = Controls()
    steering = Steering(solver.model, solver, tmp_path, controls, raw)
    view = LiveView(solver.model, render_settings(solver.model))
    view.attach(controls, steering)
    presses = [[type("Event", (), {"key": key})() for key in (ti.GUI.SPACE, "n", "f", "v", "s", "+")]]
    monkeypatch.setattr(view.gui, "get_events", lambda *_filter: presses.pop(0) if presses else [])
    try:
        view.update(solver)
        events = controls.take()
        steering.paused = True  # the run loop applied the pause: space now resumes
        view._next = -1e9
        presses.append([type("Event", (), {"key": ti.GUI.SPACE})()])
        view.update(solver, paused=True)
        events += controls.take()
    finally:
        view.close()
    kinds = [(e.kind, e.key, e.value) for e in events]
    assert kinds[:5] == [("pause", "", None), ("step", "", None), ("show", "", "speed"), ("look", "", "side"),
                         ("cut", "", 0.25)]
    assert kinds[5][:2] == ("set", "domain.wall_temperature") and kinds[5][2] > 350.0
    assert kinds[6] == ("resume", "", None)


def test_scene_view_runs_with_a_window_and_without_a_display(xvfb, monkeypatch, tmp_path):
    args = ["scene", "sphere_impact", "--smoke", "--quiet", "--no-render", "--view"]
    monkeypatch.setenv("DISPLAY", xvfb)
    result = CliRunner().invoke(app, args + ["--out", str(tmp_path / "a")])
    assert result.exit_code == 0, result.output
    assert "--view" not in result.output
    monkeypatch.delenv("DISPLAY")
    result = CliRunner().invoke(app, args + ["--out", str(tmp_path / "b")])
    assert result.exit_code == 0, result.output
    lines = [ln for ln in result.output.splitlines() if "--view" in ln]
    assert lines == ["tidem: --view: no display ($DISPLAY is not set); running without the live view"]


def test_scene_view_goes_on_headless_when_the_window_fails(monkeypatch, tmp_path):
    import tidem.render.live as live

    def no_window(*_args):
        raise RuntimeError("[x11.cpp:create_window@154] Taichi fails to create a window.\nmore")

    monkeypatch.setattr(live, "display_problem", lambda: None)
    monkeypatch.setattr(live, "LiveView", no_window)
    args = ["scene", "sphere_impact", "--smoke", "--quiet", "--no-render", "--view", "--out", str(tmp_path)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    lines = [ln for ln in result.output.splitlines() if "--view" in ln]
    assert lines == ["tidem: --view: the window could not be opened ([x11.cpp:create_window@154] Taichi fails to "
                     "create a window.); running without the live view"]
