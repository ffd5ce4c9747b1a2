"""The Model: everything about a run that does not change while it runs, derived once from a
validated scene (sizes, masses, material-pair table, walls, tubes, grid, time step, flags).
Plain numpy and numbers only; `tidem.state` turns them into Taichi fields.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tidem.contact_params import hysteretic_floor_errors, parameter_tables
from tidem.features import Features, scene_features
from tidem.gas_limits import gas_step_checks
from tidem.heat_limits import heat_step_errors
from tidem.kernels.geometry import Grid
from tidem.placement import place_groups
from tidem.reactions import reaction_constants, reaction_index, reaction_step_checks
from tidem.scene.averaging_layout import AveragingLayout, averaging_layout
from tidem.scene.errors import SceneError
from tidem.scene.load import LoadedScene
from tidem.scene.sizes import max_diameter
from tidem.surfaces import AXES, is_heated, surfaces
from tidem.timestep import TimeScales, contact_time_step


@dataclass
class Model:
    """Constant data of a run. Per-particle arrays have shape [capacity]."""

    name: str
    loaded: LoadedScene
    features: Features
    grid: Grid
    capacity: int
    radius: np.ndarray
    mass: np.ndarray
    material: np.ndarray
    group: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    active0: np.ndarray
    pair_params: np.ndarray
    surface_params: np.ndarray
    planes: list[dict]
    tubes: list[dict]
    pours: list[dict]
    dt: float
    scales: TimeScales
    skin: float
    max_neighbors: int
    wall_slots: int
    t_end: float
    gravity: tuple[float, float, float]
    fixed: np.ndarray | None = None
    temperature0: np.ndarray | None = None
    heat_capacity: np.ndarray | None = None
    thermal_limit: float | None = None
    angle_bins: int = 0
    fluid_layer: float = 0.0  # particle-fluid-particle lens thickness / smaller radius (0: off)
    heat_reach: float = 0.0  # extra neighbour-list reach for that lens [m]
    reaction_index: np.ndarray | None = None
    reaction_constants: list | None = None
    averaging: AveragingLayout | None = None

    @property
    def scene(self):
        return self.loaded.scene

    def memory_bytes(self) -> int:
        """Expected memory of the Taichi fields [bytes] (see `tidem.state.State`)."""
        fp = 8 if self.features.precision == "float64" else 4
        k, w = self.max_neighbors, self.wall_slots
        per = fp * (3 * 7 + 6) + 4 * 8  # vectors x v w f tq x_build + scalars; ints
        per += k * (4 * 3 + 3 * fp)  # nbr, nbr_new, src, ft
        per += w * (4 + 3 * fp)
        if self.features.rolling:
            per += 3 * fp * (k + w)
        if self.features.hysteretic:
            per += fp * (k + w)
        if self.features.heat:
            per += 3 * fp + (k * fp if self.features.contacts else 0)  # T, q, 1/(m c); qpair
        if self.features.gas:
            per += fp * (8 + (2 if self.features.heat else 0) + self.features.species)
        if self.features.reactions:
            per += 4 + 2 * fp
        cells = self.grid.n_cells * 4 * 3
        if self.features.gas:
            from tidem.gas import gas_grid

            gas_cells = int(np.prod(gas_grid(self.scene).cells))
            cells += gas_cells * (fp * (9 + 4 * self.features.heat + 8 * 3 + bool(self.features.reactions)
                                        + 3 * self.features.species) + 4 * 4)
        return per * self.capacity + cells

    def peak_memory_bytes(self) -> int:
        """Expected peak resident memory of a run [bytes]: the Python + Taichi + LLVM runtime,
        the Taichi fields, and the host copies of per-particle arrays (scene arrays, snapshot
        and check read-backs); constants measured on 20k and 126k particle beds."""
        return RUNTIME_BYTES + self.memory_bytes() + HOST_BYTES_PER_PARTICLE * self.capacity


RUNTIME_BYTES = 172 * 2**20  # peak RSS of a run less fields and host arrays (measured, float64 bed of 20k)
HOST_BYTES_PER_PARTICLE = 1050  # numpy arrays of the scene and of the read-backs (measured, 20k vs 126k)


def available_memory_bytes() -> int | None:
    """MemAvailable of /proc/meminfo [bytes], or None where it cannot be read."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def peak_resident_bytes() -> int:
    """This process's peak resident memory [bytes]: VmHWM of /proc/self/status where it exists.

    getrusage's ru_maxrss is not used on Linux: it survives execve, so a process started from a
    large parent (a long pytest session) reports the parent's size, not its own."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def memory_refusal(model: "Model") -> list[str]:
    """A message when the run would need more memory than the machine has available."""
    need, have = model.peak_memory_bytes(), available_memory_bytes()
    if have is None or need <= have:
        return []
    return [f"the run needs about {need / 2**30:.2f} GiB ({model.capacity} particles x "
            f"{model.memory_bytes() / model.capacity + HOST_BYTES_PER_PARTICLE:.0f} B + "
            f"{RUNTIME_BYTES / 2**20:.0f} MiB runtime), this machine has {have / 2**30:.2f} GiB available: "
            "use fewer particles, numerics.precision = \"float32\", or a smaller numerics.max_neighbors"]


def neighbour_grid(lo, lengths, periodic, capacity: int, reach: float) -> Grid:
    """The broad phase's cell grid over the domain: cells at least `reach` wide (largest
    diameter + skin + gas lens), coarsened for a sparse, huge domain to at most
    max(64 capacity, 2^20) cells."""
    cells = [max(1, int(lengths[a] / reach)) for a in range(3)]
    while np.prod(cells) > max(64 * capacity, 1 << 20):
        cells = [max(3 if periodic[a] else 1, c // 2) for a, c in enumerate(cells)]
    return Grid(lo=tuple(lo), length=tuple(lengths), periodic=periodic, cells=tuple(cells))


def neighbour_slots(num, d_max: float, d_min: float, fluid_layer: float) -> int:
    """numerics.max_neighbors, else 4 x the spheres of diameter d_min that fit in the reach of
    the largest particle (skin and gas lens included)."""
    ratio = d_max / d_min
    return num.max_neighbors or int(4 * math.ceil(3.0 * ((1 + ratio) / 2) ** 2 * (1 + num.skin + 0.5 * fluid_layer) ** 3))


def build_model(loaded: LoadedScene, smoke: bool = False, t_end: float | None = None) -> Model:
    """Derive the Model from a validated scene; raises SceneError for problems found here."""
    scene = loaded.scene
    src = str(loaded.source)
    dom = scene.domain
    mats = scene.materials
    num = scene.numerics
    errors = hysteretic_floor_errors(scene)
    if errors:
        raise SceneError(src, errors)
    mat_names = list(mats)
    planes, tubes = surfaces(scene, scene.particles[0].material)
    periodic = tuple(AXES[a] in dom.periodic for a in range(3))
    lengths = [dom.max[a] - dom.min[a] for a in range(3)]
    placed, errors = place_groups(scene, planes, tubes, lengths, periodic)
    if errors:
        raise SceneError(src, errors)
    radius, material, fixed = placed.radius, placed.material, placed.fixed
    density = np.array([mats[m].density for m in mat_names])[material]
    mass = density * 4.0 / 3.0 * math.pi * radius**3
    pair, surf = parameter_tables(scene, mat_names, planes + tubes)

    contacts = scene.contact.model != "none"
    all_fixed = bool(fixed.all())
    dt, scales, errors = contact_time_step(scene, material, radius, placed.x0, placed.v0, placed.active0,
                                           planes + tubes, all_fixed)
    if errors:
        raise SceneError(src, errors)

    d_max = max_diameter(scene)
    skin = num.skin * d_max
    fluid_layer = scene.heat.fluid_layer if scene.heat is not None else 0.0
    heat_reach = 0.5 * fluid_layer * d_max
    grid = neighbour_grid(dom.min, lengths, periodic, len(radius), d_max + skin + heat_reach)
    k = neighbour_slots(num, d_max, 2.0 * radius.min(), fluid_layer) if contacts else 1  # 1: no list is built

    heat_cap = thermal_limit = None
    if scene.heat is not None:
        c = np.array([mats[m].heat_capacity or 0.0 for m in mat_names])[material]
        heat_cap = mass * c
        thermal_limit, errors = heat_step_errors(scene, material, radius, heat_cap, k, planes + tubes, dt, contacts)
        if errors:
            raise SceneError(src, errors)
    if scene.gas is not None:
        errors = gas_step_checks(scene, dt, radius, density, placed.x0 if all_fixed else None)
        if errors:
            raise SceneError(src, errors)
    rx = rconst = None
    if scene.reactions:
        rx = reaction_index(scene, placed.group)
        rconst = reaction_constants(scene)
        errors = reaction_step_checks(scene, dt, radius, density, rx)
        if errors:
            raise SceneError(src, errors)
    end = t_end if t_end is not None else num.t_end
    if smoke:
        end = min(end, scene.output.smoke_steps * dt)
    model = Model(
        name=loaded.name, loaded=loaded, features=scene_features(scene, len(planes), len(tubes)), grid=grid,
        capacity=len(radius), radius=radius, mass=mass, material=material, group=placed.group, x0=placed.x0,
        v0=placed.v0, active0=placed.active0, pair_params=pair, surface_params=surf, planes=planes, tubes=tubes,
        pours=placed.pours, dt=dt, scales=scales, skin=skin, max_neighbors=k,
        wall_slots=num.max_wall_contacts if contacts else 1,
        t_end=end, gravity=tuple(dom.gravity), fixed=fixed, temperature0=placed.temperature0, heat_capacity=heat_cap,
        thermal_limit=thermal_limit, fluid_layer=fluid_layer, heat_reach=heat_reach,
        angle_bins=scene.heat.angle_bins if scene.heat is not None and any(map(is_heated, tubes)) else 0,
        reaction_index=rx, reaction_constants=rconst,
        averaging=averaging_layout(scene),
    )
    too_big = memory_refusal(model)
    if too_big:
        raise SceneError(src, too_big)
    return model
