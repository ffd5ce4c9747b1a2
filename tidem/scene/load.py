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
    """A file in the working folder wins; otherwise a shipped scene by name (with or without .toml)."""
    if name_or_path is None:
        name_or_path = DEFAULT_SCENE
    path = Path(name_or_path)
    if path.is_file():
        return path
    shipped = shipped_scenes()
    for candidate in (path.name, path.name + ".toml"):
        if candidate in shipped:
            return shipped[candidate]
    raise SceneError(
        str(name_or_path),
        [f"no such file, and no shipped scene of that name; shipped scenes: {', '.join(shipped)}"],
    )


_INDEX = re.compile(r"^(\w+)\[(\d+)\]$")


def apply_override(raw: dict, assignment: str) -> None:
    """Apply 'a.b[1].c=VALUE' to the raw TOML dict; VALUE is read as a TOML value (text if not)."""
    if "=" not in assignment:
        raise ValueError(f"--set {assignment!r}: expected KEY=VALUE, e.g. outlet.speed=0.003")
    key, text = assignment.split("=", 1)
    try:
        value = tomllib.loads(f"v = {text.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = text.strip()
    parts: list[str | int] = []
    for piece in key.strip().split("."):
        m = _INDEX.match(piece)
        if m:
            parts += [m.group(1), int(m.group(2))]
        elif piece.isdigit():
            parts.append(int(piece))
        else:
            parts.append(piece)
    node: Any = raw
    for here, nxt in zip(parts[:-1], parts[1:]):
        if isinstance(here, int):
            if not isinstance(node, list) or here >= len(node):
                raise ValueError(f"--set {key}: index {here} is out of range")
            node = node[here]
        else:
            if here not in node:
                node[here] = [] if isinstance(nxt, int) else {}
            node = node[here]
    last = parts[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise ValueError(f"--set {key}: index {last} is out of range")
    node[last] = value


def load(name_or_path: str | None, overrides: list[str] = ()) -> LoadedScene:
    """Load and validate a scene; raises `SceneError` listing every problem."""
    path = resolve(name_or_path)
    source = str(path)
    try:
        raw = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(source, [f"not valid TOML: {exc}"]) from None
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
