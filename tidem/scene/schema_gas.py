"""The gas and reaction tables of the scene file (`[gas]`, `[gas.oxygen]`, `[[gas.nozzles]]`,
`[[reactions]]`), as strict pydantic models; the rest of the schema is `tidem.scene.schema`."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, StrictBool, StrictInt, field_validator, model_validator

from tidem.scene.schedule import ScheduledNonNegative, ScheduledPositive
from tidem.scene.types import NonNegative, Number, Positive, Strict, Vec3


class Nozzle(Strict):
    """A part of the distributor with its own superficial gas velocity."""

    x: tuple[Number, Number]
    y: tuple[Number, Number] | None = None
    velocity: ScheduledNonNegative

    @model_validator(mode="after")
    def _ranges(self):
        for key in ("x", "y"):
            r = getattr(self, key)
            if r is not None and r[1] <= r[0]:
                raise ValueError(f"{key}: the upper end must exceed the lower ({list(r)})")
        return self


class Oxygen(Strict):
    """O2 carried by the gas as a transported mass fraction (needed by char combustion)."""

    mole_fraction: Number = Field(ge=0.0, le=1.0)
    initial_mole_fraction: Number | None = Field(default=None, ge=0.0, le=1.0)
    diffusivity: Positive = 2.0e-4
    molar_mass: Positive = 0.02897
    pressure: Positive = 101325.0


class Gas(Strict):
    """The gas phase: locally averaged incompressible flow coupled to the particles."""

    density: Positive = 1.2
    viscosity: Positive = 1.8e-5
    heat_capacity: Positive = 1005.0
    cell_size: Positive | tuple[Positive, Positive, Positive]
    inlet_velocity: ScheduledNonNegative = 0.0
    inlet_ramp: NonNegative = 0.0
    nozzles: list[Nozzle] = []
    inlet_temperature: ScheduledPositive | None = None
    initial_temperature: Positive | None = None
    drag: Literal["gidaspow", "di_felice", "beetstra", "tang"] = "gidaspow"
    voidage: Literal["layered", "cell"] = "layered"
    parcel_voidage: Literal["grain_layers", "parcel_layers"] = "grain_layers"
    averaging_length: Positive | Literal["cells"] | None = None
    drag_averaging: Literal["cells", "length"] = "cells"
    heat_transfer: Literal["ranz_marshall", "gunn"] = "ranz_marshall"
    tube_convection: Literal["martin_nilles", "churchill_bernstein", "none"] = "martin_nilles"
    tube_shape: Literal["cells", "cut"] = "cut"
    conduction: StrictBool = True
    coupling_interval: StrictInt = Field(default=10, ge=1)
    tolerance: Positive = 1e-8
    max_iterations: StrictInt = Field(default=2000, ge=1)
    min_voidage: Number = Field(default=0.3, gt=0, lt=1)
    pressure_probes: list[Number | Vec3] = []
    side_walls: Literal["free_slip", "no_slip"] = "free_slip"
    oxygen: Oxygen | None = None

    @field_validator("averaging_length", mode="before")
    @classmethod
    def _length_or_cells(cls, value):
        """One message for a bad `averaging_length`, in place of one per branch of the union."""
        if isinstance(value, bool) or (isinstance(value, str) and value != "cells"):
            shown = f"the text {value!r}" if isinstance(value, str) else str(value).lower()
            raise ValueError(f"expected a length in m or \"cells\" (the cells' own averaging), got {shown}")
        if isinstance(value, (int, float)) and not value > 0:
            raise ValueError(f"must be > 0 (got {value})")
        return value

    @field_validator("cell_size", mode="before")
    @classmethod
    def _size_or_sizes(cls, value):
        """One message for a size per axis that is not positive, in place of one per branch of the union."""
        if isinstance(value, list) and len(value) == 3 and all(type(v) in (int, float) for v in value) \
                and min(value) <= 0:
            raise ValueError(f"every size must be > 0 (got {value})")
        if type(value) in (int, float) and not value > 0:
            raise ValueError(f"must be > 0 (got {value})")
        return value


class CharCombustion(Strict):
    """C + O2 at the surface of each particle of a group, kinetics in series with the gas film."""

    type: Literal["char_combustion"]
    group: str
    pre_exponential: Positive = 0.8596
    activation_energy: Positive = 1.494e5
    co_fraction: Number = Field(default=0.0, ge=0.0, le=1.0)
    burnout: Literal["shrink", "density"] = "shrink"


class Polymerization(Strict):
    """Heat of polymerization released in each catalyst particle of a group."""

    type: Literal["polymerization"]
    group: str
    rate_constant: Positive
    monomer_pressure: Positive
    activation_energy: NonNegative = 0.0
    reference_temperature: Positive = 353.15
    enthalpy: Positive = 3.34e6
    growth: StrictBool = False
    max_diameter: Positive | None = None

    @model_validator(mode="after")
    def _growth_needs_a_cap(self):
        if self.growth and self.max_diameter is None:
            raise ValueError("growth = true needs 'max_diameter' (m): the neighbour search is sized for it, and "
                             "a particle stops reacting there (its catalyst spent); e.g. 1.2 x the group's diameter")
        return self


class Sublimation(Strict):
    """Particles of a group at their sublimation temperature turn the heat they receive into vapour."""

    type: Literal["sublimation"]
    group: str
    temperature: Positive
    latent_heat: Positive
    exit_height: Number | None = None


Reaction = Annotated[CharCombustion | Polymerization | Sublimation, Field(discriminator="type")]
