"""Kernel build time of a shipped scene with tidem's light kernel frontend against Taichi's own
(`tidem/runtime/taichi_frontend.py`), cold (empty kernel cache) and cached, in alternating rounds.

    python benchmarks/compile_frontend.py [SCENE] [ROUNDS]      # default fluidized_tube, 3 rounds

Each case runs in a process of its own with a kernel cache of its own: the cold build fills it, the
cached build (a second process) reads it. Prints one line per case and round, then the medians and
their ratios (light / Taichi's own).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile

BUILD = """
import sys, time
import tidem.runtime.taichi_frontend as frontend
if sys.argv[2] == "taichi":
    frontend.install = lambda: False
from tidem.runtime.startup import ensure_taichi
ensure_taichi("cpu", "float64")
from tidem.api import load_scene
from tidem.sim.model import build_model
from tidem.sim.solver import Solver
model = build_model(load_scene(sys.argv[1]))
t0 = time.perf_counter()
Solver(model).advance(2)
print(time.perf_counter() - t0)
"""


def build_seconds(scene: str, frontend: str, cache: str) -> float:
    env = dict(os.environ, TI_OFFLINE_CACHE_FILE_PATH=cache)
    done = subprocess.run([sys.executable, "-c", BUILD, scene, frontend], env=env, capture_output=True, text=True,
                          check=True)
    return float(done.stdout.strip().splitlines()[-1])


def main() -> None:
    scene = sys.argv[1] if len(sys.argv) > 1 else "fluidized_tube"
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    times: dict[tuple[str, str], list[float]] = {}
    for r in range(rounds):
        for frontend in ("light", "taichi"):
            cache = tempfile.mkdtemp(prefix="tidem_frontend_")
            try:
                for state in ("cold", "cached"):
                    s = build_seconds(scene, frontend, cache)
                    times.setdefault((frontend, state), []).append(s)
                    print(f"round {r + 1}: {frontend:6s} frontend, {state:6s} build {s:6.2f} s", flush=True)
            finally:
                shutil.rmtree(cache, ignore_errors=True)
    for state in ("cold", "cached"):
        light, own = (statistics.median(times[f, state]) for f in ("light", "taichi"))
        print(f"{scene}, {state} build: light {light:.2f} s, Taichi's own {own:.2f} s, ratio {light / own:.2f}")


if __name__ == "__main__":
    main()
