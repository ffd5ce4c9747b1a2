"""What watching a run costs: the same scene run headless, with the browser view open (`--serve`,
with a client asking for the state four times a second, as the page does) and with the window
(`--view`, under Xvfb), alternating, and each run's stepping wall time (run.json `wall_s`, set-up
excluded) against the headless runs'. Then how long one refresh of each view takes with 100 000
particles (the views draw a fixed subset of at most 20 000).

    python benchmarks/view_cost.py [--scene fluidized_tube] [--t-end 0.2] [--rounds 2] [--refresh-only]
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path


def one_run(scene: str, t_end: float, how: str, folder: Path) -> float:
    """Stepping wall time [s] of one run, `how`: headless, serve or view."""
    cmd = [sys.executable, "-m", "tidem", "scene", scene, "--t-end", str(t_end), "--no-render", "--quiet",
           "--out", str(folder)]
    if how == "serve":
        cmd += ["--serve", "0"]
    if how == "view":
        cmd = ["xvfb-run", "-a"] + cmd + ["--view"]
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    if how == "serve":
        line = ""
        while "serving the live view at" not in line:
            line = proc.stderr.readline()
        url = line.split(" at ")[1].split()[0]

        def client():  # the page's polling
            while proc.poll() is None:
                try:
                    urllib.request.urlopen(url + "state", timeout=5).read()
                except OSError:
                    return
                time.sleep(0.25)

        threading.Thread(target=client, daemon=True).start()
    proc.communicate()
    return json.loads((folder / "run.json").read_text())["wall_s"]


def refresh_times(n: int = 100_000) -> dict[str, float]:
    """Milliseconds of one state capture of the browser view and one capture and draw of the window
    (under Xvfb where there is one) for a bed of n particles."""
    from tests.conftest import make_scene  # noqa: F401  (sets up Taichi as the tests do)
    from tidem.render.serve import BrowserView
    from tidem.render.settings import render_settings
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    side = round((n / 0.52) ** (1 / 3)) * 0.001
    raw = make_scene(domain={"min": [0, 0, 0], "max": [side, side, 2 * side], "walls": "auto", "gravity": [0, 0, -9.81]},
                     particles=[{"name": "bed", "material": "steel", "diameter": {"value": 0.001}, "count": n,
                                 "region": {"min": [0, 0, 0], "max": [side, side, 2 * side]}}])
    solver = Solver(build_model(validate(raw)))
    out = {"particles": float(solver.model.capacity)}
    view = BrowserView(solver.model, render_settings(solver.model), 0)
    view.update(solver)  # the field reads compiled
    start = time.perf_counter()
    for _ in range(5):
        view._next = -1e9
        view.state()  # a page asks
        view.update(solver)
    out["browser_state_ms"] = 1e3 * (time.perf_counter() - start) / 5
    out["browser_state_kB"] = len(view.state()) / 1e3
    view.close()
    if os.environ.get("DISPLAY"):
        from tidem.render.live import LiveView

        live = LiveView(solver.model, render_settings(solver.model))
        live.update(solver)
        start = time.perf_counter()
        for _ in range(5):
            live._next = -1e9
            live.update(solver)
        out["window_refresh_ms"] = 1e3 * (time.perf_counter() - start) / 5
        live.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="fluidized_tube")
    parser.add_argument("--t-end", type=float, default=0.2)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--refresh-only", action="store_true", help="only the refresh times with 100 000 particles")
    args = parser.parse_args()
    if not args.refresh_only:
        kinds = ["headless", "serve"] + (["view"] if shutil.which("xvfb-run") else [])
        walls = {k: [] for k in kinds}
        with tempfile.TemporaryDirectory() as tmp:
            for r in range(args.rounds):
                for how in kinds if r % 2 == 0 else kinds[::-1]:
                    walls[how].append(one_run(args.scene, args.t_end, how, Path(tmp) / f"{how}{r}"))
                    print(f"round {r + 1}: {how:8s} {walls[how][-1]:.2f} s", flush=True)
        base = sum(walls["headless"]) / len(walls["headless"])
        for how in kinds:
            mean = sum(walls[how]) / len(walls[how])
            print(f"{how:8s} mean {mean:.2f} s, {mean / base:.3f}x headless")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    print(json.dumps(refresh_times(), indent=1))


if __name__ == "__main__":
    main()
