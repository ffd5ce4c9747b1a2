"""Settle the benchmark bed with tidem and store it as benchmarks/bed10k.npz.

Run once (about 2 minutes on 2 cores): python benchmarks/make_bed.py
"""

from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp
from tidem.runner.loop import run
from tidem.runtime.startup import ensure_taichi
from tidem.scene.load import load
from tidem.sim.model import build_model

here = Path(__file__).resolve().parent
ensure_taichi("cpu", "float64")
model = build_model(load(str(here / "settle_bed.toml")))
out = Path("renders") / "settle_bed"
result = run(model, out)
assert result.status == "finished", result.message
last = sorted((out / "snapshots").glob("*.vtp"))[-1]
points, data = read_vtp(last)
np.savez_compressed(here / "bed10k.npz", x=points[np.argsort(data["id"])])
top = points[:, 2].max()
print(f"settled bed: {len(points)} spheres, top at z = {top:.4f} m, mean speed {np.linalg.norm(data['velocity'], axis=1).mean():.2e} m/s")
