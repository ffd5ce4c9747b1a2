"""The browser view (`tidem scene SCENE --serve PORT`, `tidem.render.serve`): the page, the state and
the event endpoint over HTTP; and the page in a real headless browser (Debian's Chromium driven by
Playwright), whose inlet-velocity slider changes the running bed: the change is in steering.csv and
the pressure drop in timeseries.csv rises after it.

Chromium and Playwright are required in CI (TIDEM_REQUIRE_BROWSER=1, set by .ci/run); a local run
without them skips the browser test with a reason.
"""

import base64
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

from tests.kernels.test_gas import packed_column
from tidem.runner.controls import Controls, Event
from tidem.runner.steering import Steering

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]


def post(url, message):
    request = urllib.request.Request(url + "event", data=json.dumps(message).encode(), method="POST",
                                     headers={"Content-Type": "application/json"})
    try:
        return urllib.request.urlopen(request, timeout=10).status, ""
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode()


def test_page_state_and_events_over_http(solver_for, tmp_path):
    from tidem.render.serve import BrowserView
    from tidem.render.settings import render_settings

    solver = solver_for(packed_column(0.1))
    view = BrowserView(solver.model, render_settings(solver.model), 0)
    try:
        controls = Controls()
        view.attach(controls, Steering(solver.model, solver, tmp_path, controls, packed_column(0.1)))
        view.update(solver)
        page = urllib.request.urlopen(view.url, timeout=10).read().decode()
        assert "<canvas id=\"bed\">" in page
        state = json.loads(urllib.request.urlopen(view.url + "state", timeout=10).read())
        assert state["t"] == 0.0 and state["shown"] == state["active"] == solver.model.capacity
        x = np.frombuffer(base64.b64decode(state["x"]), "<f4").reshape(-1, 3)
        assert np.allclose(x, solver.state.x.to_numpy(), atol=1e-6)
        assert len(np.frombuffer(base64.b64decode(state["c"]), "<u4")) == state["shown"]
        assert [c["key"] for c in state["controls"]] == ["gas.inlet_velocity"]
        assert state["controls"][0]["value"] == 0.1
        assert post(view.url, {"kind": "set", "key": "gas.inlet_velocity", "value": 0.2}) == (204, "")
        assert post(view.url, {"kind": "pause"}) == (204, "")
        assert post(view.url, {"kind": "cut", "value": 0.1}) == (204, "")
        assert post(view.url, {"kind": "set", "key": "gas.inlet_velocity"}) == (
            400, "a set event needs 'key' and a number 'value'")
        assert post(view.url, {"kind": "stop"})[0] == 400
        events = [(e.kind, e.key, e.value) for e in controls.take()]
        assert events == [("set", "gas.inlet_velocity", 0.2), ("pause", "", None), ("cut", "", 0.1)]
        view.steering.apply(Event("cut", value=0.1))
        view._next = -1e9
        view.update(solver)
        state = json.loads(view.state())
        assert state["slice"] == 0.1 and 0 < state["shown"] < state["active"]  # a tenth of the depth about the middle
    finally:
        view.close()


def test_serve_alone_takes_the_default_port():
    from tidem.cli.commands import SERVE_PORT, serve_port_given

    assert serve_port_given(["scene", "x", "--serve"]) == ["scene", "x", f"--serve={SERVE_PORT}"]
    assert serve_port_given(["scene", "--serve", "--quiet"]) == ["scene", f"--serve={SERVE_PORT}", "--quiet"]
    assert serve_port_given(["scene", "--serve", "9001"]) == ["scene", "--serve", "9001"]


def test_taken_port_is_refused_in_one_line(tmp_path):
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run([sys.executable, "-m", "tidem", "scene", "sphere_impact", "--smoke", "--no-render",
                               "--quiet", "--serve", str(port), "--out", str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1].startswith(f"--serve {port}: cannot serve on 127.0.0.1:{port}")


@pytest.fixture
def chromium():
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        sync_playwright = None
    if sync_playwright is None or shutil.which(CHROMIUM) is None:
        if os.environ.get("TIDEM_REQUIRE_BROWSER"):
            pytest.fail("Chromium and Playwright are required here (apt-get install chromium; pip install playwright)")
        pytest.skip("Chromium (Debian's chromium) or Playwright is not installed")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield browser
        browser.close()


def test_a_browser_moves_the_inlet_velocity_of_a_running_bed(chromium, tmp_path):
    scene = tmp_path / "bed.toml"
    scene.write_text("""name = "served"
[domain]
min = [0.0, 0.0, 0.0]
max = [0.016, 0.004, 0.06]
periodic = ["y"]
[materials.sand]
density = 2500.0
youngs_modulus = 2e6
poisson_ratio = 0.3
restitution = 0.9
friction = 0.0
[[particles]]
name = "bed"
material = "sand"
diameter = { value = 0.001 }
region = { min = [0.0, 0.0, 0.0], max = [0.016, 0.004, 0.02] }
[gas]
cell_size = 0.004
inlet_velocity = 0.2
[numerics]
t_end = 20.0
max_overlap = 0.1
[output]
timeseries_interval = 0.002
interval = 1.0
""")
    out = tmp_path / "run"
    run = subprocess.Popen([sys.executable, "-m", "tidem", "scene", str(scene), "--out", str(out), "--no-render",
                            "--quiet", "--serve", "0"], stderr=subprocess.PIPE, text=True)
    try:
        line = ""
        while "serving the live view at" not in line:
            line = run.stderr.readline()
            assert line, "the run ended before serving"
        url = line.split(" at ")[1].split()[0]
        page = chromium.new_page(viewport={"width": 1100, "height": 700})
        page.goto(url)
        slider = page.locator('input[data-key="gas.inlet_velocity"]')
        slider.wait_for(timeout=120_000)  # the kernels compile first
        page.wait_for_function("() => document.getElementById('time').textContent.includes('t = ')")
        slider.focus()
        page.keyboard.press("End")  # the slider's top: the Courant limit's velocity
        page.wait_for_function("() => document.getElementById('changes').textContent.includes('gas.inlet_velocity')",
                               timeout=60_000)
        start = time.monotonic()
        while time.monotonic() - start < 120:  # 0.05 s of bed time after the change
            rows = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
            steered = np.genfromtxt(out / "steering.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
            if rows["time_s"][-1] > float(steered["time_s"]) + 0.05:
                break
            time.sleep(1)
    finally:
        run.send_signal(signal.SIGINT)
        run.wait(timeout=120)
    key, value = str(steered["key"]), float(steered["value"])
    assert key == "gas.inlet_velocity" and value > 0.5
    t, dp = rows["time_s"], rows["gas_pressure_drop_Pa"]
    t_change = float(steered["time_s"])
    before, after = dp[(t > t_change - 0.02) & (t < t_change)], dp[t > t_change + 0.02]
    assert after.mean() > 1.5 * before.mean(), (before.mean(), after.mean())
