"""The solids' vertical dispersion coefficient, a mixing rate, from a run's snapshots (the observable
`dispersion`, `tidem.results.observables`).

D_z = (1/2) d<(z(t + tau) - z(t))^2>/d tau [m^2/s]: the least-squares slope of the particles' mean square
vertical displacement against the lag tau over LAGS, halved (Einstein's relation for a random walk; the
axial dispersion coefficient of a fluidized bed's solids, e.g. Kunii & Levenspiel 1991, ch. 9). Particles are
followed by their id from snapshot to snapshot, over the pairs of snapshots in the second half of the run
that lie one lag apart; each lag's mean is over every such pair and every particle present in both. A
parcel's grains move with it, so the coefficient is per grain at any coarse graining (the grains' motion
inside a parcel is not in it). The lags start at 0.02 s, past a bubbling bed's ballistic start, and end at
0.1 s, before the displacements reach the bed's height.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vtp

LAGS = (0.02, 0.04, 0.06, 0.08, 0.1)  # s
MATCH = 0.2 * LAGS[0]  # s: two snapshots lie one lag apart within this, or within half their spacing if less


def indexed_heights(x: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """The heights [m] of particles at `x` [n, 3] indexed by their `ids` (NaN for ids not among them)."""
    ids = ids.astype(np.int64)
    z = np.full(int(ids.max()) + 1 if len(ids) else 0, np.nan)
    z[ids] = x[:, 2]
    return z


def heights_by_id(path: Path) -> np.ndarray:
    """The particles' heights [m] of one snapshot file, indexed by their id (`indexed_heights`)."""
    x, data = read_vtp(path)
    return indexed_heights(x, data["id"])


def mean_square_displacements(snapshots: Iterable[tuple[float, np.ndarray]],
                              match: float = MATCH) -> tuple[list[float], list[float]]:
    """(lags [s], mean square vertical displacements [m^2]) for each of LAGS that some pair of the
    `snapshots` spans within `match` [s], given in time order as (time [s], heights by id (`heights_by_id`)); each
    lag is the mean time between its pairs (snapshots fall on whole steps). Holds only the snapshots of the
    last LAGS[-1] in memory."""
    squares, spans, counts = np.zeros(len(LAGS)), np.zeros(len(LAGS)), np.zeros(len(LAGS), np.int64)
    recent: deque[tuple[float, np.ndarray]] = deque()
    for t, z in snapshots:
        while recent and t - recent[0][0] > LAGS[-1] + match:
            recent.popleft()
        for t0, z0 in recent:
            for j, lag in enumerate(LAGS):
                if abs(t - t0 - lag) <= match:
                    n = min(len(z), len(z0))
                    step = z[:n] - z0[:n]
                    step = step[np.isfinite(step)]
                    squares[j] += float(np.dot(step, step))
                    spans[j] += (t - t0) * len(step)
                    counts[j] += len(step)
        recent.append((t, z))
    spanned = np.flatnonzero(counts)
    return [float(spans[j] / counts[j]) for j in spanned], [float(squares[j] / counts[j]) for j in spanned]


def dispersion_coefficient(snapshots: Iterable[tuple[float, np.ndarray]], match: float = MATCH) -> float | None:
    """D_z [m^2/s] (module docstring) of snapshots as in `mean_square_displacements`; None where fewer than
    two of LAGS are spanned."""
    lags, msd = mean_square_displacements(snapshots, match)
    if len(lags) < 2:
        return None
    return float(np.polyfit(lags, msd, 1)[0] / 2.0)


def run_dispersion(snapshots: list[tuple[float, Path]], t_end: float) -> dict[str, float | str | None]:
    """{"dispersion_m2_s": D_z} over the snapshots [(time, file)] with t >= t_end / 2, or a note saying why
    there is none (too few snapshots one lag apart)."""
    late = sorted((t, path) for t, path in snapshots if t >= 0.5 * t_end - 1e-12)
    spacing = float(np.median(np.diff([t for t, _ in late]))) if len(late) > 1 else MATCH
    value = dispersion_coefficient(((t, heights_by_id(path)) for t, path in late), min(MATCH, 0.5 * spacing))
    if value is not None:
        return {"dispersion_m2_s": value}
    return {"dispersion_m2_s": None,
            "dispersion_note": f"needs snapshots in the second half of the run {LAGS[0]:g} and {LAGS[1]:g} s apart at "
                               f"least: output.interval = {LAGS[0]:g} s or a divisor of it, and t_end of "
                               f"{2 * LAGS[1]:g} s or more"}
