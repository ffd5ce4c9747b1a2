"""Mesh files checked before a reader sees them, so that any malformed, truncated or inconsistent file
is one line naming the file and the problem (`tidem.walls.mesh_load.read_triangles`):

- OBJ and PLY are read here (VTK's readers crash the process on a face that refers to a texture
  or normal an OBJ file does not have and on a truncated binary PLY, and return faces past the
  vertex list). OBJ: `v x y z` lines and `f i j k ...` faces (1-based vertex indices, negative ones
  counted back from the last vertex so far, `i/t/n` forms taking the vertex index); everything else
  (normals, texture coordinates, groups, materials) is not geometry and is skipped. PLY (ASCII,
  binary little- or big-endian): the `vertex` element's x, y, z and the `face` element's index
  list; other properties and elements are skipped by their declared types, and a file shorter or
  longer than its header declares is refused. Polygons are split into triangle fans;
- a binary STL must hold exactly the 50-byte triangles its header counts (84 + 50 n bytes): a
  truncated or padded file is refused instead of read short;
- the native reader (STL) runs with the process's error stream closed (`quiet_native_stderr`),
  so no line of theirs reaches the terminal: the caller reports the problem.
"""

from __future__ import annotations

import contextlib
import os
import struct
from pathlib import Path

import numpy as np


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray] | str:
    """(points [P, 3], triangles [T, 3]) of a Wavefront OBJ file, or what is wrong with it."""
    name = path.name
    data = path.read_bytes()
    if b"\x00" in data[:4096]:
        return f"'{name}' is not a text OBJ file (it holds binary data); export the part's surface as OBJ or STL"
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = data.decode("latin-1")  # comments and names may be in any code page; numbers are ASCII
    points: list[list[float]] = []
    faces: list[tuple[int, list[int]]] = []  # (line, vertex indices, 0-based, checked at the end)
    for n, line in enumerate(text.splitlines(), 1):
        parts = line.split("#", 1)[0].split()
        if not parts:
            continue
        if parts[0] == "v":
            try:
                xyz = [float(p) for p in parts[1:4]]
            except ValueError:
                return f"'{name}' line {n}: a vertex coordinate is not a number ('{line.strip()[:60]}'); {_FIX}"
            if len(xyz) < 3:
                return f"'{name}' line {n}: a vertex needs x, y and z ('{line.strip()[:60]}'); {_FIX}"
            points.append(xyz)
        elif parts[0] == "f":
            if len(parts) < 4:
                return f"'{name}' line {n}: a face needs at least 3 vertices ('{line.strip()[:60]}'); {_FIX}"
            corners = []
            for token in parts[1:]:
                try:
                    k = int(token.split("/")[0])
                except ValueError:
                    return f"'{name}' line {n}: a face's vertex index is not a whole number ('{token}'); {_FIX}"
                if k == 0:
                    return f"'{name}' line {n}: vertex index 0 (OBJ counts from 1); {_FIX}"
                corners.append(k - 1 if k > 0 else len(points) + k)
            faces.append((n, corners))
    if not faces:
        what = f"{len(points)} vertices and no faces" if points else "no vertices and no faces"
        return (f"'{name}' is not a triangle surface mesh ({what}: it is not a valid OBJ file); export the part's "
                "surface as STL (ASCII or binary)")
    for n, corners in faces:
        bad = [k for k in corners if not 0 <= k < len(points)]
        if bad:
            return (f"'{name}' line {n}: a face refers to vertex {bad[0] + 1 if bad[0] >= 0 else bad[0] - len(points)}, "
                    f"but the file has {len(points)} vertices; {_FIX}")
    triangles = [(c[0], c[i], c[i + 1]) for _n, c in faces for i in range(1, len(c) - 1)]
    return np.asarray(points, float), np.asarray(triangles, np.int64)


_FIX = "repair the file or export it again from your CAD tool"


PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}


class PlyError(ValueError):
    """What is wrong with a PLY file (the message's text)."""


def read_ply(path: Path) -> tuple[np.ndarray, np.ndarray] | str:
    """(points [P, 3], triangles [T, 3]) of a PLY file, or what is wrong with it."""
    try:
        return _read_ply(path)
    except PlyError as exc:
        return f"'{path.name}' {exc}; {_FIX}"


def _read_ply(path: Path) -> tuple[np.ndarray, np.ndarray] | str:
    data = path.read_bytes()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise PlyError("is not a PLY file (no 'ply' ... 'end_header' header)")
    body = data[data.index(b"\n", end) + 1:] if b"\n" in data[end:] else b""
    elements, fmt = [], None
    for n, line in enumerate(data[:end].decode("latin-1").splitlines()[1:], 2):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) >= 2:
            fmt = words[1]
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            kinds = words[1:-1]
            if not kinds or any(k not in PLY_TYPES for k in kinds if k != "list") or (kinds[0] == "list" and len(kinds) != 3):
                raise PlyError(f"header line {n}: a property of an unknown type ('{line.strip()}')")
            elements[-1][2].append((words[-1], kinds))
        else:
            raise PlyError(f"header line {n}: not a PLY header line ('{line.strip()[:60]}')")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise PlyError(f"has no known format line (got {fmt!r}; ascii, binary_little_endian or binary_big_endian)")
    order = ">" if fmt == "binary_big_endian" else "<"
    reader = _AsciiPly(body) if fmt == "ascii" else _BinaryPly(body, order)
    points = faces = None
    for name, count, props in elements:
        if name == "vertex":
            columns = reader.table(name, count, props)
            if not all(axis in columns for axis in "xyz"):
                raise PlyError("has a vertex element without x, y and z")
            points = np.stack([columns[a] for a in "xyz"], axis=1).astype(float)
        elif name == "face":
            lists = [p for p in props if p[1][0] == "list" and p[0] in ("vertex_indices", "vertex_index")]
            if not lists:
                raise PlyError("has a face element without a vertex_indices list")
            faces = reader.table(name, count, props)[lists[0][0]]
        else:
            reader.table(name, count, props)
    reader.finish()
    if points is None:
        raise PlyError("has no vertex element")
    if not faces:
        return (f"'{path.name}' is not a triangle surface mesh (it holds a point cloud); export the part's surface "
                "as STL (ASCII or binary)")
    triangles = []
    for row, face in enumerate(faces):
        if len(face) < 3:
            raise PlyError(f"face {row} has {len(face)} vertices (at least 3)")
        triangles += [(face[0], face[i], face[i + 1]) for i in range(1, len(face) - 1)]
    triangles = np.asarray(triangles, np.int64)
    if triangles.min() < 0 or triangles.max() >= len(points):
        bad = int(triangles[(triangles < 0) | (triangles >= len(points))][0])
        raise PlyError(f"has a face that refers to vertex {bad}, but the file has {len(points)} vertices")
    return points, triangles


class _AsciiPly:
    """The body of an ASCII PLY file, element by element."""

    def __init__(self, body: bytes):
        self.words = body.decode("latin-1").split()
        self.at = 0

    def _take(self, what: str) -> str:
        if self.at >= len(self.words):
            raise PlyError(f"ends within its {what} (fewer values than the header declares)")
        self.at += 1
        return self.words[self.at - 1]

    def table(self, element: str, count: int, props) -> dict:
        out = {name: [] for name, _kinds in props}
        try:
            for _ in range(count):
                for name, kinds in props:
                    if kinds[0] == "list":
                        k = int(self._take(element))
                        out[name].append([int(float(self._take(element))) for _ in range(k)])
                    else:
                        out[name].append(float(self._take(element)))
        except PlyError:
            raise
        except ValueError:
            raise PlyError(f"has a value in its {element} element that is not a number") from None
        return {name: (np.asarray(v) if props[i][1][0] != "list" else v) for i, (name, v) in enumerate(out.items())}

    def finish(self) -> None:
        if self.at != len(self.words):
            raise PlyError(f"holds {len(self.words) - self.at} values more than its header declares")


class _BinaryPly:
    """The body of a binary PLY file, element by element."""

    def __init__(self, body: bytes, order: str):
        self.body, self.order, self.at = body, order, 0

    def table(self, element: str, count: int, props) -> dict:
        if all(kinds[0] != "list" for _name, kinds in props):  # fixed rows: one read
            dtype = np.dtype([(name, self.order + PLY_TYPES[kinds[0]]) for name, kinds in props])
            size = dtype.itemsize * count
            if self.at + size > len(self.body):
                raise PlyError(f"ends within its {element} element (truncated: fewer bytes than the header declares)")
            rows = np.frombuffer(self.body, dtype, count, self.at)
            self.at += size
            return {name: rows[name] for name, _kinds in props}
        out = {name: [] for name, _kinds in props}
        for _ in range(count):
            for name, kinds in props:
                if kinds[0] == "list":
                    k = int(self._read(kinds[1], 1, element)[0])
                    out[name].append(self._read(kinds[2], k, element).astype(np.int64).tolist())
                else:
                    out[name].append(float(self._read(kinds[0], 1, element)[0]))
        return out

    def _read(self, kind: str, k: int, element: str) -> np.ndarray:
        dtype = np.dtype(self.order + PLY_TYPES[kind])
        if self.at + dtype.itemsize * k > len(self.body):
            raise PlyError(f"ends within its {element} element (truncated: fewer bytes than the header declares)")
        values = np.frombuffer(self.body, dtype, k, self.at)
        self.at += dtype.itemsize * k
        return values

    def finish(self) -> None:
        if self.at != len(self.body):
            raise PlyError(f"holds {len(self.body) - self.at} bytes more than its header declares")


def stl_problem(path: Path) -> str | None:
    """What is wrong with a binary STL's length (None for a whole binary file, or an ASCII one)."""
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(84)
        start = head + f.read(1024)
    if len(head) < 84:
        return None if _text(start) else (f"'{path.name}' is too short for an STL file ({size} bytes; a binary "
                                          "STL has an 84-byte header); export the part again as STL")
    count = struct.unpack("<I", head[80:84])[0]
    expected = 84 + 50 * count
    if size == expected or _ascii_stl(start) or (_text(start) and not start.startswith(b"solid")):
        return None  # whole, ASCII STL, or text that is no STL at all (the reader says so)
    return (f"'{path.name}' is a binary STL whose header counts {count} triangles ({expected} bytes), but the file "
            f"has {size} bytes ({'truncated' if size < expected else 'data after the last triangle'}); export the "
            "part again as STL")


def _ascii_stl(start: bytes) -> bool:
    """Whether the file's start reads as ASCII STL text ('solid', then text)."""
    return start.lstrip().lower().startswith(b"solid") and _text(start)


def _text(start: bytes) -> bool:
    """Text (names in any code page), not binary data; the STL reader then says what it lacks."""
    return all(b >= 32 and b != 127 or b in b"\t\r\n" for b in start)


@contextlib.contextmanager
def quiet_native_stderr():
    """Close the process's error stream (file descriptor 2) for the duration: a native reader's own
    error lines do not reach the terminal."""
    try:
        saved = os.dup(2)
    except OSError:  # no descriptor 2 to close (a detached process)
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
