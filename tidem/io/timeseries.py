"""timeseries.csv: one row per sample, columns fixed by the first row, flushed as written."""

from __future__ import annotations

from pathlib import Path


class TimeSeries:
    """Append-only CSV writer; every row is on disk as soon as `append` returns."""

    def __init__(self, path: Path, keep_rows: int | None = None):
        """A new file, or with `keep_rows` (a resumed run) the existing file cut to its header
        and first `keep_rows` rows, appended to from there."""
        self.path = Path(path)
        self.columns: list[str] | None = None
        self.rows = 0
        if keep_rows is not None and self.path.is_file():
            lines = self.path.read_text().splitlines(keepends=True)[: keep_rows + 1]
            if lines:
                self.columns = lines[0].rstrip("\n").split(",")
                self.rows = len(lines) - 1
            self.path.write_text("".join(lines))
            self._fh = open(self.path, "a", buffering=1)
        else:
            self._fh = open(self.path, "w", buffering=1)

    def append(self, row: dict) -> None:
        if self.columns is None:
            self.columns = list(row)
            self._fh.write(",".join(self.columns) + "\n")
        self._fh.write(",".join(_fmt(row.get(c, "")) for c in self.columns) + "\n")
        self._fh.flush()
        self.rows += 1

    def close(self) -> None:
        self._fh.close()


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.9g}"
    return str(v)
