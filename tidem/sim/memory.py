"""Memory: what a scene's arrays will take, estimated from the scene alone before any of them
is allocated, and the refusal, naming the key to change, when a run would not fit.

Two estimates share one set of per-item formulas:
- `scene_refusal(scene)` runs first in `tidem.sim.model.build_model`, from the validated scene
  only (particle counts, lattice sites of a fill, size bounds), so that no array is made for
  a scene that cannot fit: the lattice of a region fill, the particle fields, the neighbour
  and contact-history tables, the gas grid, the averaging grids and the broad-phase cells.
- `memory_refusal(model)` runs at the end of `build_model` with the exact counts, before the
  Taichi fields of `tidem.sim.state` are allocated.

Sizes are computed with Python numbers (never numpy integers, which overflow silently) and
printed by `format_bytes` and `format_count`, which switch to scientific notation beyond
sane sizes instead of printing 30-digit figures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from tidem.gas.geometry import (averaging_length, cuts_tubes, gas_grid, layers_for, voidage_filters,
                                voidage_layers)
from tidem.kernels.gas_band import band_width
from tidem.particles.storage_order import sorts_storage
from tidem.runtime.startup import running_arch
from tidem.scene.averaging_layout import cell_grid
from tidem.scene.sizes import gas_cell_counts, largest_parcel, max_diameter, parcel_count
from tidem.sim.features import scene_features
from tidem.walls.mesh_bins import mesh_field_bytes

RUNTIME_BYTES = 172 * 2**20  # peak RSS of a run less fields and host arrays (measured, float64 bed of 20k)
HOST_BYTES_PER_PARTICLE = 1050  # numpy arrays of the scene and of the read-backs (measured, 20k vs 126k)
LATTICE_BYTES_PER_SITE = 96  # peak of a region fill per lattice site (measured 89 B cubic, 84 B hexagonal, 1M sites)
GAS_HOST_BYTES_PER_CELL = 100  # peak of the gas set-up per cell (solid_cells: indices, centres; measured)
CELL_BYTES = 4 * 3  # broad phase: cell start, count and sort offset per cell
_UNITS = ("B", "KiB", "MiB", "GiB", "TiB", "PiB")


def format_bytes(n: float) -> str:
    """'512 B', '3.2 TiB'; beyond 1024 PiB scientific notation in bytes ('1.2e+33 B')."""
    n = float(n)
    for unit in _UNITS:
        if abs(n) < 1024 or unit == _UNITS[-1]:
            break
        n /= 1024
    if unit == _UNITS[-1] and abs(n) >= 1024:
        return f"{n * 1024.0 ** (len(_UNITS) - 1):.2g} B"
    return f"{n:.3g} {unit}" if unit != "B" and n < 100 else f"{n:.0f} {unit}"


def format_count(n: float) -> str:
    """A count as digits up to ten million, in scientific notation beyond ('7.9e+09')."""
    return f"{int(n)}" if n < 1e7 else f"{float(n):.2g}"


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


def particle_field_bytes(feat, neighbors: int, wall_slots: int) -> int:
    """Bytes of the Taichi fields per particle (`tidem.sim.state.State`) other than the neighbour
    and contact-history rows; `feat` has the attributes of `tidem.sim.model.Features` used here."""
    fp = feat.float_bytes
    # vectors x v w f tq x_build + scalars; ints (slab, slab_list, nbr_count, nbr_touch, nbr_end ...) and float32 nbr_gap
    per = fp * (3 * 7 + 6) + 4 * 17
    per += wall_slots * (4 + 3 * fp)
    if feat.rolling:
        per += 3 * fp * wall_slots
    if feat.hysteretic:
        per += fp * wall_slots
    if feat.heat:
        per += 3 * fp  # T, q, 1/(m c)
    if feat.gas:
        per += fp * (8 + (2 if feat.heat else 0) + feat.species + feat.coarse_grain)  # gK geps gu ggp (gH gT) (gY) (cg)
    if feat.reactions:
        per += 4 + 2 * fp
    return per


def neighbor_bytes(feat, neighbors: int) -> int:
    """Bytes per particle of the neighbour list and its contact history (springs), with the
    rebuild's buffer of the history of pairs that change owner (one entry per particle)."""
    fp = feat.history_bytes
    per = (neighbors + 1) * 3 * fp + neighbors * 4 * 3  # ft and flip_ft; nbr, nbr_new, src
    if feat.rolling:
        per += 3 * fp * (neighbors + 1)
    if feat.hysteretic:
        per += fp * (neighbors + 1)
    return per


def gas_filters(scene, layers: int) -> tuple[bool, bool, bool]:
    """Which averaging-length filters a scene's gas makes (cells, layers, the drag's exchange on the faces;
    `tidem.gas.geometry.voidage_filters`) with `layers` voidage layers a cell."""
    made = voidage_filters(gas_grid(scene), averaging_length(scene), layers, scene.gas.drag_averaging == "length")
    return tuple(f is not None for f in made)


def gas_cell_bytes(feat, layers: int = 1, filters: tuple[bool, bool, bool] = (False, False, False),
                   cut_tubes: bool = False) -> int:
    """Bytes of the gas grid's Taichi fields per cell (`tidem.gas.fields.allocate_gas_fields`), with `layers` voidage
    layers a cell, the scratch fields of the averaging-length `filters` (`gas_filters`) and the tubes cut into the
    grid or not (`gas.tube_shape`)."""
    fp = feat.float_bytes
    open_share = 4 * bool(feat.n_meshes or feat.n_tubes)  # open volumes of the cell and its faces beside walls
    cut = 4 * bool(feat.n_meshes or (feat.n_tubes and cut_tubes))  # the cut's gas part of a cell, its faces' apertures
    layered = layers if layers > 1 else 0
    scratch = filters[0] + layers * filters[1] + 3 * 3 * filters[2]  # solid_tmp, layer_tmp; uf, face_tmp(2) per face
    return fp * (9 + 4 * feat.heat + 8 * 3 + bool(feat.reactions) + 3 * feat.species + open_share + cut + layered
                 + scratch) + 4 * 4


def gas_band_bytes(scene) -> int:
    """Bytes per gas cell of the direct pressure solve (`kernels/gas_band.py`: the factor's w + 1 entries and
    band_y, float64) on Taichi's present backend, on the CPU before Taichi starts (`tidem check`); 0 where the
    CG solves (a GPU, a grid too wide or wrapping)."""
    width = band_width(gas_grid(scene), running_arch() in (None, "cpu"))
    return 8 * (width + 2) if width else 0


def averaging_cell_bytes(feat) -> int:
    """Bytes per averaging cell or ring sector (float64 sums per channel)."""
    from tidem.kernels.averaging import channels

    return 8 * channels(feat.heat)


@dataclass(frozen=True)
class Item:
    """One large block of memory: what it is, its size, the scene key that sets it, the fix."""

    what: str
    bytes: float
    key: str
    fix: str


def _smallest_diameter(dist) -> float:
    """Smallest diameter a distribution can produce [m] (a lower bound for the neighbour count)."""
    if dist.distribution == "mono":
        return dist.value
    if dist.distribution == "uniform":
        return dist.min
    centre = dist.mean if dist.distribution == "normal" else dist.median
    return dist.min if dist.min is not None else 0.1 * centre


def lattice_site_count(region, spacing: float, kind: str) -> float:
    """Sites `tidem.particles.placement.lattice_sites` makes in a region before any is dropped."""
    lengths = [hi - lo for lo, hi in zip(region.min, region.max)]
    if kind == "hexagonal":
        a = spacing * math.sqrt(2.0)
        return 4.0 * math.prod(max(0.0, math.floor((n - spacing) / a)) + 2 for n in lengths)
    return math.prod(max(0.0, math.floor(n / spacing + 1e-9)) for n in lengths)


def default_neighbors(ratio: float, skin: float, fluid_layer: float) -> int:
    """Neighbour-list rows per particle when numerics.max_neighbors is not given: four times
    the neighbours a particle of the smallest size can have within its reach, for a largest to
    smallest diameter `ratio` (the neighbour search of `tidem.sim.model`)."""
    return int(4 * math.ceil(3.0 * ((1 + ratio) / 2) ** 2 * (1 + skin + 0.5 * fluid_layer) ** 3))


def scene_items(scene) -> list[Item]:
    """Every large block a run of `scene` allocates, estimated before any is made."""
    feat = scene_features(scene, 0, 0)  # the surface counts do not change any size
    items: list[Item] = []
    counts = []
    for i, g in enumerate(scene.particles):
        key = f"particles[{i}]"
        d = largest_parcel(g)
        if g.region is not None:
            sites = lattice_site_count(g.region, 1.02 * d, g.lattice)
            items.append(Item(f"the {format_count(sites)} lattice sites of the fill of {key}.region "
                              f"(diameter {d:g} m)", sites * LATTICE_BYTES_PER_SITE, f"{key}.diameter",
                              "use larger particles or a smaller region"))
        n = parcel_count(g)
        n = sites if n is None else n
        counts.append((float(n), f"{key}.count" if g.count is not None else f"{key}.region", key))
    fill = {k: f"use fewer particles (the most are in {k}: a smaller region, larger particles or a 'count')"
            for _, r, k in counts if r.endswith(".region")}
    total = sum(n for n, _, _ in counts)
    biggest = max(counts)
    dmax = max_diameter(scene)
    dmin = min(g.coarse_grain * _smallest_diameter(g.diameter) for g in scene.particles)
    num = scene.numerics
    fluid = scene.heat.fluid_layer if scene.heat is not None else 0.0
    k = num.max_neighbors or default_neighbors(dmax / dmin, num.skin, fluid)
    k, w = (k, num.max_wall_contacts) if feat.contacts else (1, 1)
    per = particle_field_bytes(feat, k, w) + HOST_BYTES_PER_PARTICLE
    items.append(Item(f"the fields of {format_count(total)} particles ({per} B each)", total * per, biggest[1],
                      fill.get(biggest[2], f"use fewer particles (the most are in {biggest[2]})")
                      + " or numerics.precision = \"float32\""))
    if feat.contacts:
        items.append(Item(f"the neighbour and contact-history tables ({k} rows of {format_count(total)} particles)",
                          total * neighbor_bytes(feat, k), "numerics.max_neighbors",
                          "use fewer particles or a smaller numerics.max_neighbors"))
    pours = any(g.pour is not None for g in scene.particles)
    if sorts_storage(feat, int(total), pours, num.sort_interval):
        items.append(sort_item(total, particle_field_bytes(feat, k, w) + neighbor_bytes(feat, k)))
    lengths = [hi - lo for lo, hi in zip(scene.domain.min, scene.domain.max)]
    reach = dmax * (1 + num.skin + 0.5 * fluid)
    cells = min(math.prod(max(1.0, math.floor(n / reach)) for n in lengths), max(64 * total, 2.0**20))
    items.append(Item(f"the {format_count(cells)} broad-phase cells", cells * CELL_BYTES, "domain",
                      "use a smaller domain"))
    if scene.gas is not None:
        cells = math.prod(gas_cell_counts(scene))
        grains = scene.gas.parcel_voidage == "grain_layers"  # layers one grain high, else one parcel high
        layers = layers_for(scene, min((1 if grains else g.coarse_grain) * _smallest_diameter(g.diameter)
                                       for g in scene.particles))
        per_cell = gas_cell_bytes(feat, layers, gas_filters(scene, layers), cuts_tubes(scene)) + gas_band_bytes(scene)
        per_cell += GAS_HOST_BYTES_PER_CELL
        items.append(Item(f"the {format_count(cells)} cells of the gas grid", cells * per_cell, "gas.cell_size",
                          "use larger gas cells or a smaller domain"))
    if scene.averaging is not None:
        cells = math.prod(cell_grid(scene)[0])
        items.append(Item(f"the {format_count(cells)} averaging cells", cells * averaging_cell_bytes(feat),
                          "averaging.cell_size", "use larger averaging cells"))
    return items


def refusal(items: list[Item], have: int | None) -> list[str]:
    """Messages when the items and the runtime exceed `have` bytes: the total, then each item
    that takes a tenth of it or more, with its key and fix."""
    need = RUNTIME_BYTES + sum(it.bytes for it in items)
    if have is None or need <= have:
        return []
    out = [f"memory: the run needs about {format_bytes(need)} ({format_bytes(RUNTIME_BYTES)} of it the Python and "
           f"Taichi runtime), this machine has {format_bytes(have)} available; free memory or shrink the scene:"]
    for it in sorted(items, key=lambda it: -it.bytes):
        if it.bytes >= 0.1 * need:
            out.append(f"{it.key}: {it.what} take {format_bytes(it.bytes)}; {it.fix}")
    return out


def scene_refusal(scene) -> list[str]:
    """The refusal of a scene too large for this machine, from the scene alone."""
    return refusal(scene_items(scene), available_memory_bytes())


def model_items(model) -> list[Item]:
    """The large blocks of a built Model (exact counts; see `scene_items`)."""
    f, n = model.features, model.capacity
    per = particle_field_bytes(f, model.max_neighbors, model.wall_slots) + HOST_BYTES_PER_PARTICLE
    items = [Item(f"the fields of {format_count(n)} particles ({per} B each)", n * per, "particles",
                  "use fewer particles or numerics.precision = \"float32\""),
             Item(f"the neighbour and contact-history tables ({model.max_neighbors} rows per particle)",
                  n * neighbor_bytes(f, model.max_neighbors), "numerics.max_neighbors",
                  "use a smaller numerics.max_neighbors or fewer particles"),
             Item(f"the {format_count(model.grid.n_cells)} broad-phase cells", model.grid.n_cells * CELL_BYTES,
                  "domain", "use a smaller domain")]
    if per_sort := sort_bytes(model):
        items.append(sort_item(n, per_sort))
    items += [Item(it.what, it.bytes, it.key, it.fix) for it in scene_items(model.scene)
              if it.key in ("gas.cell_size", "averaging.cell_size")]
    return items


def sort_bytes(model) -> int:
    """Bytes per particle of the storage sort's scratch twins (`kernels/storage_sort.py`): a copy of every
    particle field and table row, or 0 where the run does not sort."""
    f = model.features
    if not sorts_storage(f, model.capacity, bool(model.pours), model.scene.numerics.sort_interval):
        return 0
    return particle_field_bytes(f, model.max_neighbors, model.wall_slots) + neighbor_bytes(f, model.max_neighbors)


def sort_item(particles: float, per: int) -> Item:
    """The storage sort's scratch copy of the particle fields, `per` bytes a particle."""
    return Item(f"the storage sort's scratch copy of the particle fields ({per} B a particle)", particles * per,
                "numerics.sort_interval", "set numerics.sort_interval = 0 (no re-sort) or use fewer particles")


def field_bytes(model) -> int:
    """Expected memory of the Taichi fields of a built Model [bytes] (see `tidem.sim.state.State`)."""
    f = model.features
    per = particle_field_bytes(f, model.max_neighbors, model.wall_slots) + neighbor_bytes(f, model.max_neighbors)
    per += sort_bytes(model)
    cells = model.grid.n_cells * CELL_BYTES
    if f.gas:
        layers = voidage_layers(model)
        per_cell = (gas_cell_bytes(f, layers, gas_filters(model.scene, layers), cuts_tubes(model.scene))
                    + gas_band_bytes(model.scene))
        cells += math.prod(gas_grid(model.scene).cells) * per_cell
    return per * model.capacity + cells + mesh_field_bytes(model)


def memory_refusal(model) -> list[str]:
    """The refusal of a built Model whose run would need more memory than is available."""
    return refusal(model_items(model), available_memory_bytes())
