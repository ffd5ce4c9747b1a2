"""VTK XML PolyData (.vtp) snapshots and the ParaView collection (.pvd) that indexes them.

Written directly with numpy (raw appended binary, little-endian, UInt64 block headers), so a
simulation never imports VTK. Each file is written to a temporary name and renamed, so an
interrupted run never leaves a half-written snapshot or collection.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

_VTK_TYPES = {np.dtype("float32"): "Float32", np.dtype("float64"): "Float64",
              np.dtype("int32"): "Int32", np.dtype("int64"): "Int64", np.dtype("uint8"): "UInt8"}


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as fh:
        fh.write(data)
    os.replace(tmp, path)


def write_vtp(path: Path, points: np.ndarray, point_data: dict[str, np.ndarray], time: float | None = None) -> None:
    """Write points (n, 3) with per-point arrays (n,) or (n, 3) as vertices of a PolyData."""
    n = len(points)
    arrays = [("Points", np.ascontiguousarray(points, dtype=np.float64))]
    arrays += [(k, np.ascontiguousarray(v)) for k, v in point_data.items()]
    conn = np.arange(n, dtype=np.int64)
    offs = np.arange(1, n + 1, dtype=np.int64)
    blobs, header, offset = [], [], 0

    def add(arr: np.ndarray) -> int:
        nonlocal offset
        raw = arr.astype(arr.dtype.newbyteorder("<"), copy=False).tobytes()
        blobs.append(np.uint64(len(raw)).tobytes() + raw)
        start = offset
        offset += 8 + len(raw)
        return start

    def tag(name: str, arr: np.ndarray) -> str:
        comps = 1 if arr.ndim == 1 else arr.shape[1]
        return (f'<DataArray type="{_VTK_TYPES[arr.dtype]}" Name="{name}" NumberOfComponents="{comps}" '
                f'format="appended" offset="{add(arr)}"/>')

    pts_tag = tag("Points", arrays[0][1])
    pd_tags = "".join(tag(k, v) for k, v in arrays[1:])
    conn_tag = tag("connectivity", conn)
    offs_tag = tag("offsets", offs)
    field = ""
    if time is not None:
        tarr = np.array([time], dtype=np.float64)
        field = f'<FieldData><DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="appended" offset="{add(tarr)}"/></FieldData>'
    header.append('<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">')
    header.append(f"<PolyData>{field}<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" "
                  'NumberOfStrips="0" NumberOfPolys="0">')
    header.append(f"<PointData>{pd_tags}</PointData><Points>{pts_tag}</Points>")
    header.append(f"<Verts>{conn_tag}{offs_tag}</Verts></Piece></PolyData>")
    header.append('<AppendedData encoding="raw">\n_')
    body = "\n".join(header).encode() + b"".join(blobs) + b"\n</AppendedData>\n</VTKFile>\n"
    _atomic_write(Path(path), body)


def read_vtp(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Read a file written by `write_vtp` back into (points, point_data)."""
    import re

    data = Path(path).read_bytes()
    head, _, tail = data.partition(b'<AppendedData encoding="raw">\n_')
    text = head.decode()
    out: dict[str, np.ndarray] = {}
    points = None
    for m in re.finditer(r'<DataArray type="(\w+)" Name="(\w+)" NumberOfComponents="(\d+)" format="appended" offset="(\d+)"/>', text):
        vtype, name, comps, off = m.group(1), m.group(2), int(m.group(3)), int(m.group(4))
        size = int(np.frombuffer(tail[off:off + 8], "<u8")[0])
        dtype = {v: k for k, v in _VTK_TYPES.items()}[vtype].newbyteorder("<")
        arr = np.frombuffer(tail[off + 8: off + 8 + size], dtype)
        if comps > 1:
            arr = arr.reshape(-1, comps)
        if name == "Points":
            points = arr
        elif name not in ("connectivity", "offsets"):
            out[name] = arr
    return points, out


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """The collection file: one DataSet per (time, relative file name)."""
    rows = "\n".join(f'    <DataSet timestep="{t:.9g}" group="" part="0" file="{f}"/>' for t, f in entries)
    text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")
    _atomic_write(Path(path), text.encode())


