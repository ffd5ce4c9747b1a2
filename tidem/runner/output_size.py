"""Disk space a run will write, estimated before it starts (`tidem scene` refuses a run its output
folder cannot hold: one that fills the disk half-way would stop without its movie), and the
output cadence the run loop writes at.

Per snapshot: the particle arrays of the .vtp (positions, radius, velocity, spin, id, group,
contacts; temperature with heat, grains when coarse-grained) for every particle the run can
hold, the gas .vti (eight values per cell) with a gas phase, a moving mesh wall's .vtp (vertices,
temperature, triangles), and a PNG frame when rendering.
The factor 1.2 covers the files' headers and per-array offsets (a fluidized_tube snapshot of
12 978 particles is 1.51 MB: 116 B per particle against 100 B of arrays). The time series adds
about 210 B per row (measured on fluidized_tube).
"""

from __future__ import annotations

import math

from tidem.gas.geometry import gas_grid

OVERHEAD = 1.2
PARTICLE_BYTES = 3 * 8 + 8 + 3 * 8 + 3 * 8 + 3 * 4  # positions, radius, velocity, omega; id, group, contacts
GAS_BYTES_PER_CELL = 8 * 8  # voidage, pressure, velocity (3), temperature, O2, solid
FRAME_BYTES = 400 * 1024  # a temperature-coloured PNG frame (gallery frames are 50-300 KiB)
ROW_BYTES = 210  # one time-series row


def cadence(scene, t_end: float) -> tuple[float, float]:
    """(snapshot interval, time-series interval) [s] from the scene's output table (the run loop's)."""
    snap_dt = scene.output.interval or t_end / scene.output.snapshots
    return snap_dt, scene.output.timeseries_interval or snap_dt / 10.0


def output_bytes(model, frames: bool) -> tuple[int, int]:
    """(snapshots, bytes) a run of `model` writes, with PNG frames if `frames`: a snapshot at
    t = 0 and one every snapshot interval, at most one snapshot and one time-series row a step."""
    f = model.features
    per_particle = PARTICLE_BYTES + 8 * bool(f.heat) + 8 * bool(f.coarse_grain)
    per_snapshot = model.capacity * per_particle
    if f.gas:
        per_snapshot += math.prod(gas_grid(model.scene).cells) * GAS_BYTES_PER_CELL
    per_snapshot += sum(len(m.vertices) * (3 * 8 + 8 * (m.temperature is not None)) + len(m.triangles) * (3 * 8 + 8)
                        for m in model.meshes if m.moving or "temperature" in m.schedules)  # points (temperature),
    # connectivity and offsets of each mesh written at every snapshot
    per_snapshot = per_snapshot * OVERHEAD + FRAME_BYTES * frames
    snap_dt, series_dt = cadence(model.scene, model.t_end)
    steps = math.ceil(model.t_end / model.dt)
    n = min(math.floor(model.t_end / snap_dt + 1e-9), steps) + 1
    rows = min(model.t_end / series_dt, steps)
    return n, int(n * per_snapshot + rows * ROW_BYTES)
