"""What the host reads of a solver's tallies (`kernels/field_copy.py`: one launch per element type):
energies, the health check's reductions, the heated surfaces' heat, the outlets' counts. A mixin of
`tidem.sim.solver.Solver`, which owns the tallies (`_tallies`) and the reduction kernels (`_energies`,
`_health`, `_sample_sums`, `kernels/diagnostics.py`)."""

from __future__ import annotations

import numpy as np

from tidem.walls.surfaces import is_heated


class TallyReads:
    """The tally reads of a Solver; a time-series sample takes `sample_tallies` once and hands the
    result to each of the others."""

    def sample_tallies(self) -> dict[str, np.ndarray]:
        """Every tally after a time-series sample's reductions (`kernels/diagnostics.make_energy_kernel`:
        energies, largest overlap, first non-finite position; one launch, one read) for `energies`,
        `largest_overlap`, `outlet_summary` and `heat_summary` (about 0.5 ms a sample less than each
        reading its own, `benchmarks/README.md`)."""
        self._sample_sums(self.n)
        return self._tallies.read()

    def outlet_summary(self, tallies: dict | None = None) -> dict:
        """Mass [kg] and number of the particles a sink outlet has taken or a recycle outlet has moved
        to the top (empty without either); `tallies`: a read of them (else read here)."""
        if not (self.model.features.sink or self.model.features.recycle):
            return {}
        mass, count = (tallies or self._tallies.read())["sink_sum"]
        return dict(discharged_mass_kg=float(mass), discharged_particles=int(count))

    def health(self, tallies: dict | None = None) -> tuple[int, int, float]:
        """(first active particle with a non-finite position, or n; first with the largest overlap
        ratio; that ratio), reduced on the device (`kernels/diagnostics.py`); `tallies`: a read of
        them just after the health kernel (else it runs here)."""
        if tallies is None:
            self._health(self.n)
            tallies = self._tallies.read()
        bad, worst_at = (int(v) for v in tallies["worst_at"])
        return bad, worst_at, float(tallies["worst"])

    def largest_overlap(self, tallies: dict) -> float:
        """The largest overlap ratio of `sample_tallies`."""
        return float(tallies["worst"])

    def energies(self, tallies: dict | None = None) -> dict:
        """Kinetic, rotational and potential energy [J], contacts per particle, active count;
        `tallies`: those of `sample_tallies` (else the energies are summed here)."""
        if tallies is None:
            self._energies(self.n)
            tallies = self._tallies.read()
        e_kin, e_rot, e_pot, contacts, active = (float(v) for v in tallies["sums"])
        return dict(kinetic_energy_J=e_kin, rotational_energy_J=e_rot, potential_energy_J=e_pot,
                    coordination=contacts / max(active, 1.0), particles=int(active))

    def heat_summary(self, tallies: dict | None = None) -> dict:
        """Heat flow [W] and heat [J] per heated surface (the particles' temperatures:
        `particle_stats`); `tallies`: a read of them (else read here)."""
        out = {}
        tallies = tallies or self._tallies.read()
        rate, energy = tallies["surf_rate"], tallies["surf_energy"]
        f = self.model.features
        n_planes = len(self.model.planes)
        foil_T = list(tallies["plane_foil_T"] if f.wall_foil else [None] * n_planes)
        foil_T += list(tallies["tube_bin_T"].mean(axis=1) if f.foil else [None] * len(self.model.tubes))
        meshes = [m.surface() for m in self.model.meshes]
        for s, surf in enumerate(self.model.planes + self.model.tubes + meshes):
            if is_heated(surf):
                key = surf["name"].replace(" ", "_").replace("[", "").replace("]", "")
                out[f"{key}_heat_W"] = float(rate[s])
                out[f"{key}_heat_J"] = float(energy[s])
                if surf.get("flux") is not None:
                    out[f"{key}_foil_T_K"] = float(foil_T[s])
        return out
