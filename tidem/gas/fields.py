"""The gas grid's Taichi fields, in one SNode tree (`GasPhase.release` frees it); the equations
that use them are in `kernels/gas_flow.py`, `kernels/gas_energy.py`, `kernels/gas_coupling.py` and
`kernels/species.py`.

Per cell [cells]: eps and eps_old (voidage now and at the last gas step), solid_vol (particle
volume deposited [m^3]; solid_tmp with an averaging-length filter), p (pressure [Pa]), rhs, diag and cg_r, cg_d, cg_q (the pressure
system and its CG vectors), solid (1 inside a tube or out of the gas's reach behind a mesh); with
tubes or meshes open (the open volume of the cell, `tidem.gas.open_volume`); with meshes part (the
share of the cell its gas part fills, `tidem.gas.apertures`); with heat T and T_new [K], H (particle
conductance [W/K]) and HT (H T of the particles [W]); with reactions Qs (heat handed back by
particles that reacted away [J]); with O2 transport Y and Y_new (mass fraction) and o2_sink
(O2 consumed since the last gas step [kg]); with gas-tube convection wall_A [m^2], wall_T [K],
wall_D [m], wall_k (tube index; a heated mesh's: the number of tubes + its index), and per wall
wall_rate [W] and wall_energy [J].
Per face, three components [face_shape(c)]: u (velocity [m/s]), us (predictor), A and C (the
correction's coefficients), gp (pressure gradient [Pa/m]), B and Bv (deposited drag
coefficients), kind (CLOSED, INTERIOR, INLET, OUTLET); with tubes or meshes open_face (the open
volume of the face's drag), with meshes aperture (the face's open share); with `gas.drag_averaging = "length"` uf
(the filtered velocity the particles read) and the scratch face_tmp, face_tmp2 (`kernels/exchange_filter.py`). Bottom faces: inlet (superficial
velocity [m/s]). Scalars: sums (CG dot products), heat_rate (max over particles of
H_p / (m_p c_p) [1/s]), with heat t_in (the inlet gas temperature [K]), with reactions bsum (enthalpy [J] and O2 [kg] that entered through
inlet and outlet; the most negative Y).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import taichi as ti

from tidem.kernels.field_copy import write_fields
from tidem.kernels.gas_grid import GasGrid


def allocate_gas_fields(gg: GasGrid, fp, solid: np.ndarray, kinds: list[np.ndarray], walls: dict | None,
                        n_walls: int, heat: bool, sources: bool, species: bool,
                        open_volumes: dict[str, np.ndarray] | None = None, layers: int = 1, band: int = 0,
                        cut=None, filters: tuple[bool, bool, bool] = (False, False, False)):
    """Place the fields a scene's gas needs and fill the fixed ones (solid cells, face kinds,
    tube walls) and the starting voidage 1; returns (namespace of fields, SNode tree). With `layers` > 1,
    solid_layer: the solid volume on cells cut into that many horizontal layers (`kernels/gas_coupling.py`). With
    `open_volumes` (tubes or meshes, `tidem.gas.open_volume.open_volumes`) the open volume over the volume of each
    cell (open), face (open_face) and layer (open_layer). With
    `band` = w > 0, band (cells x w + 1) and band_y (cells) for the direct pressure solve (`kernels/gas_band.py`).
    With `cut` (the meshes' `tidem.gas.mesh.GasCut`) part (each cell's gas part's share of its volume) and
    aperture (each face's open share, `tidem.gas.apertures`). With `filters` (cells, layers, the drag's exchange)
    filtered to `gas.averaging_length`, the scratch fields solid_tmp and layer_tmp (`kernels/gas_smoothing.py`) and
    per face uf, face_tmp and face_tmp2 (`kernels/exchange_filter.py`)."""
    G = SimpleNamespace()
    fb = ti.FieldsBuilder()
    cell_names = ["eps", "eps_old", "solid_vol", "p", "rhs", "diag", "cg_r", "cg_d", "cg_q"]
    if heat:
        cell_names += ["T", "T_new", "H", "HT"]
    if sources:
        cell_names += ["Qs"]
    if species:
        cell_names += ["Y", "Y_new", "o2_sink"]
    if open_volumes is not None:
        cell_names += ["open"]
    if filters[0]:
        cell_names += ["solid_tmp"]
    if cut is not None:
        cell_names += ["part"]
    for name in cell_names:
        setattr(G, name, ti.field(fp))
        fb.dense(ti.ijk, gg.cells).place(getattr(G, name))
    if layers > 1:
        G.solid_layer = ti.field(fp)
        fb.dense(ti.ijk, (gg.cells[0], gg.cells[1], gg.cells[2] * layers)).place(G.solid_layer)
        if filters[1]:
            G.layer_tmp = ti.field(fp)
            fb.dense(ti.ijk, (gg.cells[0], gg.cells[1], gg.cells[2] * layers)).place(G.layer_tmp)
        if open_volumes is not None:
            G.open_layer = ti.field(fp)
            fb.dense(ti.ijk, open_volumes["layers"].shape).place(G.open_layer)
    G.solid = ti.field(ti.i32)
    fb.dense(ti.ijk, gg.cells).place(G.solid)
    if band:
        cells = gg.cells[0] * gg.cells[1] * gg.cells[2]
        G.band, G.band_y = ti.field(ti.f64), ti.field(ti.f64)
        fb.dense(ti.ij, (cells, band + 1)).place(G.band)
        fb.dense(ti.i, cells).place(G.band_y)
    for name, dtype in (("u", fp), ("us", fp), ("A", fp), ("C", fp), ("gp", fp), ("B", fp), ("Bv", fp),
                        ("kind", ti.i32)):
        comps = [ti.field(dtype) for _ in range(3)]
        for c in range(3):
            fb.dense(ti.ijk, gg.face_shape(c)).place(comps[c])
        setattr(G, name, comps)
    if filters[2]:
        for name in ("uf", "face_tmp", "face_tmp2"):
            comps = [ti.field(fp) for _ in range(3)]
            for c in range(3):
                fb.dense(ti.ijk, gg.face_shape(c)).place(comps[c])
            setattr(G, name, comps)
    if open_volumes is not None:
        G.open_face = [ti.field(fp) for _ in range(3)]
        for c in range(3):
            fb.dense(ti.ijk, gg.face_shape(c)).place(G.open_face[c])
    if cut is not None:
        G.aperture = [ti.field(fp) for _ in range(3)]
        for c in range(3):
            fb.dense(ti.ijk, gg.face_shape(c)).place(G.aperture[c])
    G.inlet = ti.field(fp)
    fb.dense(ti.ij, gg.cells[:2]).place(G.inlet)
    G.sums = ti.field(fp)
    fb.dense(ti.i, 4).place(G.sums)
    G.heat_rate = ti.field(fp)  # set by `couple`
    fb.dense(ti.i, 1).place(G.heat_rate)
    if heat:
        G.t_in = ti.field(fp)  # the inlet gas temperature [K], set by the host before each gas step
        fb.dense(ti.i, 1).place(G.t_in)
    if walls is not None:
        for name in ("wall_A", "wall_T", "wall_D"):
            setattr(G, name, ti.field(fp))
            fb.dense(ti.ijk, gg.cells).place(getattr(G, name))
        G.wall_k = ti.field(ti.i32)
        fb.dense(ti.ijk, gg.cells).place(G.wall_k)
        G.wall_rate = ti.field(fp)
        G.wall_energy = ti.field(ti.f64)
        fb.dense(ti.i, n_walls).place(G.wall_rate, G.wall_energy)
    if sources:
        G.bsum = ti.field(ti.f64)
        fb.dense(ti.i, 3).place(G.bsum)
    tree = fb.finalize()
    start = {"solid": (G.solid, solid), "eps": (G.eps, 1.0), "eps_old": (G.eps_old, 1.0),
             **{f"kind{c}": (G.kind[c], kinds[c]) for c in range(3)}}
    if open_volumes is not None:
        start["open"] = (G.open, open_volumes["cells"])
        start.update({f"open_face{c}": (G.open_face[c], open_volumes[f"faces{c}"]) for c in range(3)})
        if layers > 1:
            start["open_layer"] = (G.open_layer, open_volumes["layers"])
    if cut is not None:
        start["part"] = (G.part, cut.open_fraction)
        start.update({f"aperture{c}": (G.aperture[c], cut.aperture[c]) for c in range(3)})
    if walls is not None:
        start.update({name: (getattr(G, name), values) for name, values in walls.items()})
    write_fields(start)
    return G, tree
