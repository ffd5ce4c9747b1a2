"""The particles' part of a time-series sample: the bed top (`hydrodynamics.bed_top`) and the
temperature range of the active particles.

On the CPU they are taken from the particle arrays, copied to the host in one launch per element
type (`kernels/field_copy.py`), so float64 runs keep their time series to the last bit. On a GPU copying every position, temperature and
active flag to the host at each sample held the 700 000-grain bed's run loop (output 0.6 ms a
step, `benchmarks/README.md`); there a kernel (`kernels/diagnostics.make_sample_kernel`) bins
the centres' heights into HEIGHT_BINS bins over the domain and reduces the temperatures, and
only the histogram (64 kB) and three numbers come back. The bed top is then the percentile of
the binned heights (`histogram_percentile`), within one bin (the domain height / 16 384) of
the exact one.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import taichi as ti

from tidem.kernels.diagnostics import make_sample_kernel
from tidem.kernels.field_copy import FieldCopier
from tidem.kernels.ordered import in_order
from tidem.results.hydrodynamics import BED_TOP_PERCENTILE, bed_top

HEIGHT_BINS = 1 << 14


def histogram_percentile(counts: np.ndarray, lo: float, width: float, q: float) -> float:
    """The q-th percentile (numpy's linear rule between order statistics) of values given as counts
    in bins of `width` from `lo`, each bin's values spread evenly across it (NaN without values):
    within one bin width of the percentile of the values themselves."""
    n = int(counts.sum())
    if n == 0:
        return float("nan")
    cum = np.cumsum(counts)

    def order_statistic(j: int) -> float:  # the j-th smallest value (0-based), spread within its bin
        b = int(np.searchsorted(cum, j, side="right"))
        before = cum[b] - counts[b]
        return lo + (b + (j - before + 0.5) / counts[b]) * width

    k = (n - 1) * q / 100.0
    j = int(math.floor(k))
    low = order_statistic(j)
    return low if j + 1 >= n else low + (k - j) * (order_statistic(j + 1) - low)


class ParticleStats:
    """`sample(n, bed)` -> {"bed_top": m (with `bed`), and with heat "T_mean_K", "T_min_K",
    "T_max_K" (with active particles)} over the active particles of state S (module docstring)."""

    def __init__(self, S, z_range: tuple[float, float], heat: bool):
        self.heat = heat
        self.lo = z_range[0]
        self.width = (z_range[1] - z_range[0]) / HEIGHT_BINS
        self._tree = None
        self._kernel = None
        if in_order():  # the arrays in one launch per element type (`kernels/field_copy.py`)
            self._host = FieldCopier({"active": S.active, "x": S.x, **({"T": S.T} if heat else {})})
        else:
            P = self.P = SimpleNamespace(z_hist=ti.field(ti.i32))
            fb = ti.FieldsBuilder()
            fb.dense(ti.i, HEIGHT_BINS).place(P.z_hist)
            if heat:
                P.T_sum, P.T_top, P.T_low = ti.field(ti.f64), ti.field(ti.f64), ti.field(ti.f64)
                fb.place(P.T_sum, P.T_top, P.T_low)
            self._tree = fb.finalize()
            self._kernel = make_sample_kernel(S, P, self.lo, self.width, HEIGHT_BINS, heat)

    def sample(self, n: int, bed: bool) -> dict[str, float]:
        if self._kernel is None:
            return self._from_host(bed)
        self._kernel(n)
        P = self.P
        counts = P.z_hist.to_numpy()
        out = {"bed_top": histogram_percentile(counts, self.lo, self.width, BED_TOP_PERCENTILE)} if bed else {}
        active = int(counts.sum())
        if self.heat and active:
            out.update(T_mean_K=float(P.T_sum[None]) / active, T_min_K=-float(P.T_low[None]),
                       T_max_K=float(P.T_top[None]))
        return out

    def _from_host(self, bed: bool) -> dict[str, float]:
        host = self._host.read()
        active = host["active"].astype(bool)
        out = {"bed_top": bed_top(host["x"][active, 2])} if bed else {}
        if self.heat:
            T = host["T"][active]
            if len(T):
                out.update(T_mean_K=float(T.mean()), T_min_K=float(T.min()), T_max_K=float(T.max()))
        return out

    def release(self) -> None:
        if self._tree is not None:
            self._tree.destroy()
            self._tree = None
