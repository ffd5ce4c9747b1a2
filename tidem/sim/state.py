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
                   cell order as the bed flows, `tidem.particles.storage_order`)
Neighbour list, shape [capacity, K], stored slot-major (`_Placer.rows`), each pair in its owner's
row only (`kernels/broadphase.py`): nbr (partner), ft (tangential spring [m]), mr (rolling spring
[N m]), dmax (maximum overlap [m]); nbr_new and src are scratch rows of the rebuild, nbr_count
[capacity] its row lengths, nbr_touch [capacity] the number of partners that touched at the build
(listed first), then the others in QUIET_GROUPS groups by their gap then: nbr_end [capacity,
QUIET_GROUPS - 1] where each group but the last ends, nbr_gap [capacity, QUIET_GROUPS] its smallest
gap [m] (float32; 1e30: an empty group; <= 0: none skipped), flip_ft, flip_mr, flip_dmax
[capacity] its buffer of the history of pairs that changed owner (flips[None] entries). With numerics.precision = 'mixed' the float rows (ft, mr, dmax, flip_*) are
float32, every other field float64.
Slabs (`kernels/geometry.py`, `slab_layout`): slab [capacity] (a particle's slab at the last
build), slab_list (the particles of slab s, in index order, at slab_start[s] ..
slab_start[s + 1] - 1; not built where the contact passes sweep no slabs, on a GPU), slab_fill
(scratch of the build), slab_next (the contact passes' three slab counters). cell_block: the cell
prefix sum's block offsets; sort_tail: a GPU storage sort's count (`kernels/broadphase.py`).
worst, worst_at: the health check's largest overlap ratio and its particle, and the first
non-finite position (`kernels/diagnostics.py`).
With heat: T [K], q (heat rate into the particle [W]), inv_heat_cap (1/(m c) [K/J]); per
surface (planes then tubes) surf_T (fixed temperature, -1 = adiabatic), surf_rate (heat flow
into the bed [W]) and surf_energy (its time integral [J]), surf_rate_block [BLOCKS, surfaces] (each
block of slabs' share of surf_rate on the CPU); with angle bins around heated tubes tube_bin_rate /
tube_bin_energy (the same by angle bin), tube_bin_block (each block's share, [BLOCKS, tube x bins + bin]),
tube_route_rate / tube_route_energy / tube_route_block (the shares of each tube's flow through the solid
contact spots and through the gas lens of particles that do not touch it: [tube, route], route 0 and 1)
and tube_side (the horizontal unit vector across each tube); with heated-foil tubes tube_foil
(heating per area [W/m^2], foil heat capacity per area [J/(m^2 K)], bin area [m^2], G / ds^2
[W/(m^2 K)]; zeros for other tubes), tube_bin_T (foil temperature by angle bin [K]), tube_bin_dT (its change in the step)
and tube_bin_Tsum (its time integral since the profile start [K s]); with heated-foil walls
plane_foil (heating per area, foil heat capacity per area, wall area) and plane_foil_T [K].
With gas (frozen between gas steps, see kernels/gas_coupling.py): gK (drag coefficient
[kg/s]), geps (voidage), gu (gas velocity [m/s]) and ggp (pressure gradient [Pa/m]) at the
particle; with heat also gH (gas-particle conductance [W/K]) and gT (gas temperature [K]).
With species (O2 on the gas grid): gY (O2 mass fraction of the gas at the particle; a burning
particle reads its own every step, from the fluid cells alone, `kernels/reactions.py`).
With gas and coarse-grained groups: cg (k: the parcel's diameter over its grains').
With reactions: rx (index of the particle's reaction, -1 = inert), rsum (float64 totals of
`kernels/reactions.py`: reacted mass [kg], O2 used [kg], heat released [J], latent heat [J],
sensible heat leaving with reacted mass [J], heat handed back to the gas [J], particles gone,
particles escaped, escaped mass [kg]) and on the CPU rbook (each particle's share of the totals that its
reactions book in a step, zero between steps); with sublimation rt0 (time first seen [s]) and rt1
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

import taichi as ti

from tidem.heat.reactions import KIND_IDS, N_SUMS
from tidem.kernels import contact_laws as cl
from tidem.kernels.averaging import channels
from tidem.kernels.broadphase import QUIET_GROUPS, scan_blocks
from tidem.kernels.contact import BLOCKS
from tidem.kernels.geometry import slab_layout
from tidem.kernels.ordered import in_order
from tidem.kernels.reactions import booked_slots
from tidem.sim.model import Model
from tidem.sim.state_fill import fill
from tidem.walls.mesh_bins import MESH_SLOTS


class State(SimpleNamespace):
    """Namespace of Taichi fields (attribute names as in the module docstring)."""

    def release(self) -> None:
        if getattr(self, "_tree", None) is not None:
            self._tree.destroy()
            self._tree = None


def history_dtype(feat):
    """The float type of the Verlet rows' contact history (ft, mr, dmax):
    float32 with numerics.precision = 'mixed' (and 'float32'), else float64."""
    return ti.f32 if feat.history_bytes == 4 else ti.f64


class _Placer:
    """Places fields of one SNode tree on a State and keeps the names of those indexed by
    particle first (`S.particle_fields`, permuted by a storage sort)."""

    def __init__(self, S: State, fp):
        self.S, self.fp, self.fb = S, fp, ti.FieldsBuilder()
        S.particle_fields = []

    def make(self, name, dtype=None, n=None):
        dtype = self.fp if dtype is None else dtype
        fld = ti.field(dtype) if n is None else ti.Vector.field(n, dtype)
        setattr(self.S, name, fld)
        return fld

    def place(self, shape, name, dtype=None, n=None):
        self.fb.dense(ti.ij if len(shape) == 2 else ti.i, shape).place(self.make(name, dtype, n))

    def per_particle(self, shape, name, dtype=None, n=None):
        self.place(shape, name, dtype, n)
        self.S.particle_fields.append(name)

    def rows(self, shape, name, dtype=None, n=None):
        """A Verlet-row field [capacity, K], stored slot by slot: slot k of consecutive particles sits
        side by side, so that the force loops, which walk the particles in order and read each row's
        first nbr_n slots, stream only the slots in use (the code still indexes it [i, k])."""
        self.fb.dense(ti.j, shape[1]).dense(ti.i, shape[0]).place(self.make(name, dtype, n))
        self.S.particle_fields.append(name)


def _place_contact_fields(p: _Placer, model: Model) -> None:
    """Particles, neighbour list and wall slots with their contact history, the broad phase's
    cells, the material-pair and material-surface tables, the tubes (for the averaging)."""
    N, K, W = model.capacity, model.max_neighbors, model.wall_slots
    feat = model.features
    # What the pair loop reads of a partner sits together in memory (array of structs); the radius and mass,
    # and the material, only where particles differ in them (else the loop takes constants and they are
    # fields of their own: Model.uniform_particles, one_material).
    hot = [p.make(k, n=3) for k in ("x", "v", "w")]
    apart = []
    (apart if model.uniform_particles() else hot).extend([p.make("radius"), p.make("mass")])
    (apart if model.one_material() else hot).append(p.make("mat", ti.i32))
    p.fb.dense(ti.i, N).place(*hot)
    for fld in apart:
        p.fb.dense(ti.i, N).place(fld)
    p.S.particle_fields += ["x", "v", "w", "radius", "mass", "mat"]
    p.per_particle((N,), "ident", ti.i32)
    if feat.growth:
        p.per_particle((N,), "r_build")
    for name in ("f", "tq", "x_build"):
        p.per_particle((N,), name, n=3)
    for name in ("inv_mass", "inv_inertia", "ovl"):
        p.per_particle((N,), name)
    for name in ("active", "nbr_n", "pcell", "ncontact", "sorted_idx", "wmask", "near"):
        p.per_particle((N,), name, ti.i32)
    for name in ("slab", "slab_list", "nbr_count"):  # rewritten by each neighbour build
        p.place((N,), name, ti.i32)
    # side by side: the contact passes read a row's quiet groups together (kernels/pair_contact.py)
    row = p.fb.dense(ti.i, N)
    row.place(p.make("nbr_touch", ti.i32))
    row.dense(ti.j, QUIET_GROUPS - 1).place(p.make("nbr_end", ti.i32))
    row.dense(ti.j, QUIET_GROUPS).place(p.make("nbr_gap", ti.f32))
    n_slabs = slab_layout(model.grid)[1]
    p.place((n_slabs + 1,), "slab_start", ti.i32)
    p.place((n_slabs,), "slab_fill", ti.i32)
    if feat.contact_time:
        p.per_particle((N,), "touch_start")
        p.per_particle((N,), "touch_end")
    for name in ("nbr", "nbr_new", "src"):
        p.rows((N, K), name, ti.i32)
    hist = history_dtype(feat)
    p.rows((N, K), "ft", hist, n=3)
    p.place((N,), "flip_ft", hist, n=3)
    p.per_particle((N, W), "wid", ti.i32)
    p.per_particle((N, W), "wft", n=3)
    if feat.rolling:
        p.rows((N, K), "mr", hist, n=3)
        p.place((N,), "flip_mr", hist, n=3)
        p.per_particle((N, W), "wmr", n=3)
    if feat.hysteretic:
        p.rows((N, K), "dmax", hist)
        p.place((N,), "flip_dmax", hist)
        p.per_particle((N, W), "wdmax")
    nc = model.grid.n_cells
    for name in ("cell_count", "cell_start", "cell_fill"):
        p.place((nc,), name, ti.i32)
    p.place((scan_blocks(nc),), "cell_block", ti.i32)  # the prefix sum's block offsets (kernels/broadphase.py)
    P = model.pair_params.shape[0]
    p.place((P, P), "pp", n=cl.N_PARAMS)
    p.place((P, model.surface_params.shape[1]), "ps", n=cl.N_PARAMS)
    NT = max(len(model.tubes), 1)  # the contact kernel takes planes and tubes as constants; averaging reads tubes
    p.place((NT,), "tube_c", n=3)
    p.place((NT,), "tube_mask", n=3)
    p.place((NT,), "tube_r")
    if feat.scheduled_plate:  # an outlet plate on a speed schedule: its shift from p0 and velocity, host-set
        p.place((len(model.planes),), "plane_shift", n=3)
        p.place((len(model.planes),), "plane_u", n=3)
    p.S.max_disp = ti.field(p.fp)
    p.S.flips = ti.field(ti.i32)
    p.S.sort_tail = ti.field(ti.i32)  # a GPU storage sort's count of the particles in order so far
    p.S.worst = ti.field(p.fp)  # the health check's largest overlap ratio (kernels/diagnostics.py)
    p.fb.place(p.S.max_disp, p.S.flips, p.S.sort_tail, p.S.worst)
    p.place((3,), "slab_next", ti.i32)  # the contact passes' slab counters (kernels/contact.py)
    if feat.n_meshes:
        _place_mesh_fields(p, model)


def _place_mesh_fields(p: _Placer, model: Model) -> None:
    """Mesh triangles, their bins, each particle's candidate triangles and mesh contact slots
    (`kernels/mesh_contact.py`)."""
    N, tab = model.capacity, model.mesh_table
    T = len(tab.mesh_id)
    p.place((T, 3), "tri_v", n=3)
    p.place((T,), "tri_mesh", ti.i32)
    p.place((T,), "tri_patch", ti.i32)
    if model.features.moving_meshes:
        p.place((T, 3), "tri_rest", n=3)
        p.place((T,), "tri_shift", n=3)
    p.place((model.grid.n_cells + 1,), "mbin_start", ti.i32)
    p.place((tab.bin_capacity,), "mbin_tri", ti.i32)
    p.place((len(model.meshes), 4), "mesh_motion", n=3)
    if model.features.scheduled_motion:
        p.place((len(model.meshes),), "mesh_pose", n=4)
    p.per_particle((N,), "mc_n", ti.i32)
    p.per_particle((N,), "mc_flat", ti.i32)
    p.per_particle((N, tab.candidates), "mc_tri", ti.i32)
    p.per_particle((N, MESH_SLOTS), "mh_id", ti.i32)
    for name in ("mh_n", "mh_ft"):
        p.per_particle((N, MESH_SLOTS), name, n=3)
    if model.features.rolling:
        p.per_particle((N, MESH_SLOTS), "mh_mr", n=3)
    if model.features.hysteretic:
        p.per_particle((N, MESH_SLOTS), "mh_dmax")


def _place_heat_fields(p: _Placer, model: Model) -> None:
    """Particle temperatures and heat rates, heated surfaces, angle bins and heated foils."""
    N = model.capacity
    feat = model.features
    for name in ("T", "q", "inv_heat_cap"):
        p.per_particle((N,), name)
    NS = max(len(model.planes) + len(model.tubes) + len(model.meshes), 1)
    p.place((NS,), "surf_T")
    p.place((NS,), "surf_rate")
    p.place((NS,), "surf_energy", ti.f64)
    p.place((BLOCKS, NS), "surf_rate_block")  # each block of slabs' share of surf_rate (kernels/surface_contact.py)
    p.S.conduct = ti.field(ti.i32)  # this step's conduction: heat.conduction_interval steps of it, or 0 (kernels/contact.py)
    p.fb.place(p.S.conduct)
    n_tubes, bins = len(model.tubes), model.angle_bins
    if bins:
        p.place((n_tubes, bins), "tube_bin_rate")
        p.place((BLOCKS, n_tubes * bins), "tube_bin_block")  # [block, tube * bins + bin]
        p.place((n_tubes, bins), "tube_bin_energy", ti.f64)
        p.place((n_tubes, 2), "tube_route_rate")  # through the contact spots, through the gas lens
        p.place((BLOCKS, n_tubes * 2), "tube_route_block")  # [block, tube * 2 + route]
        p.place((n_tubes, 2), "tube_route_energy", ti.f64)
        p.place((n_tubes,), "tube_side", n=3)
    if feat.wall_foil:
        p.place((len(model.planes),), "plane_foil", n=3)
        p.place((len(model.planes),), "plane_foil_T")
    if feat.foil:
        p.place((n_tubes,), "tube_foil", n=4)
        p.place((n_tubes, bins), "tube_bin_T")
        p.place((n_tubes, bins), "tube_bin_dT")
        p.place((n_tubes, bins), "tube_bin_Tsum", ti.f64)


def _place_gas_fields(p: _Placer, model: Model) -> None:
    """The gas state at each particle (the gas grid's own fields: `tidem.gas.fields`)."""
    N = model.capacity
    for name in ("gK", "geps"):
        p.per_particle((N,), name)
    for name in ("gu", "ggp"):
        p.per_particle((N,), name, n=3)
    if model.features.heat:
        for name in ("gH", "gT"):
            p.per_particle((N,), name)
    if model.features.species:
        p.per_particle((N,), "gY")
    if model.features.coarse_grain:
        p.per_particle((N,), "cg")


def _place_reaction_fields(p: _Placer, model: Model) -> None:
    N = model.capacity
    p.per_particle((N,), "rx", ti.i32)
    p.place((N_SUMS,), "rsum", ti.f64)
    if in_order():  # each particle's share of the totals in a step, added up in particle order (kernels/reactions.py)
        p.place((N,), "rbook", ti.f64, n=len(booked_slots(KIND_IDS[name] for name in model.features.reactions)))
    if model.features.gas:  # what each particle gives its gas cells in a step (kernels/reactions.py)
        p.place((N,), "gas_book", n=2)
    if "sublimation" in model.features.reactions:
        p.per_particle((N,), "rt0")
        p.per_particle((N,), "rt1")


def _place_averaging_fields(p: _Placer, model: Model) -> None:
    a, C = model.averaging, channels(model.features.heat)
    p.fb.dense(ti.ijk, (*a.cells, C)).place(p.make("avg_cells", ti.f64))
    if model.tubes:
        p.fb.dense(ti.ijk, (len(model.tubes) * a.rings, a.sectors, C)).place(p.make("avg_rings", ti.f64))
    p.S.avg_samples = ti.field(ti.i32)
    p.fb.place(p.S.avg_samples)


def allocate(model: Model) -> State:
    """Allocate every field the model's features need and fill it from the Model."""
    fp = ti.f32 if model.features.precision == "float32" else ti.f64
    feat = model.features
    S = State()
    p = _Placer(S, fp)
    _place_contact_fields(p, model)
    if feat.heat:
        _place_heat_fields(p, model)
    if feat.gas:
        _place_gas_fields(p, model)
    if feat.reactions:
        _place_reaction_fields(p, model)
    if feat.averaging:
        _place_averaging_fields(p, model)
    p.place((4,), "overflow", ti.i32)
    if feat.sink or feat.recycle:
        p.place((2,), "sink_sum", ti.f64)  # mass [kg] and number of the particles through the outlet (kernels/outlet.py)
    p.place((5,), "sums")
    p.place((2,), "worst_at", ti.i32)  # first non-finite position, largest overlap (storage indices)
    S._tree = p.fb.finalize()
    fill(S, model)
    return S
