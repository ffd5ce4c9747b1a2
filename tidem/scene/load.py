"""Read a scene: find the file (a path or a shipped scene's name), apply `--set` overrides,
validate, and collect every error of the file in one `SceneError`."""

from __future__ import annotations

import copy
import re
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from tidem.scene.checks import cross_checks
from tidem.scene.errors import SceneError, format_validation_error
from tidem.scene.schema import Scene

DEFAULT_SCENE = "fluidized_tube.toml"


@dataclass(frozen=True)
class LoadedScene:
    """A validated scene with where it came from."""

    scene: Scene
    source: Path
    name: str
    raw: dict


def shipped_scenes() -> dict[str, Path]:
    """Shipped scene files by file name, e.g. {'sphere_impact.toml': Path(...)}."""
    root = resources.files("tidem.scenes")
    return {p.name: Path(str(p)) for p in sorted(root.iterdir(), key=lambda p: p.name) if p.name.endswith(".toml")}


def resolve(name_or_path: str | None) -> Path:
    """A file in the working folder wins; otherwise a shipped scene by name (with or without .toml),
    also where a folder of that name holds no scene (e.g. a run's output folder, --out NAME)."""
    if name_or_path is None:
        name_or_path = DEFAULT_SCENE
    if not str(name_or_path).strip():
        raise SceneError("(empty name)", ["no scene given: name a scene file or a shipped scene "
                                          f"({', '.join(shipped_scenes())})"], unread=True)
    path = Path(name_or_path)
    if path.is_file():
        return path
    shipped = shipped_scenes()
    inside = sorted(p.name for p in path.glob("*.toml") if p.name != "pyproject.toml") if path.is_dir() else []
    bare_shipped = len(path.parts) == 1 and {path.name, path.name + ".toml"} & set(shipped)
    if path.is_dir() and (inside or not bare_shipped):
        raise SceneError(str(name_or_path), [
            "this is a folder, not a scene file; give the .toml file "
            + (f"inside it ({', '.join(inside[:5])}{', ...' if len(inside) > 5 else ''})" if inside
               else "itself (this folder holds none)")], unread=True)
    for candidate in (path.name, path.name + ".toml"):
        if candidate in shipped:
            return shipped[candidate]
    raise SceneError(
        str(name_or_path),
        [f"no such file, and no shipped scene of that name; shipped scenes: {', '.join(shipped)}"],
        unread=True,
    )


def read_toml(path: Path) -> dict:
    """The TOML table of a scene file; SceneError if it is not readable UTF-8 TOML text. The
    first 4 KiB are looked at first, so a large binary file given by mistake is not read whole."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
            if head.startswith((b"\xff\xfe", b"\xfe\xff")):
                raise SceneError(str(path), ["saved as UTF-16; save the file as UTF-8 (e.g. iconv -f utf-16 -t utf-8 "
                                             "OLD.toml > NEW.toml, or 'UTF-8' in the editor's save dialog)"],
                                 unread=True)
            if b"\0" in head:
                raise SceneError(str(path), ["this is a binary file, not a scene (TOML text); give the scene's "
                                             ".toml file"], unread=True)
            text = (head + fh.read()).decode("utf-8-sig")  # a byte-order mark, as some editors write, is dropped
    except OSError as exc:
        raise SceneError(str(path), [f"cannot read the file: {exc.strerror or exc}; check its permissions"],
                         unread=True) from None
    except UnicodeDecodeError as exc:
        line = exc.object[:exc.start].count(b"\n") + 1
        raise SceneError(str(path), [f"not UTF-8 text (byte {exc.object[exc.start]:#04x} on line {line}); save the "
                                     "file as UTF-8, e.g. iconv -f latin1 -t utf-8 OLD.toml > NEW.toml"],
                         unread=True) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(str(path), [f"not valid TOML: {exc}; see docs/scenes.md for the syntax"],
                         unread=True) from None


_INDEX = re.compile(r"^(\w+)\[(\d+)\]$")


def apply_override(raw: dict, assignment: str | tuple[str, Any]) -> None:
    """Apply 'a.b[1].c=VALUE' to the raw TOML dict; VALUE is read as a TOML value (text if not).
    A (key, value) pair (the Python API's overrides) sets the value as it is. A key that cannot
    be followed raises ValueError naming the key and the fix."""
    if isinstance(assignment, tuple):
        key, value = assignment
        value = _plain(value)
        key, text = key.strip(), repr(value)
    elif "=" not in assignment:
        raise ValueError(f"--set {assignment!r}: expected KEY=VALUE, e.g. outlet.speed=0.003")
    else:
        key, text = assignment.split("=", 1)
        key = key.strip()
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
    parts: list[str | int] = []
    for piece in key.split("."):
        m = _INDEX.match(piece)
        if m:
            parts += [m.group(1), int(m.group(2))]
        elif piece.isdigit():
            parts.append(int(piece))
        elif re.fullmatch(r"\w+", piece):
            parts.append(piece)
        else:
            raise ValueError(f"--set {key}={text}: '{piece}' is not a key; write KEY=VALUE with keys joined by dots "
                             "and list items as [i], e.g. particles[0].diameter.value=0.002")
    node: Any = raw
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(part, int):
            if not isinstance(node, list):
                raise ValueError(f"--set {key}: {_key_text(parts[:depth]) or 'the scene'} is not a list; drop [{part}]")
            if part == len(node):  # the next item: a new one, e.g. walls[0].point on a scene without walls
                node.append(value if last else {} if isinstance(parts[depth + 1], str) else [])
            elif part >= len(node):
                have = f"{len(node)} item{'s' if len(node) != 1 else ''}" + (f", [0] to [{len(node) - 1}]" if node else "")
                raise ValueError(f"--set {key}: index {part} is out of range ({_key_text(parts[:depth])} has {have}; "
                                 f"[{len(node)}] adds an item)")
        elif not isinstance(node, dict):
            hint = (f"; write {_key_text(parts[:depth])}[0].{part}" if isinstance(node, list)
                    else f"; set {_key_text(parts[:depth])}=VALUE itself")
            raise ValueError(f"--set {key}: {_key_text(parts[:depth])} is {'a list' if isinstance(node, list) else 'a value'}"
                             f", not a table, so it has no key '{part}'{hint}")
        if last:
            node[part] = value
        elif isinstance(part, str) and part not in node:
            node[part] = [] if isinstance(parts[depth + 1], int) else {}
            node = node[part]
        else:
            node = node[part]


def _plain(value: Any) -> Any:
    """A Python API override as the TOML reader gives it: numpy scalars (np.int64 from np.arange, np.bool_)
    as int, float and bool, numpy arrays and tuples as lists, throughout."""
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):  # numpy scalar or array
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _key_text(parts: list) -> str:
    """['particles', 0, 'diameter'] -> 'particles[0].diameter'."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else ("." if out else "") + p
    return out


def load(name_or_path: str | None, overrides: list[str | tuple[str, Any]] = ()) -> LoadedScene:
    """Load and validate a scene with overrides ('KEY=VALUE' as --set gives them, or (key, value)
    pairs); raises `SceneError` listing every problem."""
    path = resolve(name_or_path)
    source = str(path)
    raw = read_toml(path)
    raw = copy.deepcopy(raw)
    errors: list[str] = []
    for assignment in overrides:
        try:
            apply_override(raw, assignment)
        except (ValueError, TypeError, KeyError) as exc:
            errors.append(str(exc))
    if errors:
        raise SceneError(source, errors)
    return validate(raw, source, default_name=path.stem)


def validate(raw: dict, source: str = "<scene>", default_name: str = "scene") -> LoadedScene:
    """Validate a raw scene dict (as read from TOML)."""
    try:
        scene = Scene.model_validate(raw)
    except ValidationError as exc:
        raise SceneError(source, format_validation_error(exc, Scene)) from None
    errors = cross_checks(scene)
    if errors:
        raise SceneError(source, errors)
    return LoadedScene(scene=scene, source=Path(source), name=scene.name or default_name, raw=raw)
