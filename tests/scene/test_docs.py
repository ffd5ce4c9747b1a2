"""Every scene key of the schema is documented in docs/scenes.md."""

from pathlib import Path

from pydantic import BaseModel

import tidem.scene.schedule as schedule
import tidem.scene.schema as schema
import tidem.scene.types as types

DOC = Path(__file__).resolve().parents[2] / "docs" / "scenes.md"


def all_models():
    for mod in (schema, types, schedule):
        for obj in vars(mod).values():
            if isinstance(obj, type) and issubclass(obj, BaseModel) and obj.__module__ == mod.__name__:
                yield obj


def test_every_key_is_documented():
    text = DOC.read_text()
    missing = sorted({f"{m.__name__}.{k}" for m in all_models() for k in m.model_fields if f"`{k}`" not in text})
    assert not missing, f"undocumented scene keys: {missing}"


def test_shipped_scenes_validate():
    from tidem.scene.load import load, shipped_scenes

    for name in shipped_scenes():
        assert load(name).scene is not None
