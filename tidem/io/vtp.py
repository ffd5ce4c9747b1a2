"""VTK XML PolyData (.vtp) snapshots and triangle meshes, ImageData (.vti) gas fields, and the
ParaView collection (.pvd) that indexes them.

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


class _Appended:
    """The raw appended-data block of a VTK XML file: each array as a UInt64 byte count and
    its little-endian bytes; `tag` returns the DataArray element that points into it."""

    def __init__(self):
        self.blobs: list[bytes] = []
        self.offset = 0

    def add(self, arr: np.ndarray) -> int:
        raw = arr.astype(arr.dtype.newbyteorder("<"), copy=False).tobytes()
        self.blobs.append(np.uint64(len(raw)).tobytes() + raw)
        start = self.offset
        self.offset += 8 + len(raw)
        return start

    def tag(self, name: str, arr: np.ndarray) -> str:
        comps = 1 if arr.ndim == 1 else arr.shape[1]
        return (f'<DataArray type="{_VTK_TYPES[arr.dtype]}" Name="{name}" NumberOfComponents="{comps}" '
                f'format="appended" offset="{self.add(arr)}"/>')

    def time_field(self, time: float | None) -> str:
        if time is None:
            return ""
        offset = self.add(np.array([time], dtype=np.float64))
        return f'<FieldData><DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="appended" offset="{offset}"/></FieldData>'

    def write(self, path: Path, kind: str, body: str) -> None:
        head = (f'<?xml version="1.0"?>\n<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" '
                f'header_type="UInt64">\n{body}\n<AppendedData encoding="raw">\n_')
        _atomic_write(Path(path), head.encode() + b"".join(self.blobs) + b"\n</AppendedData>\n</VTKFile>\n")


def write_vtp(path: Path, points: np.ndarray, point_data: dict[str, np.ndarray], time: float | None = None) -> None:
    """Write points (n, 3) with per-point arrays (n,) or (n, 3) as vertices of a PolyData."""
    n = len(points)
    block = _Appended()
    pts_tag = block.tag("Points", np.ascontiguousarray(points, dtype=np.float64))
    pd_tags = "".join(block.tag(k, np.ascontiguousarray(v)) for k, v in point_data.items())
    conn_tag = block.tag("connectivity", np.arange(n, dtype=np.int64))
    offs_tag = block.tag("offsets", np.arange(1, n + 1, dtype=np.int64))
    field = block.time_field(time)
    block.write(path, "PolyData",
                f"<PolyData>{field}<Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" "
                f'NumberOfStrips="0" NumberOfPolys="0">\n<PointData>{pd_tags}</PointData><Points>{pts_tag}</Points>\n'
                f"<Verts>{conn_tag}{offs_tag}</Verts></Piece></PolyData>")


def write_vtp_triangles(path: Path, points: np.ndarray, triangles: np.ndarray,
                        point_data: dict[str, np.ndarray] | None = None, time: float | None = None) -> None:
    """Write a triangle surface: points (V, 3), triangles (T, 3) indices into them, per-point
    arrays (V,) or (V, 3), as the polygons of a PolyData."""
    tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    block = _Appended()
    pts_tag = block.tag("Points", np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3))
    pd_tags = "".join(block.tag(k, np.ascontiguousarray(v)) for k, v in (point_data or {}).items())
    conn_tag = block.tag("connectivity", tri.ravel())
    offs_tag = block.tag("offsets", np.arange(3, 3 * len(tri) + 1, 3, dtype=np.int64))
    field = block.time_field(time)
    block.write(path, "PolyData",
                f'<PolyData>{field}<Piece NumberOfPoints="{len(points)}" NumberOfVerts="0" NumberOfLines="0" '
                f'NumberOfStrips="0" NumberOfPolys="{len(tri)}">\n<PointData>{pd_tags}</PointData><Points>{pts_tag}</Points>\n'
                f"<Polys>{conn_tag}{offs_tag}</Polys></Piece></PolyData>")


def _cells_x_fastest(v: np.ndarray) -> np.ndarray:
    """VTK's cell order (x fastest) of an (nx, ny, nz) or (nx, ny, nz, 3) array."""
    if v.ndim == 3:
        return np.ascontiguousarray(v.ravel(order="F"))
    return np.ascontiguousarray(np.stack([v[..., c].ravel(order="F") for c in range(v.shape[3])], axis=1))


def write_vti(path: Path, origin, spacing, cells, cell_data: dict[str, np.ndarray], time: float | None = None) -> None:
    """Write a box of cells (`cells` per axis, `spacing` [m], lower corner `origin`) with
    per-cell arrays of shape cells (scalars) or cells + (3,) (vectors) as an ImageData."""
    block = _Appended()
    tags = "".join(block.tag(k, _cells_x_fastest(v)) for k, v in cell_data.items())
    field = block.time_field(time)
    extent = " ".join(f"0 {c}" for c in cells)
    block.write(path, "ImageData",
                f'<ImageData WholeExtent="{extent}" Origin="{" ".join(map(repr, map(float, origin)))}" '
                f'Spacing="{" ".join(map(repr, map(float, spacing)))}">{field}\n<Piece Extent="{extent}">'
                f"<CellData>{tags}</CellData></Piece></ImageData>")


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


def read_vtp_triangles(path: Path) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Read a file written by `write_vtp_triangles` back into (points, triangles, point_data)."""
    import re

    data = Path(path).read_bytes()
    head, _, tail = data.partition(b'<AppendedData encoding="raw">\n_')
    polys = re.search(r"<Polys>(.*?)</Polys>", head.decode(), re.S)
    if polys is None:
        raise ValueError(f"{path} holds no triangles")
    m = re.search(r'Name="connectivity" NumberOfComponents="1" format="appended" offset="(\d+)"', polys.group(1))
    off = int(m.group(1))
    size = int(np.frombuffer(tail[off:off + 8], "<u8")[0])
    triangles = np.frombuffer(tail[off + 8: off + 8 + size], "<i8").reshape(-1, 3)
    points, point_data = read_vtp(path)
    return points.reshape(-1, 3), triangles, point_data


def read_vti(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    """Read a file written by `write_vti` back into ({cells, origin, spacing, time},
    {name: array of shape cells or cells + (3,)})."""
    import re

    data = Path(path).read_bytes()
    head, _, tail = data.partition(b'<AppendedData encoding="raw">\n_')
    text = head.decode()
    ext = [int(v) for v in re.search(r'WholeExtent="([\d ]+)"', text).group(1).split()]
    cells = (ext[1], ext[3], ext[5])
    grid = {"cells": cells, "time": None,
            "origin": [float(v) for v in re.search(r'Origin="([^"]+)"', text).group(1).split()],
            "spacing": [float(v) for v in re.search(r'Spacing="([^"]+)"', text).group(1).split()]}
    stamp = re.search(r'Name="TimeValue" NumberOfTuples="1" format="appended" offset="(\d+)"', text)
    if stamp:
        off = int(stamp.group(1))
        grid["time"] = float(np.frombuffer(tail[off + 8: off + 16], "<f8")[0])
    out: dict[str, np.ndarray] = {}
    for m in re.finditer(r'<DataArray type="(\w+)" Name="(\w+)" NumberOfComponents="(\d+)" format="appended" offset="(\d+)"/>', text):
        vtype, name, comps, off = m.group(1), m.group(2), int(m.group(3)), int(m.group(4))
        size = int(np.frombuffer(tail[off:off + 8], "<u8")[0])
        dtype = {v: k for k, v in _VTK_TYPES.items()}[vtype].newbyteorder("<")
        arr = np.frombuffer(tail[off + 8: off + 8 + size], dtype)
        if comps == 1:
            out[name] = arr.reshape(cells, order="F")
        else:
            out[name] = np.stack([arr[c::comps].reshape(cells, order="F") for c in range(comps)], axis=-1)
    return grid, out


def write_pvd(path: Path, entries: list[tuple[float, str]], parts: list[int] | None = None) -> None:
    """The collection file: one DataSet per (time, relative file name); `parts` numbers the
    datasets shown together at one time (ParaView reads them as the blocks of a multiblock)."""
    parts = parts or [0] * len(entries)
    rows = "\n".join(f'    <DataSet timestep="{t:.9g}" group="" part="{k}" file="{f}"/>'
                     for (t, f), k in zip(entries, parts))
    text = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")
    _atomic_write(Path(path), text.encode())


