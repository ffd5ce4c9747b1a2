"""timeseries.csv: one row per sample, columns fixed by the first row, flushed as written."""

from __future__ import annotations

from pathlib import Path


class TimeSeries:
    """Append-only CSV writer; every row is on disk as soon as `append` returns."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self._fh = open(self.path, "w", buffering=1)
        self.columns: list[str] | None = None

    def append(self, row: dict) -> None:
        if self.columns is None:
            self.columns = list(row)
            self._fh.write(",".join(self.columns) + "\n")
        self._fh.write(",".join(_fmt(row.get(c, "")) for c in self.columns) + "\n")
        self._fh.flush()

    def close(self) -> None:
        self._fh.close()


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.9g}"
    return str(v)
