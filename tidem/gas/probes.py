"""Gas pressure probes (`gas.pressure_probes`): a height reads the mean over a horizontal layer's
fluid cells, a point [x, y, z] the pressure there, as a pressure tap or a probe tip reads it."""

from __future__ import annotations

import numpy as np


def probe_column(probe) -> str:
    """The time-series column of a probe: a height z [m] gives e.g. gas_pressure_z45mm_Pa, a point
    (x, y, z) [m] e.g. gas_pressure_x45_y4_z45mm_Pa."""
    if isinstance(probe, (tuple, list)):
        x, y, z = (1000 * v for v in probe)
        return f"gas_pressure_x{x:g}_y{y:g}_z{z:g}mm_Pa"
    return f"gas_pressure_z{1000 * probe:g}mm_Pa"


def probe_pressures(probes, p: np.ndarray, fluid: np.ndarray, lo, h) -> dict[str, float]:
    """{probe_column(probe): pressure [Pa]} of cell-centred pressures `p` on a grid with origin `lo`
    and cell sizes `h` (`fluid`: the cells that hold gas). A height: the mean over the fluid cells of a
    horizontal layer, interpolated linearly between the two layers whose centres bracket it (the lowest
    or highest layer beyond them). A point: trilinear interpolation between the eight cell centres
    around it, over those of them that hold gas (weights renormalised; where none does, the fluid cell
    whose centre lies nearest), each coordinate held at the outermost centres beyond them."""
    out = {}
    centres = [lo[a] + (np.arange(p.shape[a]) + 0.5) * h[a] for a in range(3)]
    count = fluid.sum(axis=(0, 1))
    means = np.divide(np.where(fluid, p, 0.0).sum(axis=(0, 1)), count, out=np.full(len(count), np.nan),
                      where=count > 0)
    for probe in probes:
        if isinstance(probe, (tuple, list)):
            out[probe_column(probe)] = _point_pressure(p, fluid, centres, probe)
        else:
            out[probe_column(probe)] = float(np.interp(probe, centres[2], means))
    return out


def _point_pressure(p: np.ndarray, fluid: np.ndarray, centres, point) -> float:
    """Trilinear interpolation of `p` at `point` over the fluid cells of the eight around it, else the
    nearest fluid cell's value."""
    index, weight = [], []
    for a in range(3):
        c = centres[a]
        s = float(np.clip((point[a] - c[0]) / (c[1] - c[0]) if len(c) > 1 else 0.0, 0.0, len(c) - 1))
        i = min(int(s), max(len(c) - 2, 0))
        f = s - i
        index.append((i, min(i + 1, len(c) - 1)))
        weight.append((1.0 - f, f))
    total = norm = 0.0
    for di in range(2):
        for dj in range(2):
            for dk in range(2):
                cell = index[0][di], index[1][dj], index[2][dk]
                w = weight[0][di] * weight[1][dj] * weight[2][dk]
                if w > 0 and fluid[cell]:
                    total += w * p[cell]
                    norm += w
    if norm > 0:
        return total / norm
    grid = np.meshgrid(*centres, indexing="ij")
    distance = sum((g - x) ** 2 for g, x in zip(grid, point))
    return float(p[np.unravel_index(np.argmin(np.where(fluid, distance, np.inf)), p.shape)])
