"""Constrained value types shared by the scene schema.

Numbers are SI (metres, seconds, kilograms, pascals, kelvin); strings are never accepted
where a number is expected, so `diameter = "1 mm"` is an error that names the SI value.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, StrictFloat, StrictInt, model_validator


class Strict(BaseModel):
    """Base of every scene table: unknown keys are errors, numbers must be numbers."""

    model_config = ConfigDict(extra="forbid", frozen=True)


def _finite(v: float) -> float:
    if not math.isfinite(v):
        raise ValueError(f"must be a finite number (got {v})")
    return float(v)


Number = Annotated[StrictFloat | StrictInt, AfterValidator(_finite)]
Positive = Annotated[Number, Field(gt=0)]
NonNegative = Annotated[Number, Field(ge=0)]
Fraction = Annotated[Number, Field(gt=0, le=1)]
Vec3 = tuple[Number, Number, Number]


class Box(Strict):
    """An axis-aligned box [m]."""

    min: Vec3
    max: Vec3

    @model_validator(mode="after")
    def _ordered(self):
        for a, (lo, hi) in enumerate(zip(self.min, self.max)):
            if hi <= lo:
                raise ValueError(f"max[{a}] must be greater than min[{a}] ({hi} <= {lo})")
        return self

    def contains(self, other: "Box", tol: float = 1e-12) -> bool:
        return all(o >= s - tol for o, s in zip(other.min, self.min)) and all(
            o <= s + tol for o, s in zip(other.max, self.max)
        )
