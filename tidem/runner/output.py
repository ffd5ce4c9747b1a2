"""The files of one run folder as the run loop writes them: snapshots (vtp + pvd, with the gas's
vti and the moving meshes), timeseries.csv, run.json, the alpha and bed profiles. Snapshot files
are written by a writer thread while the run loop steps on (`Output.snapshot`, `flush`).
"""

from __future__ import annotations

import json
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Callable

import numpy as np

from tidem.heat.reactions import reaction_summary
from tidem.io.mesh_output import MeshOutput
from tidem.io.timeseries import TimeSeries
from tidem.io.vtp import write_pvd, write_vti, write_vtp
from tidem.kernels.field_copy import FieldCopier
from tidem.results.averaging import AverageRecorder
from tidem.results.bed_profiles import CSV_NAME, ProfileRecorder, profile_rows, write_csv
from tidem.results.granular import GranularSampler
from tidem.results.tables import alpha_profile, tube_alpha_columns
from tidem.runner.output_size import cadence
from tidem.runner.reaction_output import ReactionLog
from tidem.scene.sizes import largest_diameter
from tidem.sim.model import Model
from tidem.sim.solver import Solver
from tidem.walls.surfaces import plate_z

SNAPSHOT_FIELDS = ("active", "ident", "x", "radius", "v", "w", "ncontact", "T")  # T: with heat
WRITES_AHEAD = 2  # snapshots the writer thread may be behind the run loop (each held in memory meanwhile)


class Output:
    """Snapshots (vtp + pvd), the mesh walls (meshes/ + meshes.pvd), timeseries.csv and run.json
    of one run folder."""

    def __init__(self, out_dir: Path, model: Model, loop: dict | None = None):
        """A fresh run folder, or with `loop` (a checkpoint's run-loop state) the folder of the
        run being resumed: its snapshots and time-series rows up to the checkpoint are kept,
        anything written after it is dropped."""
        self.dir = Path(out_dir)
        self.snap_dir = self.dir / "snapshots"
        self.snap_dir.mkdir(parents=True, exist_ok=True)
        self.model = model
        self.entries: list[tuple[float, str]] = [tuple(e) for e in loop["entries"]] if loop else []
        self.gas_dir = self.dir / "gas" if model.features.gas else None
        if self.gas_dir is not None:
            self.gas_dir.mkdir(exist_ok=True)
        folders = [self.dir, self.snap_dir] + ([self.gas_dir] if self.gas_dir is not None else [])
        for half in [p for folder in folders for p in folder.glob("*.tmp")]:
            half.unlink()  # half-written by a killed run (every file is written under .tmp, then renamed)
        kept = {Path(name).name for _, name in self.entries}
        for old in self.snap_dir.glob("*.vtp"):
            if old.name not in kept:
                old.unlink()
        if self.gas_dir is not None:
            for old in self.gas_dir.glob("*.vti"):
                if old.name.replace("gas_", "snap_").replace(".vti", ".vtp") not in kept:
                    old.unlink()
        for pvd, entries in (("snapshots.pvd", self.entries), ("gas.pvd", self._gas_entries())):
            if entries:
                write_pvd(self.dir / pvd, entries)
            else:
                (self.dir / pvd).unlink(missing_ok=True)
        self.meshes = MeshOutput(self.dir, model.meshes, self.entries)  # each mesh at t = 0, before the renderer starts
        dom = model.scene.domain
        self.open_top = (dom.max[2] if model.features.gas and "z" not in dom.periodic and "z+" not in dom.wall_sides()
                         else None)  # the gas grid's open top: particles above it read its top cell
        self.above_top: list[tuple[float, int]] = [tuple(e) for e in loop.get("above_top", [])] if loop else []
        self._particles = None  # the snapshot's particle fields (`_particle_copier`)
        self._writer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="tidem-snapshots")
        self._pending: list[tuple[Future, Path, Callable | None]] = []
        self.series = TimeSeries(self.dir / "timeseries.csv", loop["series_rows"] if loop else None)
        # the column bed_height_m: the bed_height observable's height at each sample
        self.bed_height = model.features.gas or "bed_height" in model.scene.observables
        self._granular: GranularSampler | None = None  # the column granular_temperature_m2_s2 (`granular`)
        self.reactions = (ReactionLog(self.dir, model, [tuple(r) for r in loop.get("reaction_rows", [])] if loop else None)
                          if model.features.reactions else None)
        self.profiles = (ProfileRecorder(model, loop.get("profiles") if loop else None)
                         if model.features.packed_bed_profiles else None)
        self.averages = (AverageRecorder(model, cadence(model.scene, model.t_end)[1],
                                         loop.get("averages") if loop else None)
                         if model.features.averaging else None)

    def prepare(self, solver: Solver) -> None:
        """Compile the reads of a time-series sample and a snapshot by taking them once, writing nothing:
        the run loop calls this before its clock starts, with `checkpoint.prepare`, so that a run's
        particle-steps per second are its stepping's (their first calls inside the loop took 0.04-0.07 s
        each on fluidized_tube, the first checkpoint 0.3 s; `benchmarks/README.md`)."""
        solver.sample_tallies()
        if self.bed_height or self.model.features.heat:
            solver.particle_stats.sample(solver.n, self.bed_height)
        if solver.gas is not None:
            solver.gas.host_fields()
        self._particle_copier(solver).read()
        granular = self.granular(solver)
        if granular is not None:
            granular.sample()

    def granular(self, solver: Solver) -> GranularSampler | None:
        """The granular temperature's sampler where the scene declares the observable (else None)."""
        scene = self.model.scene
        if self._granular is None and "granular_temperature" in scene.observables:
            grain = max(largest_diameter(g.diameter) for g in scene.particles)
            self._granular = GranularSampler(solver.state, scene.domain, grain)
        return self._granular

    def _particle_copier(self, solver: Solver) -> FieldCopier:
        """The snapshot's particle fields, read in one launch per element type."""
        if self._particles is None:
            S = solver.state
            self._particles = FieldCopier({name: getattr(S, name) for name in SNAPSHOT_FIELDS if hasattr(S, name)})
        return self._particles

    def snapshot(self, solver: Solver, on_written: Callable[[Path], None] | None = None) -> Path:
        """Write the next snapshot and list it in snapshots.pvd; returns its file. The particles and
        the gas are copied from the solver here; the files are written by the writer thread while the
        next steps run (at most WRITES_AHEAD snapshots behind; `flush` waits for them). `on_written`
        is called with the file once it is on disk, in this thread (`poll`, `flush`): the background
        renderer it starts dies with the thread that started it (PR_SET_PDEATHSIG)."""
        host = self._particle_copier(solver).read()
        idx = np.flatnonzero(host["active"])
        ident = host["ident"][idx]  # index in the scene (storage is re-sorted as the bed flows)
        name = f"snap_{len(self.entries):05d}.vtp"
        extra = {"temperature": host["T"][idx]} if self.model.features.heat else {}
        if self.model.features.coarse_grain:
            extra["grains"] = self.model.coarse_grain[ident] ** 3  # grains a parcel stands for (k^3)
        t = solver.t
        points, point_data = host["x"][idx], {**extra,
            "radius": host["radius"][idx],
            "velocity": host["v"][idx],
            "omega": host["w"][idx],
            "id": ident.astype(np.int32),
            "group": self.model.group[ident].astype(np.int32),
            "contacts": host["ncontact"][idx].astype(np.int32),
        }
        self.entries.append((t, f"snapshots/{name}"))
        if self.open_top is not None and (above := int((points[:, 2] > self.open_top).sum())):
            self.above_top.append((t, above))
        self.meshes.snapshot()
        gas = None
        if self.gas_dir is not None:
            gg = solver.gas.gg
            gas = (self.gas_dir / name.replace("snap_", "gas_").replace(".vtp", ".vti"), gg.lo, gg.h, gg.cells,
                   solver.gas.cell_fields(), self._gas_entries())
        entries, path = list(self.entries), self.snap_dir / name

        def write() -> None:
            write_vtp(path, points, point_data, time=t)
            if gas is not None:
                write_vti(*gas[:5], time=t)
                write_pvd(self.dir / "gas.pvd", gas[5])
            write_pvd(self.dir / "snapshots.pvd", entries)

        while len(self._pending) >= WRITES_AHEAD:
            self._done(wait=True)
        self._pending.append((self._writer.submit(write), path, on_written))
        return path

    def _done(self, wait: bool) -> bool:
        """Finish the oldest snapshot handed to the writer (waiting for it with `wait`): raise its
        error (e.g. a full disk) or call its `on_written`. False if there is none (or not yet)."""
        if not self._pending or not (wait or self._pending[0][0].done()):
            return False
        future, path, on_written = self._pending.pop(0)
        future.result()
        if on_written is not None:
            on_written(path)
        return True

    def above_top_note(self, particles: int) -> dict | None:
        """run.json's `above_open_top` where snapshots found particles above the gas grid's open top, else None:
        the snapshots, the most particles above it and when first (the bed expanded or splashed out of the
        domain; those particles read the grid's top cell), with the note the CLI prints."""
        if not self.above_top:
            return None
        first, most = self.above_top[0][0], max(n for _, n in self.above_top)
        return {"snapshots": len(self.above_top), "most": most, "first_s": first,
                "note": f"{len(self.above_top)} of {len(self.entries)} snapshots, the first at t = {first:.4g} s, "
                        f"had particles above the domain's open top z = {self.open_top:g} m (at most {most}, "
                        f"{100 * most / max(particles, 1):.2g} % of them), where the gas grid ends and they read its "
                        "top cell: raise domain.max[2] so that the expanded bed and its splashes stay inside"}

    def poll(self) -> None:
        """Finish the snapshots the writer thread has written so far (in order)."""
        while self._done(wait=False):
            pass

    def flush(self) -> None:
        """Wait until every snapshot handed to the writer thread is on disk (raises its error)."""
        while self._done(wait=True):
            pass

    def close(self) -> None:
        """Flush the snapshots and the time series, and stop the writer thread."""
        try:
            self.flush()
        finally:
            self._writer.shutdown()
            self.series.close()

    def _gas_entries(self) -> list[tuple[float, str]]:
        """gas.pvd's rows: the gas file written with each snapshot (runs with [gas])."""
        if self.gas_dir is None:
            return []
        return [(t, name.replace("snapshots/snap_", "gas/gas_").replace(".vtp", ".vti")) for t, name in self.entries]

    def sample(self, solver: Solver) -> None:
        row = {"time_s": solver.t, "step": solver.steps}
        tallies = solver.sample_tallies()
        row.update(solver.energies(tallies))
        row["max_overlap_ratio"] = solver.largest_overlap(tallies)
        stats = {}
        if self.bed_height or self.model.features.heat:
            stats = solver.particle_stats.sample(solver.n, self.bed_height)
        if self.bed_height:
            row["bed_height_m"] = stats.pop("bed_top")
        granular = self.granular(solver)
        if granular is not None:
            row["granular_temperature_m2_s2"] = granular.sample()
        row.update(solver.outlet_summary(tallies))
        if self.model.features.heat:
            row.update(stats)
            row.update(solver.heat_summary(tallies))
        if solver.gas is not None:
            row.update(solver.gas.summary())
        row.update(tube_alpha_columns(self.model, row))
        if self.reactions is not None:
            row.update(reaction_summary(solver))
            self.reactions.sample(solver)
        for p in self.model.planes:
            if p["name"] == "outlet plate":
                row["plate_z_m"] = plate_z(p, solver.t)
        self.series.append(row)

    def write_alpha_profile(self, solver: Solver) -> None:
        """alpha_profile.csv: tube, angle_deg (0 = top), alpha_W_m2K."""
        rows, _ = alpha_profile(self.model, solver)
        if rows:
            lines = ["tube,angle_deg,alpha_W_m2K"] + [f"{r['tube']},{r['angle_deg']:.2f},{r['alpha_W_m2K']:.6g}" for r in rows]
            (self.dir / "alpha_profile.csv").write_text("\n".join(lines) + "\n")

    def write_bed_profiles(self, solver: Solver) -> dict | None:
        """preheat_profiles.csv of the profiles recorded so far (`tidem.results.bed_profiles`); returns
        their summary for run.json, or None without the packed_bed_profiles observable."""
        if self.profiles is None:
            return None
        rows, result = profile_rows(self.model, solver, self.profiles)
        if rows:
            write_csv(self.dir / CSV_NAME, rows)
        return result

    def write_summary(self, data: dict) -> None:
        path = self.dir / "run.json"
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(data, indent=2, default=float))
        tmp.replace(path)
