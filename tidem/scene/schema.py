"""The scene file, as a strict pydantic schema.

Every table forbids unknown keys; every number is SI. `docs/scenes.md` documents each key
with its unit and default, and `tests/scene/test_docs.py` checks that nothing is missing.
The gas and reaction tables are in `tidem.scene.schema_gas`. Checks that span tables (a tube outside the domain, an unknown material name) live in
`tidem.scene.checks`, so that all errors of a file are reported together.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, StrictBool, StrictInt, field_validator, model_validator

from tidem.scene.schedule import NonNegativeSchedule, ScheduledNumber, ScheduledPositive, ScheduledVec3, scheduled
from tidem.scene.schema_gas import Gas, Reaction
from tidem.scene.types import Box, Fraction, NonNegative, Number, Positive, Strict, Vec3

Axis = Literal["x", "y", "z"]
Side = Literal["x-", "x+", "y-", "y+", "z-", "z+"]


class Domain(Box):
    """The simulation box, its periodic axes, its walls and gravity."""

    periodic: list[Axis] = []
    walls: Literal["auto", "none"] | list[Side] = "auto"
    wall_material: str | None = None
    wall_friction: NonNegative | None = None
    wall_temperature: ScheduledPositive | None = None
    gravity: Vec3 = (0.0, 0.0, -9.81)

    def wall_sides(self) -> list[str]:
        """Box sides that carry a wall: 'auto' means every side of a non-periodic axis but the top."""
        if self.walls == "none":
            return []
        if self.walls == "auto":
            return [f"{ax}{s}" for ax in "xyz" if ax not in self.periodic for s in "-+" if f"{ax}{s}" != "z+"]
        return list(self.walls)


class Material(Strict):
    """Solid properties of particles, walls and tubes."""

    density: Positive
    youngs_modulus: Positive
    poisson_ratio: Number = Field(default=0.3, ge=0.0, lt=0.5)
    restitution: Fraction = 0.5
    friction: NonNegative = 0.5
    dynamic_friction: NonNegative | None = None
    rolling_friction: NonNegative = 0.0
    rolling_damping: NonNegative = Field(default=0.3, le=1.0)
    conductivity: Positive | None = None
    heat_capacity: Positive | None = None
    real_youngs_modulus: Positive | None = None
    emissivity: Number | None = Field(default=None, gt=0.0, le=1.0)

    @model_validator(mode="after")
    def _dynamic_below_static(self):
        if self.dynamic_friction is not None and self.dynamic_friction > self.friction:
            raise ValueError(
                f"dynamic_friction ({self.dynamic_friction}) must not exceed friction ({self.friction})"
            )
        return self


class Mono(Strict):
    distribution: Literal["mono"] = "mono"
    value: Positive


class Uniform(Strict):
    distribution: Literal["uniform"]
    min: Positive
    max: Positive


class Normal(Strict):
    distribution: Literal["normal"]
    mean: Positive
    std: NonNegative
    min: Positive | None = None
    max: Positive | None = None


class LogNormal(Strict):
    distribution: Literal["lognormal"]
    median: Positive
    sigma: NonNegative
    min: Positive | None = None
    max: Positive | None = None


Diameter = Mono | Uniform | Normal | LogNormal


class Pour(Strict):
    """Particles appear over time at random places in a region."""

    region: Box
    rate: Positive
    start: NonNegative = 0.0


class ParticleGroup(Strict):
    """A set of particles of one material and one size distribution."""

    name: str
    material: str
    diameter: Diameter = Field(discriminator="distribution")
    count: StrictInt | None = Field(default=None, gt=0)
    region: Box | None = None
    lattice: Literal["cubic", "hexagonal"] = "cubic"
    positions: list[Vec3] | None = None
    pour: Pour | None = None
    velocity: Vec3 = (0.0, 0.0, 0.0)
    velocities: list[Vec3] | None = None
    temperature: Positive | None = None
    fixed: StrictBool = False
    seed: StrictInt = Field(default=0, ge=0)
    coarse_grain: Number = Field(default=1.0, ge=1.0, le=10.0)
    inside_mesh: StrictInt | None = Field(default=None, ge=0)
    skip_pockets: StrictBool = False

    @model_validator(mode="before")
    @classmethod
    def _mono_by_default(cls, data):
        d = data.get("diameter") if isinstance(data, dict) else None
        if isinstance(d, (int, float)) and not isinstance(d, bool):  # diameter = 0.001: one size
            d = {"value": d}
        if isinstance(d, dict) and "distribution" not in d:
            data = {**data, "diameter": {"distribution": "mono", **d}}
        return data

    @model_validator(mode="after")
    def _placement(self):
        ways = sum(x is not None for x in (self.region, self.positions, self.pour))
        if ways != 1:
            raise ValueError("give exactly one of 'region' (fill at start), 'positions' or 'pour'")
        if self.positions == []:
            raise ValueError("'positions' is empty: give at least one [x, y, z], or remove the group")
        if self.positions is not None and self.count is not None and self.count != len(self.positions):
            raise ValueError(f"count ({self.count}) differs from the number of positions ({len(self.positions)})")
        if self.inside_mesh is not None and self.region is None:
            raise ValueError("'inside_mesh' limits a filled 'region' to the inside of a mesh; give 'region' too")
        if self.skip_pockets and self.region is None:
            raise ValueError("'skip_pockets' leaves the pockets of a filled 'region' empty; give 'region' too")
        if self.pour is not None and self.count is None:
            raise ValueError("a poured group needs 'count' (the number of particles to pour)")
        if self.velocities is not None:
            if self.positions is None or len(self.velocities) != len(self.positions):
                raise ValueError("'velocities' needs 'positions' of the same length")
        return self


class Wall(Strict):
    """An infinite plane; `normal` points into the region the particles occupy."""

    point: Vec3
    normal: Vec3
    material: str | None = None
    friction: NonNegative | None = None
    velocity: Vec3 = (0.0, 0.0, 0.0)
    temperature: ScheduledPositive | None = None
    heat_flux: Positive | None = None
    foil_heat_capacity: Positive = 200.0

    @model_validator(mode="after")
    def _unit(self):
        if sum(c * c for c in self.normal) == 0:
            raise ValueError("normal must not be the zero vector")
        if self.temperature is not None and self.heat_flux is not None:
            raise ValueError("give either 'temperature' (fixed wall temperature) or 'heat_flux' (heated foil), not both")
        if self.heat_flux is not None and sum(c != 0 for c in self.normal) != 1:
            raise ValueError("a wall with 'heat_flux' needs a normal along x, y or z (its area is the domain's "
                             "cross-section)")
        if self.heat_flux is not None and any(self.velocity):
            raise ValueError("a wall with 'heat_flux' must not move")
        return self


class Tube(Strict):
    """An immersed horizontal tube (infinite cylinder along a horizontal axis). A heated tube
    has either a fixed `temperature` or a fixed `heat_flux` (source 3's heated foil)."""

    center: Vec3
    axis: Literal["x", "y"] = "y"
    diameter: Positive
    material: str | None = None
    friction: NonNegative | None = None
    temperature: ScheduledPositive | None = None
    heat_flux: Positive | None = None
    foil_heat_capacity: Positive = 200.0
    foil_conductance: NonNegative = 0.0

    @model_validator(mode="after")
    def _one_heating(self):
        if self.temperature is not None and self.heat_flux is not None:
            raise ValueError("give either 'temperature' (fixed wall temperature) or 'heat_flux' (heated foil), not both")
        return self


class MeshRotation(Strict):
    """Rigid rotation of a mesh wall about an axis through `center` (right-hand rule)."""

    center: Vec3
    axis: Vec3
    speed: ScheduledNumber


class Mesh(Strict):
    """A triangle-mesh wall read from a CAD file (STL, OBJ or PLY), two-sided. Its points are
    placed as R_z R_y R_x (scale x) + offset, `rotate` in degrees (first about x, then y, then z)."""

    file: str
    scale: Positive = 1.0
    rotate: Vec3 = (0.0, 0.0, 0.0)
    offset: Vec3 = (0.0, 0.0, 0.0)
    material: str | None = None
    friction: NonNegative | None = None
    temperature: ScheduledPositive | None = None
    convection_length: Positive | None = None
    rotation: MeshRotation | None = None
    velocity: ScheduledVec3 = (0.0, 0.0, 0.0)
    surface_velocity: Vec3 = (0.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _axis(self):
        if not self.file.strip():
            raise ValueError("file must name a mesh file (STL, OBJ or PLY), relative to the scene file")
        if self.rotation is not None and sum(c * c for c in self.rotation.axis) == 0:
            raise ValueError("rotation.axis must not be the zero vector; give the direction of the rotation axis, "
                             "e.g. [0.0, 1.0, 0.0]")
        return self


class Outlet(Strict):
    """How the bed leaves the domain."""

    type: Literal["moving_plate", "recycle", "sink"]
    speed: scheduled(Positive, NonNegativeSchedule) | None = None
    start: NonNegative = 0.0
    height: Number | None = None
    stop_height: Number | None = None
    reinsert_height: Number | None = None
    material: str | None = None
    friction: NonNegative | None = None

    @model_validator(mode="after")
    def _needs(self):
        if self.type == "moving_plate" and self.speed is None:
            raise ValueError("a moving_plate outlet needs 'speed' (plate speed downwards, m/s)")
        if self.type == "recycle" and (self.height is None or self.reinsert_height is None):
            raise ValueError("a recycle outlet needs 'height' and 'reinsert_height'")
        if self.type == "sink" and self.height is None:
            raise ValueError("a sink outlet needs 'height' (particles whose centre falls below it leave the run)")
        return self


class Contact(Strict):
    """The contact law between particles and with walls and tubes."""

    model: Literal["hertz_mindlin", "linear", "hysteretic", "none"] = "hertz_mindlin"
    parcel_restitution: Literal["kinetic_theory", "grains"] = "kinetic_theory"


class Numerics(Strict):
    """Time stepping, precision and the neighbour search."""

    t_end: Positive = 1.0
    dt: Positive | None = None
    dt_fraction: Number = Field(default=0.2, gt=0, le=1.0)
    force_dt: StrictBool = False
    impact_velocity: Positive | None = None
    precision: Literal["float32", "float64", "mixed"] = "float64"
    skin: Number = Field(default=0.1, ge=0.0, le=2.0)
    max_neighbors: StrictInt | None = Field(default=None, ge=4, le=512)
    max_wall_contacts: StrictInt = Field(default=4, ge=1, le=32)
    max_overlap: Number = Field(default=0.05, gt=0, le=0.5)
    check_interval: StrictInt = Field(default=100, ge=1)
    sort_interval: StrictInt = Field(default=20, ge=0)


class Output(Strict):
    """What a run writes and how often."""

    interval: Positive | None = None
    snapshots: StrictInt = Field(default=50, ge=1)
    timeseries_interval: Positive | None = None
    smoke_steps: StrictInt = Field(default=300, ge=1)
    checkpoint_wall_s: Positive = 600.0
    checkpoint_interval: Positive | None = None
    profile_times: list[Positive] | None = None
    profile_bins: StrictInt | None = Field(default=None, ge=1)


MAX_CONDUCTION_INTERVAL = 10000  # heat.conduction_interval: steps between evaluations of the conduction


class Heat(Strict):
    """Particle temperatures and conduction (only built when the scene has this table)."""

    initial_temperature: Positive = 293.15
    gas_conductivity: Positive = 0.026
    gas_mean_free_path: NonNegative = 6.8e-8
    roughness: NonNegative = 1e-6
    fluid_layer: Number = Field(default=0.4, ge=0.0, le=1.0)
    angle_bins: StrictInt = Field(default=36, ge=4, le=720)
    profile_start: NonNegative = 0.0
    radiation: StrictBool = False
    conduction_interval: StrictInt = Field(default=1, ge=1, le=MAX_CONDUCTION_INTERVAL)


class Averaging(Strict):
    """Time-averaged bed fields in cells and in ring sectors around the tubes (source 3 eq. 34-36)."""

    start: NonNegative = 0.0
    interval: Positive | None = None
    cell_size: tuple[Positive, Positive] | None = None
    ring_width: Positive | None = None
    rings: StrictInt = Field(default=3, ge=1, le=100)
    ring_sectors: StrictInt = Field(default=36, ge=4, le=720)


class Render(Strict):
    """Frames and movie of a run (`tidem render` can redo them with other settings)."""

    field: Literal["speed", "temperature", "radius", "group", "contacts"] | None = None
    range: tuple[Number, Number] | None = None
    colormap: str | None = None
    view: Literal["front", "side", "top", "iso"] = "front"
    height: StrictInt = Field(default=720, ge=240, le=2160)
    slice: Positive | None = None
    fps: StrictInt = Field(default=15, ge=1, le=120)
    gif: StrictBool = False

    @model_validator(mode="after")
    def _range(self):
        if self.range is not None and self.range[1] <= self.range[0]:
            raise ValueError(f"range: the upper end must exceed the lower ({list(self.range)})")
        return self


class Scene(Strict):
    """A whole scene file."""

    name: str | None = None
    description: str = ""
    runtime: str = ""
    domain: Domain
    contact: Contact = Contact()
    materials: dict[str, Material]
    particles: list[ParticleGroup] = Field(min_length=1)
    walls: list[Wall] = []
    tubes: list[Tube] = []
    meshes: list[Mesh] = []
    outlet: Outlet | None = None
    numerics: Numerics = Numerics()
    output: Output = Output()
    render: Render = Render()
    heat: Heat | None = None
    gas: Gas | None = None
    reactions: list[Reaction] = []
    averaging: Averaging | None = None
    observables: list[str] = []

    @field_validator("observables")
    @classmethod
    def _known_observables(cls, names: list[str]) -> list[str]:
        from tidem.scene.observable_names import unknown_name_message

        problems = [m for m in map(unknown_name_message, names) if m]
        if len(set(names)) != len(names):
            problems.append("a name is listed twice")
        if problems:
            raise ValueError("; ".join(problems))
        return names
