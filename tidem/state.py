"""The State: Taichi fields of a run, allocated from the Model and sized from the scene.

A history array exists only when a model needs it (rolling springs only with rolling
friction, maximum overlap only for the hysteretic law). Fields live in one SNode tree that
`release()` frees, so a process can run many scenes (the test suite does).

Per-particle fields, shape [capacity]:
  x, v, w          position [m], velocity [m/s], angular velocity [rad/s]
  f, tq            force [N], torque [N m] of the last force evaluation
  x_build          position at the last neighbour build [m]
  r_build          radius at the last neighbour build [m] (only with growing particles)
  radius, mass, inv_mass [1/kg], inv_inertia [1/(kg m^2)], mat (material index), active
  ovl              largest overlap / smaller radius over the particle's contacts
  ncontact         number of contacts
  ident            the particle's index in the Model's arrays (storage is re-sorted into
                   cell order as the bed flows, `tidem.storage_order`)
Neighbour list, shape [capacity, K]: nbr (partner), ft (tangential spring [m]), mr (rolling
spring [N m]), dmax (maximum overlap [m]); nbr_new and src are scratch rows of the rebuild.
With heat: T [K], q (heat rate into the particle [W]), inv_heat_cap (1/(m c) [K/J]), qpair
[capacity, K] (heat rate into the particle from that neighbour, written by the lower-index
particle of the pair, read by the higher one; see kernels/contact.py); per
surface (planes then tubes) surf_T (fixed temperature, -1 = adiabatic), surf_rate (heat flow
into the bed [W]) and surf_energy (its time integral [J]); with angle bins around heated tubes
tube_bin_rate / tube_bin_energy (the same by angle bin) and tube_side (the horizontal unit
vector across each tube); with heated-foil tubes tube_foil (heating per area [W/m^2], foil
heat capacity per area [J/(m^2 K)], bin area [m^2], G / ds^2 [W/(m^2 K)]; zeros for other
tubes), tube_bin_T (foil temperature by angle bin [K]), tube_bin_dT (its change in the step)
and tube_bin_Tsum (its time integral since the profile start [K s]); with heated-foil walls
plane_foil (heating per area, foil heat capacity per area, wall area) and plane_foil_T [K].
With gas (frozen between gas steps, see kernels/gas_coupling.py): gK (drag coefficient
[kg/s]), geps (voidage), gu (gas velocity [m/s]) and ggp (pressure gradient [Pa/m]) at the
particle; with heat also gH (gas-particle conductance [W/K]) and gT (gas temperature [K]).
With species (O2 on the gas grid): gY (O2 mass fraction of the gas at the particle).
With reactions: rx (index of the particle's reaction, -1 = inert), rsum (float64 totals of
`kernels/reactions.py`: reacted mass [kg], O2 used [kg], heat released [J], latent heat [J],
sensible heat leaving with reacted mass [J], heat handed back to the gas [J], particles gone,
particles escaped, escaped mass [kg]); with sublimation rt0 (time first seen [s]) and rt1
(time sublimated away [s], minus the time it left through the exit, 0 while present).
Wall and tube history, shape [capacity, W]: wid (surface index or -1), wft, wmr, wdmax;
wmask [capacity]: bit s set while surface s holds one of the particle's slots; near
[capacity]: bit s set when static surface s was within reach at the last neighbour build.
With [averaging] (`kernels/averaging.py`, source 3 eq. 34-36): float64 sums per control volume
and channel, avg_cells [cells x, cells z, channels] and, with tubes, avg_rings
[tubes x rings, sectors, channels]; avg_samples (number of samples taken).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import taichi as ti

from tidem.kernels import contact_laws as cl
from tidem.model import Model
from tidem.surfaces import angle_bin_area


class State(SimpleNamespace):
    """Namespace of Taichi fields (attribute names as in the module docstring)."""

    def release(self) -> None:
        if getattr(self, "_tree", None) is not None:
            self._tree.destroy()
            self._tree = None


def foil_vector(tube: dict, model: Model) -> list[float]:
    """tube_foil's row for a tube (see the module docstring); zeros unless it has a heat flux."""
    if tube["flux"] is None:
        return [0.0, 1.0, 1.0, 0.0]
    ds = 2 * np.pi * tube["r"] / model.angle_bins
    return [tube["flux"], tube["foil_C"], angle_bin_area(model, tube), tube["foil_G"] / ds**2]


def wall_foil_vector(plane: dict, model: Model) -> list[float]:
    """plane_foil's row: heating per area [W/m^2], foil heat capacity per area [J/(m^2 K)] and
    the wall's area, the domain's cross-section normal to it [m^2]; zeros without a heat flux."""
    if plane.get("flux") is None:
        return [0.0, 1.0, 1.0]
    axis = int(np.argmax(np.abs(plane["n"])))
    area = float(np.prod([model.grid.length[a] for a in range(3) if a != axis]))
    return [plane["flux"], plane["foil_C"], area]


def allocate(model: Model) -> State:
    """Allocate and fill every field the model's features need."""
    fp = ti.f64 if model.features.precision == "float64" else ti.f32
    N, K, W = model.capacity, model.max_neighbors, model.wall_slots
    feat = model.features
    fb = ti.FieldsBuilder()
    S = State()

    def make(name, dtype=fp, n=None):
        fld = ti.field(dtype) if n is None else ti.Vector.field(n, dtype)
        setattr(S, name, fld)
        return fld

    def place(shape, name, dtype=fp, n=None):
        fb.dense(ti.ij if len(shape) == 2 else ti.i, shape).place(make(name, dtype, n))

    S.particle_fields = []  # names of the fields indexed by particle first (permuted by a storage sort)

    def per_particle(shape, name, dtype=fp, n=None):
        place(shape, name, dtype, n)
        S.particle_fields.append(name)

    # What the pair loop reads of a partner sits together in memory (array of structs).
    hot = [make(k, n=3) for k in ("x", "v", "w")] + [make("radius"), make("mass"), make("mat", ti.i32)]
    fb.dense(ti.i, N).place(*hot)
    S.particle_fields += ["x", "v", "w", "radius", "mass", "mat"]
    per_particle((N,), "ident", ti.i32)
    if feat.growth:
        per_particle((N,), "r_build")
    for name in ("f", "tq", "x_build"):
        per_particle((N,), name, n=3)
    for name in ("inv_mass", "inv_inertia", "ovl"):
        per_particle((N,), name)
    for name in ("active", "nbr_n", "pcell", "ncontact", "sorted_idx", "wmask", "near"):
        per_particle((N,), name, ti.i32)
    if feat.contact_time:
        per_particle((N,), "touch_start")
        per_particle((N,), "touch_end")
    for name in ("nbr", "nbr_new", "src"):
        per_particle((N, K), name, ti.i32)
    per_particle((N, K), "ft", n=3)
    per_particle((N, W), "wid", ti.i32)
    per_particle((N, W), "wft", n=3)
    if feat.rolling:
        per_particle((N, K), "mr", n=3)
        per_particle((N, W), "wmr", n=3)
    if feat.hysteretic:
        per_particle((N, K), "dmax")
        per_particle((N, W), "wdmax")
    nc = model.grid.n_cells
    for name in ("cell_count", "cell_start", "cell_fill"):
        place((nc,), name, ti.i32)
    P = model.pair_params.shape[0]
    place((P, P), "pp", n=cl.N_PARAMS)
    place((P, model.surface_params.shape[1]), "ps", n=cl.N_PARAMS)
    NP = max(len(model.planes), 1)
    NT = max(len(model.tubes), 1)
    for name in ("plane_p0", "plane_n", "plane_vel"):
        place((NP,), name, n=3)
    place((NP,), "plane_t", n=2)
    place((NT,), "tube_c", n=3)
    place((NT,), "tube_mask", n=3)
    place((NT,), "tube_r")
    S.max_disp = ti.field(fp)
    fb.place(S.max_disp)
    if feat.heat:
        for name in ("T", "q", "inv_heat_cap"):
            per_particle((N,), name)
        if feat.contacts:
            per_particle((N, K), "qpair")
        NS = max(len(model.planes) + len(model.tubes), 1)
        place((NS,), "surf_T")
        place((NS,), "surf_rate")
        place((NS,), "surf_energy", ti.f64)
        if model.angle_bins:
            place((len(model.tubes), model.angle_bins), "tube_bin_rate")
            place((len(model.tubes), model.angle_bins), "tube_bin_energy", ti.f64)
            place((len(model.tubes),), "tube_side", n=3)
        if feat.wall_foil:
            place((len(model.planes),), "plane_foil", n=3)
            place((len(model.planes),), "plane_foil_T")
        if feat.foil:
            place((len(model.tubes),), "tube_foil", n=4)
            place((len(model.tubes), model.angle_bins), "tube_bin_T")
            place((len(model.tubes), model.angle_bins), "tube_bin_dT")
            place((len(model.tubes), model.angle_bins), "tube_bin_Tsum", ti.f64)
    if feat.gas:
        for name in ("gK", "geps"):
            per_particle((N,), name)
        for name in ("gu", "ggp"):
            per_particle((N,), name, n=3)
        if feat.heat:
            for name in ("gH", "gT"):
                per_particle((N,), name)
        if feat.species:
            per_particle((N,), "gY")
    if feat.reactions:
        from tidem.reactions import N_SUMS

        per_particle((N,), "rx", ti.i32)
        place((N_SUMS,), "rsum", ti.f64)
        if "sublimation" in feat.reactions:
            per_particle((N,), "rt0")
            per_particle((N,), "rt1")
    if feat.averaging:
        from tidem.kernels.averaging import channels

        a, C = model.averaging, channels(feat.heat)
        fb.dense(ti.ijk, (*a.cells, C)).place(make("avg_cells", ti.f64))
        if model.tubes:
            fb.dense(ti.ijk, (len(model.tubes) * a.rings, a.sectors, C)).place(make("avg_rings", ti.f64))
        S.avg_samples = ti.field(ti.i32)
        fb.place(S.avg_samples)
    place((2,), "overflow", ti.i32)
    place((5,), "sums")
    S._tree = fb.finalize()

    radius = model.radius
    inertia = 0.4 * model.mass * radius**2
    movable = ~model.fixed  # fixed particles: zero inverse mass and inertia, zero velocity
    S.x.from_numpy(model.x0)
    S.x_build.from_numpy(model.x0)
    S.v.from_numpy(model.v0 * movable[:, None])
    S.radius.from_numpy(radius)
    if feat.growth:
        S.r_build.from_numpy(radius)
    S.mass.from_numpy(model.mass)
    S.inv_mass.from_numpy(movable / model.mass)
    S.inv_inertia.from_numpy(movable / inertia)
    if feat.heat:
        S.T.from_numpy(model.temperature0)
        S.inv_heat_cap.from_numpy(1.0 / model.heat_capacity)
        T0 = model.scene.heat.initial_temperature  # a foil's own temperature is in tube_bin_T
        temps = [T0 if s.get("flux") is not None else s["T"] for s in model.planes + model.tubes]
        S.surf_T.from_numpy(np.array([-1.0 if T is None else T for T in temps] or [-1.0]))
        if feat.foil:
            S.tube_foil.from_numpy(np.array([foil_vector(t, model) for t in model.tubes]))
            S.tube_bin_T.fill(T0)
        if feat.wall_foil:
            S.plane_foil.from_numpy(np.array([wall_foil_vector(p, model) for p in model.planes]))
            S.plane_foil_T.fill(T0)
        if model.angle_bins:
            S.tube_side.from_numpy(np.array([[0.0, 1.0, 0.0] if t["mask"][1] else [1.0, 0.0, 0.0]
                                             for t in model.tubes]))
    S.mat.from_numpy(model.material)
    if feat.reactions:
        S.rx.from_numpy(model.reaction_index)
        if "sublimation" in feat.reactions:
            S.rt0.fill(-1.0)
            S.rt1.fill(0.0)
    S.active.from_numpy(model.active0.astype(np.int32))
    S.ident.from_numpy(np.arange(N, dtype=np.int32))
    S.wid.fill(-1)
    if feat.contact_time:
        S.touch_start.fill(-1.0)
        S.touch_end.fill(-1.0)
    S.pp.from_numpy(model.pair_params)
    S.ps.from_numpy(model.surface_params)
    if model.planes:
        S.plane_p0.from_numpy(np.array([p["p0"] for p in model.planes], float))
        S.plane_n.from_numpy(np.array([p["n"] for p in model.planes], float))
        S.plane_vel.from_numpy(np.array([p["vel"] for p in model.planes], float))
        S.plane_t.from_numpy(np.array([p["t"] for p in model.planes], float))
    if model.tubes:
        S.tube_c.from_numpy(np.array([t["c"] for t in model.tubes], float))
        S.tube_mask.from_numpy(np.array([t["mask"] for t in model.tubes], float))
        S.tube_r.from_numpy(np.array([t["r"] for t in model.tubes], float))
    return S
