"""The Model: everything about a run that does not change while it runs, derived once from a
validated scene (sizes, masses, material-pair table, walls, tubes, grid, time step, flags).
Plain numpy and numbers only; `tidem.sim.state` turns them into Taichi fields.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tidem.gas.geometry import mesh_gas_cut
from tidem.gas.limits import gas_step_checks
from tidem.gas.mesh import GasCut
from tidem.heat.limits import heat_step_errors
from tidem.heat.reactions import reaction_constants, reaction_index, reaction_step_checks
from tidem.kernels.geometry import Grid, slab_axis_for
from tidem.particles.contact_params import hysteretic_floor_errors, parameter_tables
from tidem.particles.overlaps import initial_overlaps
from tidem.particles.placement import place_groups
from tidem.particles.timestep import TimeScales, contact_time_step, impact_speed
from tidem.scene.averaging_layout import AveragingLayout, averaging_layout
from tidem.scene.errors import SceneError
from tidem.scene.load import LoadedScene
from tidem.scene.sizes import max_diameter
from tidem.sim.features import Features, scene_features
from tidem.sim.memory import (HOST_BYTES_PER_PARTICLE, RUNTIME_BYTES, default_neighbors, field_bytes, memory_refusal,
                              scene_refusal)
from tidem.walls.mesh_bins import MeshTable, mesh_table
from tidem.walls.mesh_load import load_mesh_walls, tube_mesh_overlaps
from tidem.walls.mesh_walls import pass_through_errors
from tidem.walls.surfaces import AXES, is_heated, surfaces


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
    coarse_grain: np.ndarray | None = None  # k of each particle's group: a parcel of k^3 grains (1: a grain)
    meshes: list = field(default_factory=list)  # [[meshes]] as tidem.walls.mesh_walls.MeshWall
    mesh_table: MeshTable | None = None  # their triangles and bins as the kernels hold them
    gas_cut: GasCut | None = None  # with [gas]: what the meshes do to the gas grid (tidem.gas.mesh)
    pocket_sites: dict[int, int] = field(default_factory=dict)  # group -> lattice sites skip_pockets left empty

    def uniform_particles(self) -> tuple[float, float] | None:
        """(radius, mass) where all particles have the same and keep it (no reactions), else None: the
        contact passes then take them as constants (`kernels/contact.py`)."""
        r, m = self.radius, self.mass
        if self.features.reactions or len(r) == 0 or r.min() != r.max() or m.min() != m.max():
            return None
        return float(r[0]), float(m[0])

    def one_material(self) -> tuple[list[float], list[list[float]]] | None:
        """Where all particles are of one material (walls and tubes may be of others): its material-pair
        parameters and its material-surface parameters for each surface, else None; the contact passes
        then take them as constants."""
        m = self.material
        if len(m) == 0 or m.min() != m.max():
            return None
        return self.pair_params[m[0], m[0]].tolist(), self.surface_params[m[0]].tolist()

    @property
    def scene(self):
        return self.loaded.scene

    @property
    def grain_scale(self) -> float:
        """k of a scene whose particles are all parcels of one size ratio (scene.checks refuses
        mixed k with heat, the only place a scene-wide k is needed); 1 otherwise."""
        ks = np.unique(self.coarse_grain)
        return float(ks[0]) if len(ks) == 1 else 1.0

    def memory_bytes(self) -> int:
        """Expected memory of the Taichi fields [bytes] (see `tidem.sim.state.State`)."""
        return field_bytes(self)

    def peak_memory_bytes(self) -> int:
        """Expected peak resident memory of a run [bytes]: the Python + Taichi + LLVM runtime,
        the Taichi fields, and the host copies of per-particle arrays (scene arrays, snapshot
        and check read-backs); constants measured on 20k and 126k particle beds."""
        return RUNTIME_BYTES + self.memory_bytes() + HOST_BYTES_PER_PARTICLE * self.capacity


def neighbour_grid(lo, lengths, periodic, capacity: int, reach: float, gravity=(0.0, 0.0, 0.0)) -> Grid:
    """The broad phase's cell grid over the domain: cells at least `reach` wide (largest
    diameter + skin + gas lens), coarsened for a sparse, huge domain to at most
    max(64 capacity, 2^20) cells; its slab axis chosen by `gravity` (`kernels/geometry.py`), with an
    even count of cells along it (one fewer where it was odd), so that each slab of the contact
    passes is one layer of cells and the neighbour build skips the layer behind
    (`kernels/broadphase.py`)."""
    cells = [max(1, int(lengths[a] / reach)) for a in range(3)]
    while math.prod(cells) > max(64 * capacity, 1 << 20):
        cells = [max(min(c, 3) if periodic[a] else 1, c // 2) for a, c in enumerate(cells)]
    axis = slab_axis_for(cells, gravity)
    if cells[axis] >= 3 and cells[axis] % 2:
        cells[axis] -= 1
    return Grid(lo=tuple(lo), length=tuple(lengths), periodic=periodic, cells=tuple(cells), slab_axis=axis)


def neighbour_slots(num, d_max: float, d_min: float, fluid_layer: float) -> int:
    """numerics.max_neighbors, else 4 x the spheres of diameter d_min that fit in the reach of
    the largest particle (skin and gas lens included)."""
    return num.max_neighbors or default_neighbors(d_max / d_min, num.skin, fluid_layer)


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
    too_big = scene_refusal(scene)  # before any array of the scene's size is made
    if too_big:
        raise SceneError(src, too_big)
    mat_names = list(mats)
    planes, tubes = surfaces(scene, scene.particles[0].material)
    meshes, errors = load_mesh_walls(scene, loaded.source, scene.particles[0].material)
    errors = errors or tube_mesh_overlaps(scene, meshes)
    if errors:
        raise SceneError(src, errors)
    walls = planes + tubes + [m.surface() for m in meshes]  # every surface, for the tables and the step limits
    periodic = tuple(AXES[a] in dom.periodic for a in range(3))
    lengths = [dom.max[a] - dom.min[a] for a in range(3)]
    placed, errors = place_groups(scene, planes, tubes, lengths, periodic, meshes)
    if errors:
        raise SceneError(src, errors)
    radius, material, fixed = placed.radius, placed.material, placed.fixed
    coarse_grain = np.array([g.coarse_grain for g in scene.particles])[placed.group]  # parcel / grain diameter
    grain_radius = radius / coarse_grain
    density = np.array([mats[m].density for m in mat_names])[material]
    mass = density * 4.0 / 3.0 * math.pi * radius**3
    pair, surf = parameter_tables(scene, mat_names, walls)

    contacts = scene.contact.model != "none"
    all_fixed = bool(fixed.all())
    overlaps = contacts and initial_overlaps(scene, placed.x0, radius, placed.active0, placed.group, planes, tubes,
                                             lengths, periodic)
    if overlaps:
        raise SceneError(src, overlaps)
    dt, scales, errors = contact_time_step(scene, material, radius, placed.x0, placed.v0, placed.active0,
                                           walls, all_fixed)
    if not errors and contacts:  # fixed particles never move: only a mesh's own motion can close on them
        speed = 0.0 if all_fixed else impact_speed(scene, placed.v0)
        errors = pass_through_errors(meshes, dt, speed, float(radius.min()))
    if errors:
        raise SceneError(src, errors)

    d_max = max_diameter(scene)
    skin = num.skin * d_max
    fluid_layer = scene.heat.fluid_layer if scene.heat is not None else 0.0
    heat_reach = 0.5 * fluid_layer * d_max
    grid = neighbour_grid(dom.min, lengths, periodic, len(radius), d_max + skin + heat_reach, dom.gravity)
    k = neighbour_slots(num, d_max, 2.0 * radius.min(), fluid_layer) if contacts else 1  # 1: no list is built
    # triangles within a particle's reach (half the largest diameter, skin, gas lens) of each cell, and a
    # moving mesh's a diameter beyond, so that it is binned anew only after moving that far
    table = mesh_table(meshes, grid, 0.5 * d_max, skin, heat_reach, d_max) if meshes and contacts else None

    heat_cap = thermal_limit = None
    if scene.heat is not None:
        c = np.array([mats[m].heat_capacity or 0.0 for m in mat_names])[material]
        heat_cap = mass * c
        thermal_limit, errors = heat_step_errors(scene, material, radius, heat_cap, k, walls, dt, contacts,
                                                   coarse_grain)
        if errors:
            raise SceneError(src, errors)
    cut = None
    if scene.gas is not None:
        errors = gas_step_checks(scene, dt, radius, density, placed.x0 if all_fixed else None, grain_radius)
        cut, cut_errors = mesh_gas_cut(scene, tubes, meshes)
        errors += cut_errors
        if errors:
            raise SceneError(src, errors)
    rx = rconst = None
    if scene.reactions:
        rx = reaction_index(scene, placed.group)
        rconst = reaction_constants(scene)
        errors = reaction_step_checks(scene, dt, grain_radius, density, rx)
        if errors:
            raise SceneError(src, errors)
    end = t_end if t_end is not None else num.t_end
    if smoke:
        end = min(end, scene.output.smoke_steps * dt)
    model = Model(
        name=loaded.name, loaded=loaded, features=scene_features(scene, len(planes), len(tubes), meshes), grid=grid,
        capacity=len(radius), radius=radius, mass=mass, material=material, group=placed.group, x0=placed.x0,
        v0=placed.v0, active0=placed.active0, pair_params=pair, surface_params=surf, planes=planes, tubes=tubes,
        pours=placed.pours, dt=dt, scales=scales, skin=skin, max_neighbors=k,
        wall_slots=num.max_wall_contacts if contacts else 1,
        t_end=end, gravity=tuple(dom.gravity), fixed=fixed, temperature0=placed.temperature0, heat_capacity=heat_cap,
        thermal_limit=thermal_limit, fluid_layer=fluid_layer, heat_reach=heat_reach,
        angle_bins=scene.heat.angle_bins if scene.heat is not None and any(map(is_heated, tubes)) else 0,
        reaction_index=rx, reaction_constants=rconst,
        averaging=averaging_layout(scene),
        coarse_grain=coarse_grain, meshes=meshes, mesh_table=table, gas_cut=cut, pocket_sites=placed.pocket_sites,
    )
    too_big = memory_refusal(model)
    if too_big:
        raise SceneError(src, too_big)
    return model
