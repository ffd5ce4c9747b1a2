"""The gas grid of a scene's `[gas]` table, set-up side (plain numpy; the grid's index maths is
`kernels/gas_grid.py`): cells of about `gas.cell_size`, the cells inside tubes (walls for the
gas), the kind of every face (closed, interior, inlet at the bottom, outlet at the top), the
inlet velocity of each bottom face and the tube (and heated mesh) surface each cell borders
(gas-tube convection). Meshes cut the grid in `tidem.gas.mesh` (blocked faces, cells the gas cannot
reach, open volume of cut cells); `gas_walls` puts tubes and meshes together; the open volume each
cell's voidage is taken over is `tidem.gas.open_volume`.
"""

from __future__ import annotations

import numpy as np

from tidem.gas.mesh import GasCut, gas_cut
from tidem.gas.mesh_convection import inward_sides, wetted_area
from tidem.gas.tube_cut import tube_axis, tube_cut_walls, tubes_triangles
from tidem.kernels.gas_grid import CLOSED, INLET, INTERIOR, OUTLET, GasGrid
from tidem.kernels.gas_smoothing import plan_filter
from tidem.kernels.layered_voidage import parcel_rows
from tidem.scene.sizes import AVERAGING_GRAINS, gas_cell_counts, largest_grain


def gas_grid(scene) -> GasGrid:
    """Cells of about `gas.cell_size` (a whole number per axis) over the domain."""
    dom = scene.domain
    cells = gas_cell_counts(scene)
    h = [(dom.max[a] - dom.min[a]) / cells[a] for a in range(3)]
    periodic = tuple("xyz"[a] in dom.periodic for a in range(3))
    return GasGrid(lo=tuple(dom.min), cells=cells, h=tuple(h), periodic=periodic)


def axis_distance2(gg: GasGrid, tube: dict) -> np.ndarray:
    """[cells, flat] the squared distance of each cell centre from a tube's axis."""
    idx = np.indices(gg.cells).reshape(3, -1).T
    d = (np.asarray(gg.lo) + (idx + 0.5) * np.asarray(gg.h) - np.asarray(tube["c"])) * np.asarray(tube["mask"])
    return np.einsum("ij,ij->i", d, d)


def tube_cells(gg: GasGrid, tube: dict) -> np.ndarray:
    """The cells a tube fills for the gas: those whose centre lies inside it, or, for a tube
    too thin to hold a cell centre, the one row of cells along its axis nearest to it (the
    first of equals on a cell edge or corner), so that every tube blocks the gas and exchanges
    heat with it. Tubes centred on cell centres are represented best."""
    dist2 = axis_distance2(gg, tube)
    inside = dist2 < tube["r"] ** 2
    if not inside.any():
        idx = np.indices(gg.cells).reshape(3, -1).T
        across = np.asarray(tube["mask"]) > 0  # the two axes across the tube
        nearest = idx[np.argmin(dist2)]
        inside = (idx[:, across] == nearest[across]).all(axis=1)
    return inside.reshape(gg.cells)


def section_per_cell(gg: GasGrid, tube: dict) -> float:
    """The share of a tube's section that one whole cell along its length stands for (a cell's area across the
    axis over the cells along it, over pi r^2)."""
    axis = tube_axis(tube)
    across = np.prod([gg.h[a] for a in range(3) if a != axis])
    return float(across / gg.cells[axis] / (np.pi * tube["r"] ** 2))


def staircase_share(gg: GasGrid, tube: dict) -> float:
    """The share of a tube's section that its cells (`tube_cells`) block for the gas."""
    return float(tube_cells(gg, tube).sum()) * section_per_cell(gg, tube)


def cut_share(gg: GasGrid, tube: dict, cut: GasCut) -> float:
    """The share of a tube's section that the gas loses to it cut into the grid (`gas.tube_shape = "cut"`): the
    cells sealed whole and the cut cells' part outside their gas part, over the cells within half a cell's
    diagonal of the tube's surface."""
    axis = tube_axis(tube)
    reach = tube["r"] + 0.5 * np.hypot(*[gg.h[a] for a in range(3) if a != axis])
    near = (axis_distance2(gg, tube) < reach**2).reshape(gg.cells)
    lost = np.where(cut.unreachable, 1.0, 1.0 - cut.open_fraction)[near].sum()
    return float(lost) * section_per_cell(gg, tube)


def solid_cells(gg: GasGrid, tubes: list[dict]) -> np.ndarray:
    """1 for the cells a tube fills (`tube_cells`: wall for the gas)."""
    solid = np.zeros(gg.cells, np.int32)
    for t in tubes:
        solid |= tube_cells(gg, t).astype(np.int32)
    return solid


def gas_walls(gg: GasGrid, tubes: list[dict], meshes: list, cut: GasCut | None = None,
              cut_tubes: bool = False) -> tuple[np.ndarray, list[np.ndarray], GasCut | None]:
    """The walls the gas sees: solid cells (in a tube, or out of the gas's reach behind a mesh or, with
    `cut_tubes` (`gas.tube_shape = "cut"`), inside a tube drawn as a prism, `tidem.gas.tube_cut`), face kinds
    (`face_kinds`, with the faces the cut blocks closed), and the cut of the grid (`cut` if given, as the Model
    keeps it; None without meshes and cut tubes; meshes are static when there is gas, `tidem.scene.checks`)."""
    solid = solid_cells(gg, [] if cut_tubes else tubes)
    kinds = face_kinds(gg, solid)
    if not meshes and not (cut_tubes and tubes):
        return solid, kinds, None
    if cut is None:
        tri, clip = tubes_triangles(gg, tubes if cut_tubes else [])
        if meshes:
            tri = np.concatenate([tri, *(m.vertices[m.triangles] for m in meshes)])
            clip = np.concatenate([clip, spans_period(gg, meshes)])
        cut = gas_cut(gg, tri, solid, kinds, clip)
    solid = solid | cut.unreachable.astype(np.int32)
    kinds = [np.where(b, CLOSED, k) for b, k in zip(cut.blocked, face_kinds(gg, solid))]
    return solid, kinds, cut


def spans_period(gg: GasGrid, meshes: list) -> np.ndarray:
    """[T, 3] per triangle (all meshes in order) and axis: the axis is periodic and the triangle's
    mesh spans the whole period along it, so that what it holds beyond the period is not part of
    the apparatus (the particles' rule, `mesh_bins.triangle_table`); elsewhere a mesh wraps."""
    rows = [np.tile([gg.periodic[a] and m.spans(a, gg.lo[a], gg.cells[a] * gg.h[a]) for a in range(3)],
                    (len(m.triangles), 1)) for m in meshes]
    return np.concatenate(rows).astype(bool)


def cuts_tubes(scene) -> bool:
    """Whether the gas grid's tubes are cut cells (`gas.tube_shape = "cut"`) rather than the staircase."""
    return scene.gas is not None and scene.gas.tube_shape == "cut"


def mesh_gas_cut(scene, tubes: list[dict], meshes: list) -> tuple[GasCut | None, list[str]]:
    """The meshes' (and with `gas.tube_shape = "cut"` the tubes') cut of a scene's gas grid (None without gas, or
    without meshes and cut tubes), and the refusal of a cut through which no gas can flow."""
    if scene.gas is None or not (meshes or (cuts_tubes(scene) and tubes)):
        return None, []
    solid, kinds, cut = gas_walls(gas_grid(scene), tubes, meshes, cut_tubes=cuts_tubes(scene))
    if (kinds[2][:, :, 0] == INLET).any():
        return cut, []
    keys = [k for k, present in (("meshes", meshes), ("tubes", cuts_tubes(scene) and tubes)) if present]
    walls = " and ".join(keys)
    return cut, [f"{', '.join(keys)}: the {walls} close every inlet face of the gas grid, or every path "
                 f"from the inlet to the outlet ({int(cut.unreachable.sum())} of {solid.size} gas cells sealed off), "
                 f"so no gas can flow: open the distributor under the {walls} and a way up to the top, or make "
                 f"gas.cell_size fit the openings (a face is closed where a wall cuts half of it)"]


def shifted(gg: GasGrid, mask: np.ndarray, a: int, shift: int) -> np.ndarray:
    """`mask` moved `shift` (+1 or -1) cells along axis a: wrapped on a periodic axis, False coming in
    from an open side."""
    out = np.roll(mask, shift, axis=a)
    if not gg.periodic[a]:
        edge = [slice(None)] * 3
        edge[a] = 0 if shift == 1 else -1
        out[tuple(edge)] = False
    return out


def tube_walls(gg: GasGrid, tubes: list[dict]) -> dict[str, np.ndarray] | None:
    """Per cell, the surface of a heated tube that the cell borders, for gas-tube convection:
    wall_A [m^2] (the faces it shares with that tube's solid cells, scaled so that each tube's
    cells add up to pi D L), wall_T [K], wall_D [m] and wall_k (tube index); None without a
    heated tube."""
    face_area = [gg.h[1] * gg.h[2], gg.h[0] * gg.h[2], gg.h[0] * gg.h[1]]
    area = np.zeros(gg.cells)
    out = {"wall_T": np.zeros(gg.cells), "wall_D": np.ones(gg.cells), "wall_k": np.zeros(gg.cells, np.int32)}
    for k, t in enumerate(tubes):
        if t["T"] is None:
            continue
        inside = tube_cells(gg, t)
        borders = np.zeros(gg.cells)
        for a in range(3):
            for shift in (1, -1):
                borders += (shifted(gg, inside, a, shift) & ~inside) * face_area[a]
        axis = tube_axis(t)
        true_area = 2 * np.pi * t["r"] * gg.cells[axis] * gg.h[axis]
        mine = borders > 0
        area[mine] += borders[mine] * true_area / borders.sum()
        out["wall_T"][mine], out["wall_D"][mine], out["wall_k"][mine] = t["T"], 2 * t["r"], k
    if not area.any():
        return None
    out["wall_A"] = area
    return out


def convection_walls(gg: GasGrid, tubes: list[dict], meshes: list, cut: GasCut | None,
                     cut_tubes: bool = False) -> dict[str, np.ndarray] | None:
    """`tube_walls` (`tube_cut.tube_cut_walls` with `cut_tubes`), and the heated meshes' wetted surface
    (`tidem.gas.mesh_convection`) in the cells no tube borders: wall_k = len(tubes) + the mesh's index, wall_D
    its `convection_length`; a mesh's area in the cells a tube (or an earlier mesh) holds goes to its other cells,
    so that each mesh keeps its whole wetted area. None without a heated surface that the gas touches."""
    out = tube_cut_walls(gg, tubes, cut) if cut_tubes and tubes else tube_walls(gg, tubes)
    heated = [k for k, m in enumerate(meshes) if m.temperature is not None]
    if not heated or cut is None:
        return out
    if out is None:
        out = {"wall_T": np.zeros(gg.cells), "wall_D": np.ones(gg.cells), "wall_k": np.zeros(gg.cells, np.int32),
               "wall_A": np.zeros(gg.cells)}
    clip = spans_period(gg, meshes)
    first = np.cumsum([0] + [len(m.triangles) for m in meshes])
    for k in heated:
        m = meshes[k]
        area = wetted_area(gg, cut, m.vertices[m.triangles], clip[first[k]:first[k + 1]],
                           inward_sides(m.vertices, m.triangles))
        free = (area > 0.0) & (out["wall_A"] == 0.0) & ~cut.unreachable
        if not free.any():
            continue
        out["wall_A"][free] = area[free] * area.sum() / area[free].sum()
        out["wall_T"][free], out["wall_D"][free], out["wall_k"][free] = m.temperature, m.convection_length, len(tubes) + k
    return out if out["wall_A"].any() else None


def face_kinds(gg: GasGrid, solid: np.ndarray) -> list[np.ndarray]:
    """Per face component: CLOSED, INTERIOR, INLET (bottom) or OUTLET (top)."""
    kinds = []
    for c in range(3):
        shape = gg.face_shape(c)
        kind = np.full(shape, INTERIOR, np.int32)
        idx = np.indices(shape)
        below = [idx[a] - (1 if a == c else 0) for a in range(3)]
        above = [idx[a] for a in range(3)]
        for cell in (below, above):
            i = [np.mod(cell[a], gg.cells[a]) if gg.periodic[a] else np.clip(cell[a], 0, gg.cells[a] - 1)
                 for a in range(3)]
            kind[solid[i[0], i[1], i[2]] == 1] = CLOSED
        if not gg.periodic[c]:
            lo_face = kind[tuple(0 if a == c else slice(None) for a in range(3))]  # views
            hi_face = kind[tuple(gg.cells[c] if a == c else slice(None) for a in range(3))]
            if c == 2:
                lo_face[lo_face != CLOSED] = INLET
                hi_face[hi_face != CLOSED] = OUTLET
            else:
                lo_face[:] = CLOSED
                hi_face[:] = CLOSED
        kinds.append(kind)
    return kinds


def inlet_parts(gg: GasGrid, gas) -> np.ndarray:
    """The distributor part of each bottom face: 0 the background inflow, i + 1 nozzle i (a nozzle
    overrides the background and the nozzles listed before it); a face's superficial velocity is its
    part's (`tidem.gas.phase.GasPhase.inlet_at`)."""
    xc = gg.lo[0] + (np.arange(gg.cells[0]) + 0.5) * gg.h[0]
    yc = gg.lo[1] + (np.arange(gg.cells[1]) + 0.5) * gg.h[1]
    X, Y = np.meshgrid(xc, yc, indexing="ij")
    parts = np.zeros(X.shape, np.int64)
    for i, nz in enumerate(gas.nozzles):
        inside = (X >= nz.x[0]) & (X <= nz.x[1])
        if nz.y is not None:
            inside &= (Y >= nz.y[0]) & (Y <= nz.y[1])
        parts[inside] = i + 1
    return parts


def voidage_layers(model) -> int:
    """Horizontal layers per gas cell for the voidage a grain sees (`kernels/layered_voidage.py`): about one
    grain high, the Sauter mean of the scene's grains (with `gas.parcel_voidage = "parcel_layers"`, of its particles:
    one parcel high), at least 1; 1 with `gas.voidage = "cell"`."""
    if model.scene.gas.parcel_voidage == "parcel_layers":
        return layers_for(model.scene, sauter_diameter(2.0 * model.radius))
    return layers_for(model.scene, grain_sauter_diameter(model))


def grain_sauter_diameter(model) -> float:
    """Sauter mean diameter [m] of the scene's grains, sum d^3 / sum d^2 over every grain (a parcel
    of coarse-graining factor k holds k^3 grains of its diameter / k): the layers' height and the length of the
    packed-bed tube convection."""
    k = np.ones_like(model.radius) if model.coarse_grain is None else model.coarse_grain
    return sauter_diameter(2.0 * model.radius / k, k**3)


def parcel_rows_max(model) -> int:
    """The most rows of its grains a parcel stands in on the layers (`kernels/layered_voidage.py`, eq. (1)): 1 without
    parcels, layers or with `gas.parcel_voidage = "parcel_layers"`."""
    if model.coarse_grain is None or model.scene.gas.parcel_voidage == "parcel_layers" or voidage_layers(model) <= 1:
        return 1
    return parcel_rows(float(np.max(model.coarse_grain)))


def averaging_length(scene) -> float | None:
    """The length the voidage is averaged over [m] (`gas.averaging_length`): the key's length, None for the cells'
    own ("cells"), and by default 12 diameters of the largest grain (a parcel's grains, not the parcel)."""
    length = scene.gas.averaging_length
    if length == "cells":
        return None
    return length if length is not None else AVERAGING_GRAINS * largest_grain(scene)


def voidage_filters(gg, length: float | None, layers: int, drag: bool = False):
    """The averaging-length filters (`kernels/gas_smoothing.py`) of the cells' solid volume, with the layered
    voidage of the layers' (across only: a layer keeps its height of about one grain), and with `drag`
    (`gas.drag_averaging = "length"`) of the drag's exchange on the faces (`kernels/exchange_filter.py`: the cells'
    filter, the faces having the cells' spacing); None where none is needed."""
    cells = plan_filter(gg.h, gg.cells, length)
    exchange = cells if drag else None
    if layers <= 1:
        return cells, None, exchange
    return cells, plan_filter(gg.h, (gg.cells[0], gg.cells[1], gg.cells[2] * layers), length, axes=(0, 1)), exchange


def sauter_diameter(d: np.ndarray, count: np.ndarray | float = 1.0) -> float:
    """Sauter mean diameter [m] of `count` spheres of each diameter d: sum n d^3 / sum n d^2."""
    return float((count * d**3).sum() / (count * d**2).sum())


def layers_for(scene, d: float) -> int:
    """`voidage_layers` for particles of diameter d [m]."""
    if scene.gas.voidage == "cell":
        return 1
    return max(1, round(gas_grid(scene).h[2] / d))
