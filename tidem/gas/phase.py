"""The gas phase of a run (built only when the scene has a `[gas]` table).

`GasPhase` owns the gas grid's Taichi fields (see `kernels/gas_flow.py` for the equations and
`kernels/gas_coupling.py` for the exchange with particles) and advances the gas by one step
of `coupling_interval` DEM steps: deposit voidage and drag, predict, project (CG), correct,
gas energy, then sample the new gas state at the particles. Stability limits it cannot
meet (gas Courant number, a drag relaxation time or a gas-particle heat-exchange time
m c / H_p shorter than the DEM step) raise `GasError` with the setting to change.

Set-up beside it: the grid's cells, faces and tube walls (`tidem.gas.geometry`), its Taichi
fields (`tidem.gas.fields`), and the refusals before the first step (`tidem.gas.limits`).
"""

from __future__ import annotations

import math

import numpy as np
import taichi as ti

from tidem.analytic.fluidized_bed_heat import wen_yu_minimum_fluidization
from tidem.gas.fields import allocate_gas_fields
from tidem.gas.geometry import (averaging_length, convection_walls, cuts_tubes, gas_grid, gas_walls,
                                grain_sauter_diameter, inlet_parts, parcel_rows_max, voidage_filters, voidage_layers)
from tidem.gas.limits import MAX_COURANT, inlet_velocities
from tidem.gas.open_volume import open_volumes
from tidem.gas.probes import probe_pressures
from tidem.gas.species import M_O2, o2_mass_fraction
from tidem.kernels.drag import DRAG_IDS, NUSSELT_IDS
from tidem.kernels.field_copy import FieldCopier
from tidem.kernels.gas_band import band_width
from tidem.kernels.gas_coupling import make_coupling_kernels
from tidem.kernels.gas_flow import RR, cg_batch, make_flow_kernels, serial_solve
from tidem.kernels.gas_grid import CLOSED, INLET
from tidem.kernels.species import make_species_kernel
from tidem.runtime.phases import PhaseTimer, clock
from tidem.scene.schedule import is_scheduled, start, value_at


class GasError(RuntimeError):
    """The gas step cannot go on stably; the message names the setting to change."""


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
        cut_tubes = cuts_tubes(scene)
        self.solid, self.kinds, self.cut = gas_walls(gg, model.tubes, model.meshes, model.gas_cut, cut_tubes)
        self.tubes = model.tubes
        self.heated_meshes = [k for k, m in enumerate(model.meshes) if m.temperature is not None]
        self.velocities = dict(inlet_velocities(gas))  # {scene key: velocity or schedule}, `install` replaces one
        self.scheduled_inlet = any(is_scheduled(u) for u in self.velocities.values())
        self.inlet_parts = inlet_parts(gg, gas)  # background, then each nozzle (the dict's order)
        self.inlet = self.inlet_at(0.0)
        walls = convection_walls(gg, model.tubes, model.meshes, self.cut, cut_tubes) \
            if self.heat and gas.tube_convection != "none" else None
        self.walls = walls is not None
        self._wall_T = (walls["wall_T"].copy(), walls["wall_k"], walls["wall_A"] > 0.0) if self.walls else None
        self.layers = voidage_layers(model)
        self.open = open_volumes(gg, self.solid, self.kinds, model.tubes, self.cut, self.layers)
        self.filters = voidage_filters(gg, averaging_length(scene), self.layers, gas.drag_averaging == "length")
        self.band = band_width(gg)  # > 0: the pressure solved directly (`kernels/gas_band.py`)
        n_walls = len(model.tubes) + (len(model.meshes) if self.heated_meshes else 0)  # wall_k of mesh k: tubes + k
        self.G, self._tree = allocate_gas_fields(gg, fp, self.solid, self.kinds, walls, n_walls, self.heat,
                                                 self.sources, self.species, self.open, self.layers, self.band,
                                                 self.cut, tuple(f is not None for f in self.filters))
        G = self.G
        host = {"p": G.p, "gp2": G.gp[2], "eps": G.eps, **{f"u{c}": G.u[c] for c in range(3)}}
        host.update({name: getattr(G, name) for name, on in (("T", self.heat), ("Y", self.species),
                                                              ("wall_rate", self.walls)) if on})
        self._host = FieldCopier(host)  # what samples and snapshots read, in one launch (`kernels/field_copy.py`)
        k_gas = scene.heat.gas_conductivity if self.heat else 0.026
        self.t_in_key = (gas.inlet_temperature or scene.heat.initial_temperature) if self.heat else 0.0
        self.t_in = float(start(self.t_in_key))
        wall_grain, wall_umf = 0.0, 0.0
        if self.walls and gas.tube_convection == "martin_nilles":
            wall_grain = grain_sauter_diameter(model)
            rho_p = float((model.mass).sum() / (4.0 / 3.0 * math.pi * model.radius**3).sum())
            g = float(np.linalg.norm(model.gravity))  # no gravity: nothing fluidizes, no cap
            wall_umf = wen_yu_minimum_fluidization(wall_grain, rho_p, gas.density, gas.viscosity, g) if g > 0 else 1e30
        self.flow = make_flow_kernels(gg, G, gas.density, gas.viscosity, model.gravity, self.heat,
                                      gas.density * gas.heat_capacity, self.walls, k_gas,
                                      gas.heat_capacity * gas.viscosity / k_gas, self.sources,
                                      self.heat and gas.conduction, wall_grain, wall_umf, self.band,
                                      self.open is not None, self.cut is not None, gas.side_walls == "no_slip")
        self.serial_solve = serial_solve(self.solid.size)  # as make_flow_kernels decided
        self.cg_batch = cg_batch()
        self._deposit, self._couple, self._sample, self.add_forces, self.force = make_coupling_kernels(
            gg, G, S, DRAG_IDS[gas.drag], gas.density, gas.viscosity, gas.min_voidage, self.heat,
            NUSSELT_IDS[gas.heat_transfer], gas.heat_capacity * gas.viscosity / k_gas, k_gas, self.species,
            model.dt if self.sources else 0.0, model.features.coarse_grain, self.open is not None,
            self.layers, parcel_rows_max(model), *self.filters)
        if self.species:
            ox = gas.oxygen
            self._species = make_species_kernel(gg, G, self.flow, gas.density, ox.diffusivity)
            self.y_in = o2_mass_fraction(ox.mole_fraction, ox.molar_mass)
            x0 = ox.mole_fraction if ox.initial_mole_fraction is None else ox.initial_mole_fraction
            G.Y.fill(o2_mass_fraction(x0, ox.molar_mass))
        if self.heat:
            T0 = gas.initial_temperature or scene.heat.initial_temperature
            G.T.fill(T0)
            G.t_in.fill(self.t_in)
        self.n = model.capacity
        self.iterations = 0
        self.residual = 0.0
        self.divergence = 0.0
        self.steps = 0
        self.set_inlet(0.0)
        self._deposit(self.n)
        G.eps_old.copy_from(G.eps)
        # start from the inlet flow (at its ramped value) spread over the bed
        uz = np.where(self.kinds[2] == CLOSED, 0.0, start(self.velocities["gas.inlet_velocity"]) * self.inlet_scale)
        G.u[2].from_numpy(uz)

    def set_inlet(self, t: float) -> None:
        """The inlet velocities at time t: gas.inlet_ramp's share of the map, or the scheduled velocities."""
        ramp = self.gas.inlet_ramp
        scale = min(t / ramp, 1.0) if ramp > 0 else 1.0
        if self.scheduled_inlet:
            inlet = self.inlet_at(t)
            if t > 0.0 and np.array_equal(inlet, self.inlet):
                return
            self.inlet = inlet
        self.G.inlet.from_numpy(self.inlet * scale)
        self.inlet_scale = scale

    def inlet_at(self, t: float) -> np.ndarray:
        """Superficial inlet velocity [m/s] of each bottom face at time t: its distributor part's value."""
        return np.array([float(value_at(u, t)) for u in self.velocities.values()])[self.inlet_parts]

    def install(self, key: str, schedule) -> None:
        """From the next gas step on, the inlet velocity or temperature `key` follows `schedule`."""
        if key in self.velocities:
            self.velocities[key] = schedule
            self.scheduled_inlet = True
        elif key == "gas.inlet_temperature" and self.heat:
            self.t_in_key = schedule
        else:
            raise ValueError(f"{key}: not a gas condition this run can change")

    def sync_from_fields(self) -> None:
        """After a checkpoint's fields are restored: take the scheduled inlet and wall temperatures the
        host keeps from the fields, as the last gas step set them."""
        if self.heat:
            self.t_in = float(self.G.t_in[0])
        if self.scheduled_inlet:
            self.inlet = self.G.inlet.to_numpy()
        if self._wall_T is not None:
            self._wall_T[0][...] = self.G.wall_T.to_numpy()

    def set_wall_temperature(self, wall: int, value: float) -> None:
        """The temperature [K] of heated wall `wall` (tube k, then mesh k after the tubes) in the cells whose
        gas it heats (wall_T), as its schedule gives it (`tidem.sim.conditions`)."""
        wall_T, wall_k, heated = self._wall_T
        wall_T[heated & (wall_k == wall)] = value
        self.G.wall_T.from_numpy(wall_T)

    def set_inlet_temperature(self, t: float) -> None:
        """The inlet gas temperature at time t, where a schedule gives it."""
        t_in = float(value_at(self.t_in_key, t))
        if t_in != self.t_in:
            self.t_in = t_in
            self.G.t_in.fill(t_in)

    def step(self, t: float) -> None:
        """One gas step ending at time t (particles at their current positions and velocities)."""
        dt = self.dt
        f = self.flow
        lap = self.timer.lap
        start = clock()
        if self.inlet_scale < 1.0 or self.scheduled_inlet:  # ramping up, or on a schedule
            self.set_inlet(t)
        if self.heat and is_scheduled(self.t_in_key):  # (a schedule installed while the run goes counts too)
            self.set_inlet_temperature(t)
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
                Y = self.G.Y.to_numpy()
                worst = np.unravel_index(np.argmin(Y), Y.shape)
                at = ", ".join(f"{v:.4g}" for v in self.gg.center(worst))
                raise GasError(
                    f"the particles took more O2 from a gas cell than it held within one gas step at t = {t:.6g} s "
                    f"(the cell centred at ({at}) m, O2 mass fraction {Y[worst]:.3g} after the step): "
                    f"lower gas.coupling_interval (now {self.interval}) or numerics.dt")
        self.divergence = f["divergence"](dt)
        start = lap("gas flow", start)
        self._sample(self.n)
        lap("gas coupling", start)
        self.steps += 1

    def _project(self, dt: float) -> None:
        """Solve for p directly on thin grids (banded Cholesky, `kernels/gas_band.py`; 0 iterations), else by
        Jacobi-preconditioned CG (`kernels/gas_flow.py`), also where the direct solve finds the system singular."""
        f, G = self.flow, self.G
        bb = f["assemble"](dt)
        u_scale = max(float(np.abs(self.inlet).max()) * self.inlet_scale, 1e-3)
        scale = max(math.sqrt(bb), u_scale / min(self.gg.h) * math.sqrt(self.solid.size))
        if self.band:
            rr = f["band_solve"]()
            if rr >= 0.0:
                self._finish(0, math.sqrt(rr) / scale)
                return
            self.band = 0  # singular (a fluid region without an outlet): the CG from now on
        if self.serial_solve:
            it = f["cg_serial"](self.gas.max_iterations, self.tol * scale)
            self._finish(it, math.sqrt(max(float(G.sums[RR]), 0.0)) / scale)
            return
        f["cg_start"]()
        it, rr = 0, 0.0
        while it < self.gas.max_iterations:
            rr = f["cg_iterate"]()
            it += self.cg_batch
            if math.sqrt(max(rr, 0.0)) <= self.tol * scale:
                break
        self._finish(it, math.sqrt(max(rr, 0.0)) / scale)

    def _finish(self, it: int, residual: float) -> None:
        self.iterations = it
        self.residual = residual
        if residual > 10 * self.tol and it >= self.gas.max_iterations:
            raise GasError(
                f"the pressure solve did not converge in {it} iterations (relative residual {self.residual:.2e}, "
                f"tolerance {self.tol:.0e}): raise gas.max_iterations or gas.tolerance")

    def host_fields(self) -> dict[str, np.ndarray]:
        """Pressure, its z gradient (gp2), voidage, face velocities (u0, u1, u2) and where solved the
        temperature (T), O2 mass fraction (Y) and the tubes' heat flows (wall_rate), read together."""
        return self._host.read()

    def pressure_drop(self, host: dict | None = None) -> float:
        """Mean pressure on the inlet faces [Pa] (p = 0 at the outlet), fluid cells only (from `host`,
        `host_fields()`, where given)."""
        host = host or self.host_fields()
        p = host["p"][:, :, 0]
        gp = host["gp2"][:, :, 0]
        open_ = self.kinds[2][:, :, 0] == INLET
        if not open_.any():
            return 0.0
        face = p - 0.5 * self.gg.h[2] * gp
        return float(face[open_].mean())

    def probe_pressures(self, host: dict) -> dict[str, float]:
        """The pressures of gas.pressure_probes (`tidem.gas.probes`); gauge, p = 0 at the outlet
        (`host`: `host_fields()`)."""
        if not self.gas.pressure_probes:
            return {}
        return probe_pressures(self.gas.pressure_probes, host["p"], self.solid == 0, self.gg.lo, self.gg.h)

    def summary(self) -> dict:
        host = self.host_fields()
        out = dict(gas_pressure_drop_Pa=self.pressure_drop(host), gas_cg_iterations=self.iterations,
                   gas_residual=self.residual, gas_divergence_per_s=self.divergence)
        out.update(self.probe_pressures(host))
        if self.heat:
            T = host["T"][self.solid == 0]
            out["gas_T_mean_K"] = float(T.mean())
        if self.walls:
            rate = host["wall_rate"]
            for k, tube in enumerate(self.tubes):
                if tube["T"] is not None:
                    out[f"tubes{k}_gas_heat_W"] = float(rate[k])
            for k in self.heated_meshes:
                out[f"meshes{k}_gas_heat_W"] = float(rate[len(self.tubes) + k])
        return out

    def cell_fields(self) -> dict[str, np.ndarray]:
        """The gas state per cell for snapshots (`gas/*.vti`): voidage, pressure [Pa],
        velocity at the cell centre [m/s] (mean of the two faces), with heat the temperature
        [K], with O2 transport its mole fraction, and `solid` (1 inside a tube)."""
        host = self.host_fields()
        out = {"voidage": host["eps"], "pressure": host["p"]}
        centre = []
        for c in range(3):
            u = host[f"u{c}"]
            if u.shape[c] == self.gg.cells[c]:  # periodic: the last face is the first
                u = np.concatenate([u, np.take(u, [0], axis=c)], axis=c)
            lo = np.take(u, range(self.gg.cells[c]), axis=c)
            hi = np.take(u, range(1, self.gg.cells[c] + 1), axis=c)
            centre.append(0.5 * (lo + hi))
        out["velocity"] = np.stack(centre, axis=-1)
        if self.heat:
            out["temperature"] = host["T"]
        if self.species:
            out["o2_mole_fraction"] = host["Y"] * self.gas.oxygen.molar_mass / M_O2
        out["solid"] = self.solid.astype(np.int32)
        return out

    def mean_o2_mole_fraction(self) -> float:
        """Mean O2 mole fraction over the fluid cells."""
        y = self.host_fields()["Y"][self.solid == 0]
        return float(y.mean() * self.gas.oxygen.molar_mass / M_O2)

    def release(self) -> None:
        if self._tree is not None:
            self._tree.destroy()
            self._tree = None
