"""Local averaging of the bed (source 3, Bartsch 2020, eq. 34-36): when to sample the control
volumes of a scene's [averaging] table (`tidem.scene.averaging_layout`), and the
time-averaged fields written at the end.

Control volumes: rectangular cells in the x-z plane spanning the domain's depth (y), and
around every tube `rings` layers of `ring_width` from its surface, each cut into
`ring_sectors` angle bins (omega from the top of the tube, 0 = top, 90 deg = the +side,
180 deg = below). From `start` on, every `interval`, `kernels/averaging.py` adds each active
particle to the volumes its centre lies in (eq. 36). With V the control volume, S the number
of samples and the sums over all samples of the particles inside:
  packing_fraction = sum V_i / (V S)             eq. 34 with Q_i = 1
  flux             = sum V_i v_i / (V S)         eq. 34 with Q_i = v_i: solid volume flux [m/s]
  u                = sum v_i / sum 1             eq. 35: number mean velocity [m/s]
  temperature      = sum V_i T_i / sum V_i       volume-weighted mean temperature [K]
A volume no particle entered has packing fraction 0 and NaN velocity and temperature.
Eq. 36 holds for volumes larger than a particle: cells and rings narrower than the largest
particle diameter are refused (`tidem.scene.checks.averaging_checks`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from tidem.kernels.averaging import COUNT, NUM_V, VOL_T, VOL_V, VOLUME

CELLS_CSV = "averages_cells.csv"
RINGS_CSV = "averages_rings.csv"
VTI = "averages.vti"


class AverageRecorder:
    """Samples the averages from `start` every `interval` (default `default_interval`);
    `state()` gives the next sample time for a checkpoint and `saved` puts it back on resume."""

    def __init__(self, model, default_interval: float, saved: float | None = None):
        layout = model.averaging
        self.every = layout.interval or default_interval
        self.next = layout.start if saved is None else saved
        self.tol = 1e-12 * model.t_end

    def state(self) -> float:
        return self.next

    def due(self, t: float) -> bool:
        return t >= self.next - self.tol

    def record(self, solver) -> None:
        solver.sample_averages()
        while self.next <= solver.t + self.tol:
            self.next += self.every


def _fields(sums: np.ndarray, volume, samples: int) -> dict[str, np.ndarray]:
    """Packing fraction, flux (3), number-mean velocity u (3) and, with heat, temperature of
    accumulated sums (last axis: channels of `kernels/averaging.py`) in volumes `volume` [m^3]."""
    count, solid = sums[..., COUNT], sums[..., VOLUME]
    with np.errstate(divide="ignore", invalid="ignore"):
        per = np.asarray(1.0 / (np.asarray(volume, float) * samples) if samples else np.nan)
        out = {"packing_fraction": solid * per, "flux": sums[..., VOL_V:VOL_V + 3] * per[..., None],
               "u": np.where(count[..., None] > 0, sums[..., NUM_V:NUM_V + 3] / count[..., None], np.nan)}
        if sums.shape[-1] > VOL_T:
            out["temperature"] = np.where(solid > 0, sums[..., VOL_T] / solid, np.nan)
    return out


def cell_fields(model, solver) -> tuple[dict[str, np.ndarray], int]:
    """The cells' fields (`_fields`, shape [cells x, cells z, ...]) and the number of samples."""
    samples = int(solver.state.avg_samples[None])
    return _fields(solver.state.avg_cells.to_numpy(), model.averaging.cell_volume, samples), samples


def cell_rows(model, solver) -> list[dict]:
    """One row per cell: i, k, centre x_m and z_m, the fields (module docstring), samples."""
    a = model.averaging
    f, samples = cell_fields(model, solver)
    rows = []
    for i in range(a.cells[0]):
        for k in range(a.cells[1]):
            row = {"i": i, "k": k, "x_m": a.lo[0] + (i + 0.5) * a.size[0], "z_m": a.lo[1] + (k + 0.5) * a.size[1],
                   "packing_fraction": f["packing_fraction"][i, k]}
            row.update({f"u_{c}": f["u"][i, k, n] for n, c in enumerate("xyz")})
            row.update({f"flux_{c}": f["flux"][i, k, n] for n, c in enumerate("xyz")})
            if "temperature" in f:
                row["temperature_K"] = f["temperature"][i, k]
            row["samples"] = samples
            rows.append(row)
    return rows


def ring_rows(model, solver) -> list[dict]:
    """One row per tube, ring and sector: radii, sector-centre angle, the fields with velocity
    and flux as (r radial outwards, t towards increasing angle, axis along the tube), samples."""
    a = model.averaging
    if not model.tubes:
        return []
    samples = int(solver.state.avg_samples[None])
    sums = solver.state.avg_rings.to_numpy().reshape(len(model.tubes), a.rings, a.sectors, -1)
    d_omega = 2.0 * math.pi / a.sectors
    rows = []
    for t, tube in enumerate(model.tubes):
        length = model.grid.length[tube["mask"].index(0.0)]
        inner = tube["r"] + a.ring_width * np.arange(a.rings)
        outer = inner + a.ring_width
        volume = 0.5 * d_omega * (outer**2 - inner**2) * length
        f = _fields(sums[t], volume[:, None], samples)
        for j in range(a.rings):
            for b in range(a.sectors):
                row = {"tube": t, "ring": j, "r_inner_m": inner[j], "r_outer_m": outer[j],
                       "angle_deg": (b + 0.5) * 360.0 / a.sectors, "packing_fraction": f["packing_fraction"][j, b]}
                row.update({f"u_{c}": f["u"][j, b, n] for n, c in enumerate(("r", "t", "axis"))})
                row.update({f"flux_{c}": f["flux"][j, b, n] for n, c in enumerate(("r", "t", "axis"))})
                if "temperature" in f:
                    row["temperature_K"] = f["temperature"][j, b]
                row["samples"] = samples
                rows.append(row)
    return rows


def write_csv(path: Path, rows: list[dict]) -> None:
    keys = list(rows[0])
    lines = [",".join(keys)] + [",".join(f"{r[k]:.9g}" if isinstance(r[k], float) else str(r[k]) for k in keys)
                                for r in rows]
    Path(path).write_text("\n".join(lines) + "\n")


def write_averages(run_dir: Path, model, solver) -> None:
    """averages_cells.csv, averages.vti (the cells as VTK ImageData, one cell deep in y) and,
    with tubes, averages_rings.csv."""
    from tidem.io.vtp import write_vti

    run_dir = Path(run_dir)
    a = model.averaging
    write_csv(run_dir / CELLS_CSV, cell_rows(model, solver))
    f, _ = cell_fields(model, solver)
    shape = (a.cells[0], 1, a.cells[1])
    data = {"packing_fraction": f["packing_fraction"].reshape(shape), "velocity": f["u"].reshape(shape + (3,)),
            "flux": f["flux"].reshape(shape + (3,))}
    if "temperature" in f:
        data["temperature"] = f["temperature"].reshape(shape)
    dom = model.scene.domain
    write_vti(run_dir / VTI, (a.lo[0], dom.min[1], a.lo[1]), (a.size[0], a.depth, a.size[1]), shape, data,
              time=solver.t)
    rings = ring_rows(model, solver)
    if rings:
        write_csv(run_dir / RINGS_CSV, rings)
