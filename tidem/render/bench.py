"""`tidem bench --render`: frames per second of the frame renderer (`render_frame`).

The bed is a slab like the shipped moving bed: 1 mm spheres on a cubic lattice, 4 deep, in a
front view of 16:9, drawn at 1280x720, coloured by speed (viridis) or by temperature
(inferno); random speeds and temperatures. Each case runs in its own process with llvmpipe
capped to the given thread count (the background renderer of a run uses 1): one warm-up
frame, then the timed frames, each read from its snapshot file and written as a PNG, as in a
run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

D = 0.001  # m, sphere diameter
DEPTH = 4  # spheres across the slab
SIZE = (1280, 720)


def slab(n: int) -> tuple[np.ndarray, tuple[float, ...]]:
    """About n sphere centres on a lattice DEPTH deep, 1.6 times wider than high (the plot part
    of a 16:9 frame); returns them and the domain bounds."""
    nz = max(1, round(np.sqrt(n / DEPTH / 1.6)))
    nx = max(1, round(n / DEPTH / nz))
    i, j, k = np.meshgrid(np.arange(nx), np.arange(DEPTH), np.arange(nz), indexing="ij")
    x = (np.stack([i, j, k], axis=-1).reshape(-1, 3) + 0.5) * D
    return x, (0.0, nx * D, 0.0, DEPTH * D, 0.0, 1.25 * nz * D)


def time_case(n: int, field: str, frames: int) -> dict:
    """Time `frames` frames of an n-sphere slab in this process (called by `run_render_bench`)."""
    from tidem.io.vtp import write_vtp
    from tidem.render.frames import FIELDS, FrameStyle, render_frame

    x, bounds = slab(n)
    rng = np.random.default_rng(1)
    data = {"radius": np.full(len(x), 0.5 * D), "velocity": rng.normal(0.0, 0.01, (len(x), 3)),
            "temperature": rng.uniform(293.15, 373.15, len(x))}
    clim = (0.0, 0.04) if field == "speed" else (293.15, 373.15)
    style = FrameStyle(field=field, clim=clim, colormap=FIELDS[field][1], size=SIZE, view="front",
                       bounds=bounds, tubes=[])
    with tempfile.TemporaryDirectory() as tmp:
        snap, png = Path(tmp) / "s.vtp", Path(tmp) / "f.png"
        write_vtp(snap, x, data, time=0.0)
        render_frame(snap, 0.0, style, png)  # warm-up: GL context, shader compilation
        t0 = time.perf_counter()
        for _ in range(frames):
            render_frame(snap, 0.0, style, png)
        wall = time.perf_counter() - t0
    return {"particles": len(x), "field": field, "size": list(SIZE), "frames": frames,
            "s_per_frame": wall / frames, "fps": frames / wall}


def run_render_bench(sizes: list[int], threads: int, out: Path | None) -> list[dict]:
    """Every (size, field) case in a fresh process; prints a table."""
    from tidem.render.gl import prepare_offscreen

    prepare_offscreen()
    rows = []
    print(f"{'N':>7} {'field':>12} {'threads':>7} {'size':>9} {'frames':>6} {'s/frame':>8} {'fps':>6}")
    for n in sizes:
        for field in ("speed", "temperature"):
            frames = max(3, min(20, 40000 // max(n, 1)))
            env = dict(os.environ, LP_NUM_THREADS=str(threads), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
            proc = subprocess.run([sys.executable, "-c", "import json, tidem.render.bench as b; "
                                   f"print(json.dumps(b.time_case({n}, {field!r}, {frames})))"],
                                  capture_output=True, text=True, env=env)
            if proc.returncode != 0:
                print(f"{n:>7} {field:>12} failed: {(proc.stderr.strip().splitlines() or [''])[-1]}")
                continue
            row = {**json.loads(proc.stdout.strip().splitlines()[-1]), "threads": threads}
            rows.append(row)
            print(f"{row['particles']:>7} {field:>12} {threads:>7} {'x'.join(map(str, SIZE)):>9} {frames:>6} "
                  f"{row['s_per_frame']:>8.3f} {row['fps']:>6.2f}", flush=True)
    if out is not None:
        Path(out).write_text(json.dumps(rows, indent=2))
    return rows
