"""The gas phase of a run (built only when the scene has a `[gas]` table).

`GasPhase` owns the gas grid's Taichi fields (see `kernels/gas_flow.py` for the equations and
`kernels/gas_coupling.py` for the exchange with particles) and advances the gas by one step
of `coupling_interval` DEM steps: deposit voidage and drag, predict, project (CG), correct,
gas energy, then sample the new gas state at the particles. Stability limits it cannot
meet (gas Courant number, a drag relaxation time or a gas-particle heat-exchange time
m c / H_p shorter than the DEM step) raise `GasError` with the setting to change.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import taichi as ti

from tidem.kernels.drag import DRAG_IDS, NUSSELT_IDS
from tidem.kernels.gas_coupling import make_coupling_kernels
from tidem.kernels.gas_flow import CLOSED, INLET, INTERIOR, OUTLET, SERIAL_CELLS, make_flow_kernels
from tidem.kernels.gas_grid import GasGrid
from tidem.kernels.species import make_species_kernel
from tidem.phases import PhaseTimer, clock

MAX_COURANT = 0.5


class GasError(RuntimeError):
    """The gas step cannot go on stably; the message names the setting to change."""


def gas_grid(scene) -> GasGrid:
    """Cells of about `gas.cell_size` (a whole number per axis) over the domain."""
    dom = scene.domain
    cells, h = [], []
    for a in range(3):
        length = dom.max[a] - dom.min[a]
        n = max(1, int(round(length / scene.gas.cell_size)))
        cells.append(n)
        h.append(length / n)
    periodic = tuple("xyz"[a] in dom.periodic for a in range(3))
    return GasGrid(lo=tuple(dom.min), cells=tuple(cells), h=tuple(h), periodic=periodic)


def solid_cells(gg: GasGrid, tubes: list[dict]) -> np.ndarray:
    """1 for cells whose centre lies inside a tube (wall for the gas)."""
    idx = np.indices(gg.cells).reshape(3, -1).T
    centres = np.asarray(gg.lo) + (idx + 0.5) * np.asarray(gg.h)
    solid = np.zeros(len(idx), np.int32)
    for t in tubes:
        d = (centres - np.asarray(t["c"])) * np.asarray(t["mask"])
        solid |= (np.einsum("ij,ij->i", d, d) < t["r"] ** 2).astype(np.int32)
    return solid.reshape(gg.cells)


def tube_walls(gg: GasGrid, tubes: list[dict]) -> dict[str, np.ndarray] | None:
    """Per cell, the surface of a heated tube that the cell borders, for gas-tube convection:
    wall_A [m^2] (the faces it shares with that tube's solid cells, scaled so that each tube's
    cells add up to pi D L), wall_T [K], wall_D [m] and wall_k (tube index); None when no
    heated tube has solid cells."""
    idx = np.indices(gg.cells).reshape(3, -1).T
    centres = np.asarray(gg.lo) + (idx + 0.5) * np.asarray(gg.h)
    face_area = [gg.h[1] * gg.h[2], gg.h[0] * gg.h[2], gg.h[0] * gg.h[1]]
    area = np.zeros(gg.cells)
    out = {"wall_T": np.zeros(gg.cells), "wall_D": np.ones(gg.cells), "wall_k": np.zeros(gg.cells, np.int32)}
    for k, t in enumerate(tubes):
        if t["T"] is None:
            continue
        d = (centres - np.asarray(t["c"])) * np.asarray(t["mask"])
        inside = (np.einsum("ij,ij->i", d, d) < t["r"] ** 2).reshape(gg.cells)
        if not inside.any():
            continue
        borders = np.zeros(gg.cells)
        for a in range(3):
            for shift in (1, -1):
                nb = np.roll(inside, shift, axis=a)
                if not gg.periodic[a]:  # no wrap-around on open axes
                    edge = [slice(None)] * 3
                    edge[a] = 0 if shift == 1 else -1
                    nb[tuple(edge)] = False
                borders += (nb & ~inside) * face_area[a]
        axis = int(np.flatnonzero(np.asarray(t["mask"]) == 0.0)[0])
        true_area = 2 * np.pi * t["r"] * gg.cells[axis] * gg.h[axis]
        mine = borders > 0
        area[mine] += borders[mine] * true_area / borders.sum()
        out["wall_T"][mine], out["wall_D"][mine], out["wall_k"][mine] = t["T"], 2 * t["r"], k
    if not area.any():
        return None
    out["wall_A"] = area
    return out


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


def inlet_map(gg: GasGrid, gas) -> np.ndarray:
    """Superficial inlet velocity [m/s] of each bottom face (nozzles override the background)."""
    xc = gg.lo[0] + (np.arange(gg.cells[0]) + 0.5) * gg.h[0]
    yc = gg.lo[1] + (np.arange(gg.cells[1]) + 0.5) * gg.h[1]
    X, Y = np.meshgrid(xc, yc, indexing="ij")
    u = np.full(X.shape, gas.inlet_velocity)
    for nz in gas.nozzles:
        inside = (X >= nz.x[0]) & (X <= nz.x[1])
        if nz.y is not None:
            inside &= (Y >= nz.y[0]) & (Y <= nz.y[1])
        u[inside] = nz.velocity
    return u


def drag_rate_bound(gas, d: float, rho_p: float) -> float:
    """Upper estimate of K/m [1/s] for a particle of diameter d and density rho_p: the larger
    of the Wen-Yu Stokes-range drag at eps = 0.8 (Re from the fastest inlet velocity) and the
    Ergun drag at the clipped voidage; twice that for margin."""
    u = max([gas.inlet_velocity] + [nz.velocity for nz in gas.nozzles]) / gas.min_voidage
    mu, rho = gas.viscosity, gas.density
    re = rho * u * d / mu
    wen_yu = 18 * mu / (rho_p * d * d) * (1 + 0.15 * re**0.687) * 0.8**-2.65
    eps = gas.min_voidage
    ergun = (150 * (1 - eps) * mu / (eps * d * d) + 1.75 * rho * u / (eps * d)) / rho_p
    return 2.0 * max(wen_yu, ergun)


def fixed_bed_voidage(gg: GasGrid, x: np.ndarray, radius: np.ndarray) -> float:
    """Smallest voidage of a gas cell holding a fixed bed: particle volumes binned to the cell
    of their centre (the bed never moves, so this is the voidage the gas always sees)."""
    idx = np.floor((x - np.asarray(gg.lo)) / np.asarray(gg.h)).astype(int)
    idx = np.clip(idx, 0, np.asarray(gg.cells) - 1)
    solid = np.zeros(gg.cells)
    np.add.at(solid, tuple(idx.T), 4.0 / 3.0 * np.pi * radius**3)
    return float(1.0 - solid.max() / (gg.h[0] * gg.h[1] * gg.h[2]))


def gas_step_checks(scene, dt: float, radius: np.ndarray, density: np.ndarray,
                    fixed_x: np.ndarray | None = None) -> list[str]:
    """Refusals before the first step: drag relaxation, gas Courant and diffusion numbers.
    The Courant number takes the interstitial inlet velocity at `gas.min_voidage` (a moving
    bed may pack that far), or for a bed whose particles are all fixed (at `fixed_x`) at its
    densest cell's voidage."""
    gas = scene.gas
    gg = gas_grid(scene)
    errs = []
    i = int(np.argmin(density * radius**2))
    rate = drag_rate_bound(gas, 2 * radius[i], density[i])
    if dt * rate > 1.0:
        errs.append(f"gas: the drag relaxation time of the smallest, lightest particles (about {1 / rate:.3g} s) is "
                    f"shorter than the time step {dt:.3g} s; use numerics.dt <= {1 / rate:.3g} (or a smaller "
                    "dt_fraction), or larger particles")
    dt_gas = gas.coupling_interval * dt
    voidage = gas.min_voidage if fixed_x is None else max(gas.min_voidage, fixed_bed_voidage(gg, fixed_x, radius))
    u = max([gas.inlet_velocity] + [nz.velocity for nz in gas.nozzles]) / voidage
    courant = u * dt_gas / min(gg.h)
    if courant > MAX_COURANT:
        stable = max(1, int(MAX_COURANT * min(gg.h) / (u * dt)))
        errs.append(f"gas.coupling_interval: a gas step of {dt_gas:.3g} s gives a Courant number {courant:.2f} at the "
                    f"interstitial inlet velocity {u:.3g} m/s (limit {MAX_COURANT}); use coupling_interval <= {stable}")
    diffusion = gas.viscosity / gas.density * dt_gas * sum(1 / h**2 for h in gg.h)
    if diffusion > 0.5:
        stable = max(1, int(0.5 / (gas.viscosity / gas.density * dt * sum(1 / h**2 for h in gg.h))))
        errs.append(f"gas.coupling_interval: the gas diffusion number nu dt sum(1/h^2) = {diffusion:.2f} exceeds 0.5; "
                    f"use coupling_interval <= {stable} or larger gas cells")
    if scene.heat is not None and gas.conduction:
        # explicit conduction stays positive while alpha dt sum(2/h^2) eps_f/eps <= 1, and a face
        # between a cell at min_voidage and an empty one has eps_f/eps = (1 + 1/min_voidage)/2
        per_dt = (scene.heat.gas_conductivity / (gas.density * gas.heat_capacity) * sum(1 / h**2 for h in gg.h)
                  * (1 + 1 / gas.min_voidage) / 2)
        if per_dt * dt_gas > 0.5:
            stable = max(1, int(0.5 / (per_dt * dt)))
            errs.append(f"gas.conduction: the gas conduction number alpha dt sum(1/h^2) (1 + 1/min_voidage)/2 = "
                        f"{per_dt * dt_gas:.2f} exceeds 0.5; use gas.coupling_interval <= {stable}, larger gas cells, "
                        "or gas.conduction = false")
    return errs


class GasPhase:
    """Gas fields and the gas step for one Solver."""

    def __init__(self, model, S, fp, timer: PhaseTimer | None = None):
        scene = model.scene
        gas = scene.gas
        self.gas = gas
        self.timer = timer or PhaseTimer()
        self.gg = gg = gas_grid(scene)
        self.heat = model.features.heat
        self.species = model.features.species
        self.sources = bool(model.features.reactions)
        self.interval = gas.coupling_interval
        self.dt = gas.coupling_interval * model.dt
        self.tol = max(gas.tolerance, 1e-5 if fp == ti.f32 else 0.0)
        self.solid = solid_cells(gg, model.tubes)
        self.tubes = model.tubes
        self.kinds = face_kinds(gg, self.solid)
        self.inlet = inlet_map(gg, gas)
        G = SimpleNamespace()
        fb = ti.FieldsBuilder()
        cell_names = ["eps", "eps_old", "solid_vol", "p", "rhs", "diag", "cg_r", "cg_d", "cg_q"]
        if self.heat:
            cell_names += ["T", "T_new", "H", "HT"]
        if self.sources:
            cell_names += ["Qs"]
        if self.species:
            cell_names += ["Y", "Y_new", "o2_sink"]
        for name in cell_names:
            setattr(G, name, ti.field(fp))
            fb.dense(ti.ijk, gg.cells).place(getattr(G, name))
        G.solid = ti.field(ti.i32)
        fb.dense(ti.ijk, gg.cells).place(G.solid)
        for name, dtype in (("u", fp), ("us", fp), ("A", fp), ("C", fp), ("gp", fp), ("B", fp), ("Bv", fp),
                            ("kind", ti.i32)):
            comps = [ti.field(dtype) for _ in range(3)]
            for c in range(3):
                fb.dense(ti.ijk, gg.face_shape(c)).place(comps[c])
            setattr(G, name, comps)
        G.inlet = ti.field(fp)
        fb.dense(ti.ij, gg.cells[:2]).place(G.inlet)
        G.sums = ti.field(fp)
        fb.dense(ti.i, 2).place(G.sums)
        G.heat_rate = ti.field(fp)  # max over particles of H_p / (m_p c_p) [1/s], set by `couple`
        fb.dense(ti.i, 1).place(G.heat_rate)
        walls = tube_walls(gg, model.tubes) if self.heat and gas.tube_convection != "none" else None
        self.walls = walls is not None
        if walls is not None:
            for name in ("wall_A", "wall_T", "wall_D"):
                setattr(G, name, ti.field(fp))
                fb.dense(ti.ijk, gg.cells).place(getattr(G, name))
            G.wall_k = ti.field(ti.i32)
            fb.dense(ti.ijk, gg.cells).place(G.wall_k)
            G.wall_rate = ti.field(fp)
            G.wall_energy = ti.field(ti.f64)
            fb.dense(ti.i, len(model.tubes)).place(G.wall_rate, G.wall_energy)
        if self.sources:  # enthalpy [J] and O2 [kg] that entered through inlet and outlet; most negative Y
            G.bsum = ti.field(ti.f64)
            fb.dense(ti.i, 3).place(G.bsum)
        self._tree = fb.finalize()
        self.G = G
        G.solid.from_numpy(self.solid)
        if walls is not None:
            for name, values in walls.items():
                getattr(G, name).from_numpy(values)
        for c in range(3):
            G.kind[c].from_numpy(self.kinds[c])
        G.eps.fill(1.0)
        G.eps_old.fill(1.0)
        k_gas = scene.heat.gas_conductivity if self.heat else 0.026
        self.t_in = (gas.inlet_temperature or scene.heat.initial_temperature) if self.heat else 0.0
        self.flow = make_flow_kernels(gg, G, gas.density, gas.viscosity, model.gravity, self.heat,
                                      gas.density * gas.heat_capacity, self.walls, k_gas,
                                      gas.heat_capacity * gas.viscosity / k_gas, self.sources,
                                      self.heat and gas.conduction)
        self._deposit, self._couple, self._sample, self.add_forces, self.force = make_coupling_kernels(
            gg, G, S, DRAG_IDS[gas.drag], gas.density, gas.viscosity, gas.min_voidage, self.heat,
            NUSSELT_IDS[gas.heat_transfer], gas.heat_capacity * gas.viscosity / k_gas, k_gas, self.species,
            model.dt if self.sources else 0.0, self.t_in)
        if self.species:
            from tidem.reactions import o2_mass_fraction

            ox = gas.oxygen
            self._species = make_species_kernel(gg, G, self.flow, gas.density, ox.diffusivity)
            self.y_in = o2_mass_fraction(ox.mole_fraction, ox.molar_mass)
            x0 = ox.mole_fraction if ox.initial_mole_fraction is None else ox.initial_mole_fraction
            G.Y.fill(o2_mass_fraction(x0, ox.molar_mass))
        if self.heat:
            T0 = gas.initial_temperature or scene.heat.initial_temperature
            G.T.fill(T0)
        self.n = model.capacity
        self.iterations = 0
        self.residual = 0.0
        self.divergence = 0.0
        self.steps = 0
        self.set_inlet(0.0)
        self._deposit(self.n)
        G.eps_old.copy_from(G.eps)
        # start from the inlet flow (at its ramped value) spread over the bed
        uz = np.where(self.kinds[2] == CLOSED, 0.0, gas.inlet_velocity * self.inlet_scale)
        G.u[2].from_numpy(uz)

    def set_inlet(self, t: float) -> None:
        ramp = self.gas.inlet_ramp
        scale = min(t / ramp, 1.0) if ramp > 0 else 1.0
        self.G.inlet.from_numpy(self.inlet * scale)
        self.inlet_scale = scale

    def step(self, t: float) -> None:
        """One gas step ending at time t (particles at their current positions and velocities)."""
        dt = self.dt
        f = self.flow
        lap = self.timer.lap
        start = clock()
        if self.gas.inlet_ramp > 0:
            self.set_inlet(t)
        self._deposit(self.n)
        rate = self._couple(self.n)
        start = lap("gas coupling", start)
        if rate * dt / self.interval > 1.0:
            raise GasError(
                f"the drag relaxation time of the lightest particle ({1.0 / rate:.3g} s) is shorter than the DEM step "
                f"({dt / self.interval:.3g} s): lower numerics.dt (or dt_fraction), or use larger particles")
        if self.heat:
            heat_rate = float(self.G.heat_rate[0])
            if heat_rate * dt / self.interval > 1.0:
                raise GasError(
                    f"the gas-particle heat-exchange time m c / (h pi d^2) of the fastest particle ({1.0 / heat_rate:.3g} s) "
                    f"is shorter than the DEM step ({dt / self.interval:.3g} s), so the explicit particle temperature "
                    "update would overshoot: lower numerics.dt (or dt_fraction), or raise the particles' heat capacity")
        f["predict"](dt)
        start = lap("gas flow", start)
        self._project(dt)
        start = lap("pressure solve", start)
        f["correct"]()
        courant = f["courant"](dt)
        if courant > MAX_COURANT:
            fix = (f"lower gas.coupling_interval (now {self.interval})" if self.interval > 1
                   else "lower numerics.dt (or dt_fraction)")
            raise GasError(
                f"gas Courant number {courant:.2f} exceeds {MAX_COURANT} at t = {t:.6g} s (gas step {dt:.3g} s): {fix}")
        if self.heat:
            f["energy"](dt, self.t_in)
        if self.species:
            self._species(dt, self.y_in)
            if self.G.bsum[2] < 0.0:
                raise GasError(
                    f"the particles took more O2 from a gas cell than it held within one gas step at t = {t:.6g} s: "
                    f"lower gas.coupling_interval (now {self.interval}) or numerics.dt")
        self.divergence = f["divergence"](dt)
        start = lap("gas flow", start)
        self._sample(self.n)
        lap("gas coupling", start)
        self.steps += 1

    def _project(self, dt: float) -> None:
        """Solve for p by Jacobi-preconditioned CG (module `kernels/gas_flow`)."""
        f, G = self.flow, self.G
        bb = f["assemble"](dt)
        u_scale = max(float(np.abs(self.inlet).max()) * self.inlet_scale, 1e-3)
        scale = max(math.sqrt(bb), u_scale / min(self.gg.h) * math.sqrt(self.solid.size))
        if self.solid.size <= SERIAL_CELLS:
            it = f["cg_serial"](self.gas.max_iterations, self.tol * scale)
            self._finish(it, math.sqrt(max(float(G.sums[1]), 0.0)) / scale)
            return
        rz = f["cg_start"]()
        it = 0
        rr = rz
        for it in range(1, self.gas.max_iterations + 1):
            dq = f["cg_apply"]()
            if dq <= 0.0:
                break
            alpha = rz / dq
            f["cg_update"](alpha)
            rz_new, rr = float(G.sums[0]), float(G.sums[1])
            if math.sqrt(rr) <= self.tol * scale:
                break
            f["cg_direction"](rz_new / rz)
            rz = rz_new
        self._finish(it, math.sqrt(max(rr, 0.0)) / scale)

    def _finish(self, it: int, residual: float) -> None:
        self.iterations = it
        self.residual = residual
        if residual > 10 * self.tol and it >= self.gas.max_iterations:
            raise GasError(
                f"the pressure solve did not converge in {it} iterations (relative residual {self.residual:.2e}, "
                f"tolerance {self.tol:.0e}): raise gas.max_iterations or gas.tolerance")

    def pressure_drop(self) -> float:
        """Mean pressure on the inlet faces [Pa] (p = 0 at the outlet), fluid cells only."""
        p = self.G.p.to_numpy()[:, :, 0]
        gp = self.G.gp[2].to_numpy()[:, :, 0]
        open_ = self.kinds[2][:, :, 0] == INLET
        if not open_.any():
            return 0.0
        face = p - 0.5 * self.gg.h[2] * gp
        return float(face[open_].mean())

    def summary(self) -> dict:
        out = dict(gas_pressure_drop_Pa=self.pressure_drop(), gas_cg_iterations=self.iterations,
                   gas_residual=self.residual, gas_divergence_per_s=self.divergence)
        if self.heat:
            T = self.G.T.to_numpy()[self.solid == 0]
            out["gas_T_mean_K"] = float(T.mean())
        if self.walls:
            rate = self.G.wall_rate.to_numpy()
            for k, tube in enumerate(self.tubes):
                if tube["T"] is not None:
                    out[f"tubes{k}_gas_heat_W"] = float(rate[k])
        return out

    def cell_fields(self) -> dict[str, np.ndarray]:
        """The gas state per cell for snapshots (`gas/*.vti`): voidage, pressure [Pa],
        velocity at the cell centre [m/s] (mean of the two faces), with heat the temperature
        [K], with O2 transport its mole fraction, and `solid` (1 inside a tube)."""
        G = self.G
        out = {"voidage": G.eps.to_numpy(), "pressure": G.p.to_numpy()}
        centre = []
        for c in range(3):
            u = G.u[c].to_numpy()
            if u.shape[c] == self.gg.cells[c]:  # periodic: the last face is the first
                u = np.concatenate([u, np.take(u, [0], axis=c)], axis=c)
            lo = np.take(u, range(self.gg.cells[c]), axis=c)
            hi = np.take(u, range(1, self.gg.cells[c] + 1), axis=c)
            centre.append(0.5 * (lo + hi))
        out["velocity"] = np.stack(centre, axis=-1)
        if self.heat:
            out["temperature"] = G.T.to_numpy()
        if self.species:
            from tidem.reactions import M_O2

            out["o2_mole_fraction"] = G.Y.to_numpy() * self.gas.oxygen.molar_mass / M_O2
        out["solid"] = self.solid.astype(np.int32)
        return out

    def mean_o2_mole_fraction(self) -> float:
        """Mean O2 mole fraction over the fluid cells."""
        from tidem.reactions import M_O2

        y = self.G.Y.to_numpy()[self.solid == 0]
        return float(y.mean() * self.gas.oxygen.molar_mass / M_O2)

    def release(self) -> None:
        if self._tree is not None:
            self._tree.destroy()
            self._tree = None
