"""The solids' granular temperature, a time-series column of scenes that declare the observable
`granular_temperature` (`tidem.results.observables`).

theta = sum_cells n/(n - 1) sum_i m_i |v_i - u_cell|^2 / (3 sum_cells m_cell) [m^2/s^2]: each particle's
velocity about the mass-weighted mean velocity u_cell of its cell, cubes of CELL_DIAMETERS diameters of the
largest grain (the grain's, not a parcel's: every k is measured on the same cells), over the cells that hold
at least two particles; n/(n - 1) makes each cell's sum an unbiased variance (the mean velocity is taken from
the same particles). It is the kinetic theory's theta (Gidaspow 1994: 3/2 theta the fluctuation energy per
mass) of the particles' translation. A parcel's grains move with it, so a parcel's fluctuation is its grains'
and theta is per grain at any k; the grains' own motion inside a parcel is not in it.
The particles' positions, velocities and masses are copied to the host at each sample (one launch per element
type, `kernels/field_copy.py`), so the column costs what a snapshot's copy does, and only where declared.
"""

from __future__ import annotations

import numpy as np

from tidem.kernels.field_copy import FieldCopier

CELL_DIAMETERS = 6.0  # the cell's edge in diameters of the largest grain


def granular_temperature(x: np.ndarray, v: np.ndarray, m: np.ndarray, lo: np.ndarray, cell: float,
                         dims: tuple[int, int, int]) -> float:
    """theta [m^2/s^2] of particles at `x` [n, 3] with velocities `v` [n, 3] and masses `m` [n] in cubes of
    `cell` from `lo`, `dims` cells per axis (particles beyond count in the outermost cells); NaN where no
    cell holds two particles."""
    idx = np.clip(np.floor((x - lo) / cell).astype(np.int64), 0, np.array(dims) - 1)
    key = idx[:, 0] + dims[0] * (idx[:, 1] + dims[1] * idx[:, 2])
    cells = dims[0] * dims[1] * dims[2]
    n = np.bincount(key, minlength=cells)
    mass = np.bincount(key, m, minlength=cells)
    keep = n >= 2
    if not keep.any():
        return float("nan")
    momentum = np.stack([np.bincount(key, m * v[:, c], minlength=cells) for c in range(3)], axis=1)
    energy = np.bincount(key, m * np.einsum("ij,ij->i", v, v), minlength=cells)
    # sum m |v - u|^2 = sum m |v|^2 - |sum m v|^2 / sum m, per cell
    spread = energy[keep] - np.einsum("ij,ij->i", momentum[keep], momentum[keep]) / mass[keep]
    unbiased = np.maximum(spread, 0.0) * n[keep] / (n[keep] - 1)
    return float(unbiased.sum() / (3.0 * mass[keep].sum()))


class GranularSampler:
    """`sample()` -> theta of the active particles of state S now (module docstring)."""

    def __init__(self, S, domain, grain_diameter: float):
        self.lo = np.array(domain.min, float)
        self.cell = CELL_DIAMETERS * grain_diameter
        extent = np.array(domain.max, float) - self.lo
        self.dims = tuple(int(max(1, np.ceil(e / self.cell))) for e in extent)
        self._host = FieldCopier({"active": S.active, "x": S.x, "v": S.v, "mass": S.mass})

    def sample(self) -> float:
        host = self._host.read()
        on = host["active"].astype(bool)
        return granular_temperature(host["x"][on], host["v"][on], host["mass"][on], self.lo, self.cell, self.dims)
