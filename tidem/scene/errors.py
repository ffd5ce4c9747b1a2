"""Turn pydantic's validation errors into one line per problem: key path, what is wrong, the fix."""

from __future__ import annotations

import difflib
import re
import typing
from typing import Any

from pydantic import BaseModel, ValidationError

_DISTRIBUTIONS = {"mono", "uniform", "normal", "lognormal"}

# SI factors for the units people write by habit; used only to suggest the number to write.
_UNITS = {
    "mm": 1e-3, "cm": 1e-2, "m": 1.0, "um": 1e-6, "µm": 1e-6, "micron": 1e-6,
    "mm/s": 1e-3, "cm/s": 1e-2, "m/s": 1.0,
    "s": 1.0, "ms": 1e-3, "us": 1e-6,
    "kg/m3": 1.0, "g/cm3": 1e3, "pa": 1.0, "kpa": 1e3, "mpa": 1e6, "gpa": 1e9,
    "kg": 1.0, "g": 1e-3,
}


_TUPLE_FIX = "write 3 numbers [x, y, z] for a point or vector, 2 [low, high] for a range"


class SceneError(Exception):
    """A scene file that cannot be run; `messages` holds one line per problem. `unread`: the file itself could
    not be found or read (one line, "SOURCE: problem", rather than a count of errors in a scene never read)."""

    def __init__(self, source: str, messages: list[str], unread: bool = False):
        self.source = source
        self.messages = messages
        self.unread = unread
        super().__init__(self.render())

    def render(self) -> str:
        if self.unread:
            return "\n".join(f"{self.source}: {m}" for m in self.messages)
        n = len(self.messages)
        head = f"{self.source}: {n} error{'s' if n != 1 else ''} in the scene"
        return "\n".join([head] + [f"  {m}" for m in self.messages])


def key_path(loc: tuple) -> str:
    """('tubes', 1, 'diameter') -> 'tubes[1].diameter'; drops pydantic's union tags."""
    out = ""
    prev = None
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif prev == "diameter" and part in _DISTRIBUTIONS:
            pass
        elif "[" in part or "(" in part or part in ("float", "int", "str", "bool"):
            pass
        else:
            out += ("." if out else "") + part
        prev = part
    return out


def _unit_hint(value: str) -> str:
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([a-zA-Zµ/0-9]+)\s*", value)
    if not m:
        return "write a plain number in SI units"
    try:
        number = float(m.group(1))
    except ValueError:
        return "write a plain number in SI units"
    unit = m.group(2).lower()
    if unit == "c" or unit == "degc":
        return f"temperatures are in kelvin: write {number + 273.15:g}"
    if unit in _UNITS:
        return f"units are SI: write {number * _UNITS[unit]:g}"
    return "write a plain number in SI units"


def _described(value: Any) -> str:
    """'the list [1, 2]', 'the table {...}', 'true', '1e+30' for an error message."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, list):
        return f"the list {value!r}"
    if isinstance(value, dict):
        return f"the table {{{', '.join(map(str, value))}}}"
    return f"{value!r}"


def _model_at(root: type[BaseModel], loc: tuple) -> type[BaseModel] | None:
    """The pydantic model class that owns the last key of `loc`, if one can be found."""
    cls: Any = root
    for part in loc[:-1]:
        cls = _unwrap(cls)
        if isinstance(part, int) or cls is None or part.startswith("["):  # an index, or a union's tag
            continue
        if isinstance(cls, type) and issubclass(cls, BaseModel):
            field = cls.model_fields.get(part)
            if field is None:
                if part in _DISTRIBUTIONS:
                    continue
                return None
            cls = field.annotation
        elif typing.get_origin(cls) is dict:
            cls = typing.get_args(cls)[1]
    cls = _unwrap(cls)
    return cls if isinstance(cls, type) and issubclass(cls, BaseModel) else None


def _unwrap(cls: Any) -> Any:
    """Strip Optional/list/union/Annotated wrappers down to a single model class where there is one."""
    for _ in range(6):
        origin = typing.get_origin(cls)
        if origin is typing.Annotated:
            cls = typing.get_args(cls)[0]
        elif origin in (list, tuple):
            cls = typing.get_args(cls)[0]
        elif origin in (typing.Union, getattr(__import__("types"), "UnionType")):
            args = [typing.get_args(a)[0] if typing.get_origin(a) is typing.Annotated else a for a in typing.get_args(cls)]
            models = [a for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
            if len(models) == 1:
                cls = models[0]
            else:
                return models[0] if models else None
        else:
            break
    return cls


def _tag_message(path: str, ctx: dict, value: Any) -> str:
    """A table of a tagged union (a diameter's `distribution`, a reaction's `type`) with a missing or
    unknown tag: the key, what it may be and what it was."""
    key = str(ctx.get("discriminator", "'type'")).strip("'")
    options = {"distribution": "mono, uniform, normal, lognormal",
               "type": "char_combustion, polymerization, sublimation"}.get(key)
    if ctx.get("expected_tags"):
        options = ", ".join(t.strip().strip("'") for t in str(ctx["expected_tags"]).split(","))
    got = value.get(key) if isinstance(value, dict) else value
    return f"{path}: {key} must be one of {options} (got {'nothing' if got is None else repr(got)})"


def format_validation_error(err: ValidationError, root: type[BaseModel]) -> list[str]:
    """One message per pydantic error, each naming the key path and the fix."""
    lines: list[str] = []
    seen: set[str] = set()
    for e in err.errors(include_url=False):
        loc = tuple(e["loc"])
        path = key_path(loc)
        kind = e["type"]
        value = e.get("input")
        if kind == "extra_forbidden":
            owner = _model_at(root, loc)
            name = str(loc[-1])
            hint = ""
            if owner is not None:
                close = difflib.get_close_matches(name, list(owner.model_fields), n=1, cutoff=0.6)
                hint = f"; did you mean '{close[0]}'?" if close else f"; valid keys: {', '.join(owner.model_fields)}"
            where = key_path(loc[:-1]) or "top level"
            msg = f"{where}: unknown key '{name}'{hint}"
        elif kind == "missing" and isinstance(loc[-1], int):
            msg = f"{key_path(loc[:-1])}: too few numbers (got {value!r}); {_TUPLE_FIX}"
        elif kind == "missing":
            msg = f"{path}: required key is missing; add it (docs/scenes.md lists every key)"
        elif kind in ("too_long", "too_short") and e["msg"].startswith("Tuple"):
            msg = f"{path}: {'too many' if kind == 'too_long' else 'too few'} numbers (got {value!r}); {_TUPLE_FIX}"
        elif kind == "too_short":
            least = e.get("ctx", {}).get("min_length", 1)
            msg = f"{path}: needs at least {least} item{'s' if least != 1 else ''} (got {_described(value)})"
        elif kind == "tuple_type":
            msg = f"{path}: expected a list of numbers, got {_described(value)}; {_TUPLE_FIX}" + (
                ", and a list of points as [[x, y, z], [x, y, z]]" if isinstance(loc[-1], int) else "")
        elif kind in ("bool_type", "bool_parsing"):
            msg = f"{path}: expected true or false, got {_described(value)}; write true or false (no quotes)"
        elif kind == "list_type":
            msg = f"{path}: expected a list, got {_described(value)}; write [a, b, ...], or each item as a [[{path}]] table"
        elif kind in ("dict_type", "model_type"):
            example = "one table per material, e.g. [materials.sand]" if path == "materials" else f"[{path}] with key = value lines"
            msg = f"{path}: expected a table, got {_described(value)}; write {example}"
        elif kind in ("float_type", "int_type", "finite_number") and isinstance(value, str):
            msg = f"{path}: expected a number, got the text {value!r}; {_unit_hint(value)}"
        elif kind in ("float_type", "int_type", "float_parsing", "int_parsing", "int_from_float", "finite_number"):
            whole = kind.startswith("int") and "int" not in loc  # not the int half of a number
            msg = (f"{path}: expected {'a whole number' if whole else 'a number'}, got {_described(value)}; "
                   f"write {'an integer, e.g. 1000 (not 1e3 or 1000.5)' if whole else 'one number in SI units'}")
        elif kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
            op = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}[kind]
            bound = next(iter(e.get("ctx", {}).values()), "?")
            msg = f"{path}: must be {op} {bound} (got {value})"
            if path.endswith("temperature") and isinstance(value, (int, float)) and value < 200:
                msg += f"; temperatures are in K ({value} °C is {value + 273.15:g} K)"
        elif kind == "literal_error":
            msg = f"{path}: {e['msg'].lower()} (got {value!r})"
        elif kind in ("union_tag_invalid", "union_tag_not_found"):
            msg = _tag_message(path, e.get("ctx", {}), value)
        elif kind == "value_error":
            msg = f"{path}: {str(e.get('ctx', {}).get('error', e['msg']))}"
        else:
            shown = "" if isinstance(value, dict) else f" (got {value!r})"
            msg = f"{path}: {e['msg'][0].lower() + e['msg'][1:]}{shown}"
        if msg not in seen:
            seen.add(msg)
            lines.append(msg)
    return lines
