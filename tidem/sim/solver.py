"""The Solver: builds the kernels a scene needs and advances the state one step at a time.

`step()` is a short list of kernel launches and makes no physics decisions: kick-drift,
neighbour rebuild when a particle moved more than half the skin (or particles appeared),
every `numerics.sort_interval` rebuilds first a re-sort of particle storage into cell order
(`tidem.particles.storage_order`), a gas step every `gas.coupling_interval` steps (scenes with gas),
forces (contacts, with the conduction every `heat.conduction_interval` steps, then drag and
pressure-gradient force), reactions (with a rebuild when a
particle burnt out or left), kick. Unless a reaction can remove particles (char combustion,
sublimation), the contact passes and the kick (which adds the gas forces and lets each particle
react first) are one kernel launch (`forces_and_kick`), and `advance(k)`, which the run loop calls between
outputs, has each kick go on with the next step's kick-drift: a step is then one kernel launch
(plus the gas step and the neighbour build when due), bit for bit the same as k calls of
`step()` and as separate kernels (`split_passes`, which `tidem bench --profile` sets).
The contact counts and overlaps (`ovl`, `ncontact`) are filled only in the last step of
`advance(k)` and at health checks, where the host reads them.
Each phase's wall time is booked in `timer` (`tidem.runtime.phases`, run.json's profile). Health
checks (NaN, runaway overlap, capacity overflow) run every `numerics.check_interval` steps
and raise `RunError` naming the particle and the fix.
"""

from __future__ import annotations

import numpy as np
import taichi as ti

from tidem.gas.phase import GasError, GasPhase
from tidem.kernels.averaging import make_averaging_kernel
from tidem.kernels.broadphase import make_neighbor_builder
from tidem.kernels.contact import make_force_kernel
from tidem.kernels.contact_laws import LINEAR
from tidem.kernels.diagnostics import make_energy_kernel, make_health_kernel
from tidem.kernels.field_copy import FieldCopier
from tidem.kernels.integrate import make_integrators
from tidem.kernels.mesh_contact import make_mesh_mover
from tidem.kernels.ordered import in_order
from tidem.kernels.outlet import make_recycle_kernel, make_sink_kernel
from tidem.kernels.reactions import make_reaction_kernel
from tidem.kernels.storage_sort import make_storage_permuter
from tidem.particles.pour import Pourer
from tidem.particles.storage_order import SCRATCH, sort_storage, sorts_storage
from tidem.results.particle_stats import ParticleStats
from tidem.runtime.phases import PhaseTimer, clock
from tidem.runtime.startup import hot
from tidem.sim.conditions import Conditions
from tidem.sim.kernel_settings import mesh_settings, quiet_bounds, quiet_margin, static_surfaces
from tidem.sim.model import Model
from tidem.sim.solver_reads import TallyReads
from tidem.sim.state import State, allocate
from tidem.sim.state_fill import load_bins
from tidem.walls.mesh_bins import MESH_SLOTS, bin_triangles

# The small fields the host reads at health checks and time-series samples, copied all at once (`kernels/field_copy.py`:
# one launch in the calling thread, against a parallel launch per field for to_numpy())
TALLIES = ("overflow", "sums", "worst_at", "worst", "surf_rate", "surf_energy", "plane_foil_T", "tube_bin_T", "sink_sum")


class RunError(RuntimeError):
    """The simulation became invalid; the message names the particle or setting and the fix."""


class Solver(TallyReads):
    """Advance a Model's State in time."""

    def __init__(self, model: Model):
        self.model = model
        self.state: State = allocate(model)
        f = model.features
        self.n = model.capacity
        self.dt = model.dt
        self.t = 0.0
        self.steps = 0
        self.rebuilds = 0
        self._drift_done = False  # within advance(): the next step's kick-drift is done
        self.split_passes = False  # forces and kick as kernels of their own (`tidem bench --profile` tells them apart)
        self.timer = PhaseTimer()  # seconds per phase of the step (run.json's profile)
        self.field_copier = None  # every field a checkpoint keeps, to and from the host (`tidem.runner.checkpoint`)
        forces = self._build_contacts()
        self.gas = None
        if f.gas:
            self.gas = GasPhase(model, self.state, ti.f32 if f.precision == "float32" else ti.f64, self.timer)
        self._build_integrators(forces)
        self.profile_t0 = None  # time at which the tube heat-flux profile started accumulating
        self._energies, self._sample_sums = make_energy_kernel(model.gravity, self.state)
        self._health = make_health_kernel(self.state)
        self._tallies = FieldCopier({name: getattr(self.state, name) for name in TALLIES
                                     if hasattr(self.state, name)})
        dom = model.scene.domain
        self.particle_stats = ParticleStats(self.state, (dom.min[2], dom.max[2]), f.heat)
        self._build_sources_and_sinks()
        self._move_meshes = None
        self.mesh_t_build = 0.0  # time of the last neighbour build, as the moving meshes' candidates see it
        self.mesh_t_binned = 0.0  # time the moving meshes were last binned (`rebuild`)
        if f.moving_meshes:
            self._move_meshes = hot(make_mesh_mover(self.state, [
                (m.moving, m.center, m.axis, m.speed, m.velocity, bool(m.schedules.keys() - {"temperature"}))
                for m in model.meshes]))
        self.conditions = Conditions(model, self.state, self.gas)  # scheduled temperatures, plate and mesh motions
        self._average = None
        if f.averaging:
            a = model.averaging
            self._average = make_averaging_kernel(model.grid, a.lo, a.cells, a.size, f.n_tubes, a.rings, a.ring_width,
                                                  a.sectors, f.heat, self.state)
        self._check_every = model.scene.numerics.check_interval
        self._rebuild_disp2 = (0.5 * model.skin) ** 2  # kick_drift leaves the largest displacement squared
        heat = model.scene.heat
        self._conduct_every = heat.conduction_interval if heat is not None else 1  # steps per conduction evaluation
        sortable = sorts_storage(f, self.n, bool(model.pours), model.scene.numerics.sort_interval)
        self._sort_every = model.scene.numerics.sort_interval if sortable else 0
        self._permute = None  # the fields moved on the device (kernels/storage_sort.py), the CPU's order from the host
        if self._sort_every:
            self._permute = make_storage_permuter(self.state, [
                name for name in self.state.particle_fields if name not in SCRATCH])
        self.start()

    def _build_contacts(self):
        """The neighbour builder (none without contacts) and the force kernels (`kernels/contact.py`:
        contact law, walls and tubes, heat conduction and radiation in the same pair loop)."""
        model, f, S = self.model, self.model.features, self.state
        forces = make_force_kernel(model.grid, f.law if f.contacts else LINEAR, f.rolling, model.planes, model.tubes,
                                   model.wall_slots, model.gravity, S, f.contact_time,
                                   model.one_material(), f.heat, model.angle_bins, model.fluid_layer,
                                   f.contacts, f.radiation, f.foil, f.wall_foil, static_surfaces(model) if f.contacts else 0,
                                   model.skin + model.heat_reach, model.grain_scale, uniform=model.uniform_particles(),
                                   quiet_margin=quiet_margin(model), meshes=mesh_settings(model))
        self._rebuild = self._cell_order = None
        if f.contacts:  # one launch: the list, then the surfaces in reach (culling), then the meshes' triangles
            after = tuple(fn for fn in (forces.mark_near, forces.list_meshes) if fn is not None)
            rebuild, self._cell_order = make_neighbor_builder(
                model.grid, model.max_neighbors, model.skin + model.heat_reach, f.rolling, f.hysteretic, S, f.growth,
                after, model.uniform_particles(), bounds=quiet_bounds(model))
            self._rebuild = hot(rebuild)
        return forces

    def _build_integrators(self, forces) -> None:
        """Kick-drift and kick (`kernels/integrate.py`), and the reactions (`kernels/reactions.py`, coupled
        to the gas grid when there is one). Unless a reaction may remove particles (which the host must
        learn of between the forces and the kick), the kick also adds the gas forces, lets each particle
        react, and runs in the contact passes' launch."""
        model, f, S = self.model, self.model.features, self.state
        self._react = in_kick = None
        if f.reactions:
            G = self.gas.G if self.gas is not None else None
            gas = model.scene.gas
            reactions = make_reaction_kernel(model.reaction_constants, S, self.gas.gg if G else None, G,
                                             gas.density if gas else 1.0, gas.viscosity if gas else 1.0,
                                             model.wall_slots)
            in_kick = reactions.in_kick
            if in_kick is None:  # else the kick reacts, and the kernel of its own is never launched
                self._react = reactions.react
        self._fused = not f.reactions or in_kick is not None
        self._forces = hot(forces.forces)
        finish = (forces.finish,) if forces.finish is not None else ()
        if self._fused and self.gas:
            finish += (self.gas.force,)
        kernels = make_integrators(model.grid, S, f.heat, f.n_planes + f.n_tubes + f.n_meshes, model.angle_bins, f.foil,
                                   f.growth, f.wall_foil, f.n_planes, finish, forces if self._fused else None, in_kick)
        self._kick_drift, self._kick, self._forces_and_kick = (hot(k) if k is not None else None for k in kernels)

    def _build_sources_and_sinks(self) -> None:
        """Outlet recycling (`kernels/outlet.py`) and pours (`tidem.particles.pour`)."""
        model, f, S = self.model, self.model.features, self.state
        self._recycle = None
        if f.recycle:
            o = model.scene.outlet
            self._recycle = make_recycle_kernel(o.height, o.reinsert_height, model.wall_slots, S)
        elif f.sink:
            self._recycle = make_sink_kernel(model.scene.outlet.height, model.wall_slots, S)
        self.pourer = Pourer(model, S) if model.pours else None

    def start(self) -> None:
        """First neighbour build and force evaluation (so that step() can begin with a kick)."""
        if self.pourer is not None:
            self.pourer.insert(self.t)
        self.rebuild()
        if self.gas is not None:
            self._gas_step()
        if self._fused:
            self._forces_and_kick(self.n, self.t, self.dt, self._conduct_every, 1, 0, 0)  # forces only
        else:
            self._forces(self.n, self.t, self.dt, self._conduct_every, 1)
            self._finish_forces()
        self.check()

    def _finish_forces(self) -> None:
        """The gas forces, in a kernel of their own (with reactions, which act between the forces and
        the kick)."""
        if self.gas is not None:
            self.gas.add_forces(self.n)

    def step(self) -> None:
        """One step; the state is then at the step's end (full-step velocities)."""
        self.advance(1)

    def advance(self, steps: int) -> None:
        """Take `steps` steps with nothing read by the host between them: the kick of each step but
        the last goes on with the next step's kick-drift in the same kernel (`kernels/integrate.py`)."""
        for k in range(steps):
            self._step(drift_next=k < steps - 1, diag=k == steps - 1)

    def steps_until(self, due, every: int, last: int) -> int:
        """The number of steps (at least one) until the first step end at time t with due(t), a
        step count that is a multiple of `every` or of numerics.check_interval (the health check
        then sees a finished step), or step `last` (t summed as `_step` does)."""
        t, k = self.t, 0
        while True:
            k += 1
            t += self.dt
            n = self.steps + k
            if due(t) or n % every == 0 or n % self._check_every == 0 or n >= last:
                return k

    def _step(self, drift_next: bool, diag: bool) -> None:
        """One step; `diag`: the host reads the contact counts and overlaps after it (also at every health
        check; `kernels/contact.py`)."""
        dt = self.dt
        lap = self.timer.lap
        t = self.timer.begin_step(self.steps + 1)
        if not self._drift_done:
            self._kick_drift(self.n, dt)
        self.t += dt
        self.steps += 1
        need = self.state.max_disp[None] > self._rebuild_disp2
        self._drift_done = False
        if self.conditions.active:
            self.conditions.apply(self.t)
        if self._move_meshes is not None:
            self._move_meshes(self.t)
            need |= self._meshes_moved() > 0.5 * self.model.skin
        t = lap("kick-drift", t)
        if self._recycle is not None:
            need |= self._recycle(self.n) > 0
        if self.pourer is not None:
            need |= self.pourer.insert(self.t) > 0
        t = lap("inflow and outflow", t)
        if need:
            t = lap("neighbour build", self.rebuild(t))
        if self.gas is not None and self.steps % self.gas.interval == 0:
            self._gas_step()
            t = clock()
        # the conduction at steps 1, m + 1, 2 m + 1, ... for m steps each: the heat balances after every m steps
        conduct = self._conduct_every if (self.steps - 1) % self._conduct_every == 0 else 0
        diag = int(diag or self.steps % self._check_every == 0)
        if self._fused and not self.split_passes:  # one launch: the contact passes, each particle kicked in the second
            self._forces_and_kick(self.n, self.t, dt, conduct, diag, int(drift_next), 1)
            t = lap("forces and kick", t)
        else:
            self._forces(self.n, self.t, dt, conduct, diag)
            t = lap("contact forces", t)
            if not self._fused:  # else the kick adds the gas forces
                self._finish_forces()
                t = lap("contact forces", t)
                left = self.gas.interval - 1 - self.steps % self.gas.interval if self.gas is not None else 0
                if self._react(self.n, self.t, dt, left) > 0:
                    self.rebuild()  # partners of a removed particle drop it (and their history with it) at once
                t = lap("reactions", t)
            self._kick(self.n, self.t, dt, int(drift_next))
            t = lap("kick", t)
        self._drift_done = drift_next  # the next step's kick-drift is done; max_disp holds its largest displacement
        if self.steps % self._check_every == 0:
            self.check()
            t = lap("checks", t)
        if self.model.angle_bins and self.profile_t0 is None and self.t >= self.model.scene.heat.profile_start:
            self.state.tube_bin_energy.fill(0.0)
            self.state.tube_route_energy.fill(0.0)
            if self.model.features.foil:
                self.state.tube_bin_Tsum.fill(0.0)
            if self.gas is not None and self.gas.walls:
                self.gas.G.wall_energy.fill(0.0)
            self.profile_t0 = self.t

    def sample_averages(self) -> None:
        """Add the particles now to the time-averaged fields of [averaging] (`tidem.results.averaging`)."""
        self._average(self.n)

    def _meshes_moved(self, since: float | None = None) -> float:
        """How far the moving meshes may have moved since the last neighbour build (or since time
        `since`) [m], a bound."""
        t0 = self.mesh_t_build if since is None else since
        return max(m.displacement_bound(t0, self.t) for m in self.model.meshes)

    def rebuild(self, phase_start: float | None = None) -> float | None:
        """Neighbour list (none with contact.model = 'none'); every numerics.sort_interval
        rebuilds the storage is first re-sorted into cell order (`tidem.particles.storage_order`), booked as
        "storage sort" from `phase_start` where given (returns the next phase's start). Moving meshes
        are binned anew where they are now (`tidem.walls.mesh_bins`)."""
        if self._move_meshes is not None:
            tab = self.model.mesh_table
            if self._meshes_moved(self.mesh_t_binned) > tab.margin - 0.5 * self.model.skin:
                start, tri = bin_triangles(tab.at(self.model.meshes, self.t), self.model.grid, tab.inflate)
                if len(tri) > tab.bin_capacity:
                    raise RunError(f"mesh bins overflow: the moving meshes' triangles fill {len(tri)} cell entries, "
                                   f"room for {tab.bin_capacity}; coarsen the mesh or lower numerics.skin")
                load_bins(self.state, start, tri)
                self.mesh_t_binned = self.t
            self.mesh_t_build = self.t
        if self._rebuild is not None:
            if self._sort_every and self.rebuilds % self._sort_every == 0:
                if in_order():
                    sort_storage(self.state, self.model.grid.lo, np.array(self.model.grid.cell_size), self._permute,
                                 self.n)
                else:
                    self._cell_order(self.n)
                    self._permute(self.n)
                if phase_start is not None:
                    phase_start = self.timer.lap("storage sort", phase_start)
            self._rebuild(self.n)
            self.rebuilds += 1
        return phase_start

    def _gas_step(self) -> None:
        try:
            self.gas.step(self.t)
        except GasError as exc:
            raise RunError(str(exc)) from None

    def check(self) -> None:
        """Raise RunError on capacity overflow, NaN or an overlap above numerics.max_overlap."""
        S = self.state
        self._health(self.n)
        tallies = self._tallies.read()  # one read for both
        over = tallies["overflow"]
        if over[0] > 0:
            raise RunError(
                f"neighbour list overflow: a particle has {over[0]} neighbours within reach, capacity is "
                f"{self.model.max_neighbors}; set numerics.max_neighbors = {min(int(over[0] * 1.25) + 1, 512)}")
        if over[1] > 0:
            raise RunError(
                f"wall contact overflow: a particle touches more than {self.model.wall_slots} walls/tubes (or "
                f"{MESH_SLOTS} mesh faces) at once; raise numerics.max_wall_contacts")
        if over[3] > 0:
            raise RunError(
                f"mesh contact overflow: a particle has {over[3]} mesh triangles within reach, room for "
                f"{self.model.mesh_table.candidates}; coarsen the mesh near the particles or lower numerics.skin")
        if over[2] > 0:
            raise RunError(
                f"neighbour list: {over[2]} contacts that changed owner at a rebuild lost their history (more than "
                f"{self.n} at once); lower numerics.skin")
        i, worst_at, worst = self.health(tallies)
        if i < self.n:
            raise RunError(f"particle {S.ident[i]} has a non-finite position at t = {self.t:.6g} s (step {self.steps}); "
                           "the time step is too large for the contact stiffness: lower numerics.dt_fraction")
        limit = self.model.scene.numerics.max_overlap
        if worst > limit:
            raise RunError(
                f"particle {S.ident[worst_at]} overlaps a neighbour or wall by {100 * worst:.1f} % of its radius at t = {self.t:.6g} s "
                f"(limit {100 * limit:.0f} %): the contacts are too soft or too fast for this step; raise "
                "youngs_modulus, lower numerics.dt_fraction, or raise numerics.max_overlap (a run with a checkpoint "
                "continues under a raised one: --resume RUN --set numerics.max_overlap=...)")

    def release(self) -> None:
        self.particle_stats.release()
        if self.gas is not None:
            self.gas.release()
        self.state.release()
