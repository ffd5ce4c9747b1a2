"""What a run with `[[reactions]]` writes besides the usual output.

- `reactions.csv` (every time-series sample): for up to `TRACKED` reacting particles of each
  reaction, `time_s, reaction, id, T_K, gas_T_K, o2_mole_fraction, diameter_m`, and
  `plots/reactions.png` (particle against gas temperature, and the O2 they see, over time);
- run.json `observables.reactions`: per reaction, char combustion: mean and hottest reacting
  particle against the inert bed, the gas and the O2 they see, carbon burnt, burnt out;
  polymerization: the hottest particles and where they sit; sublimation: the distribution of
  sublimation times (first seen to gone) and the fraction (by number and mass) sublimated
  before the exit, and `plots/sublimation_times.png`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tidem.gas.species import M_O2
from tidem.heat.reactions import ESCAPED, GONE, MASS_ESCAPED, REACTED

TRACKED = 20
HOTTEST = 10


class ReactionLog:
    """Samples reacting particles during a run and writes the files above at the end."""

    def __init__(self, out_dir: Path, model, rows: list | None = None):
        self.dir = Path(out_dir)
        self.model = model
        self.scene = model.scene
        rx = model.reaction_index
        self.tracked = np.concatenate([np.flatnonzero(rx == k)[:TRACKED] for k in range(len(self.scene.reactions))])
        self.rows: list[tuple] = list(rows or [])

    def sample(self, solver) -> None:
        S = solver.state
        idx = self.tracked
        active = S.active.to_numpy()[idx].astype(bool)
        if not active.any():
            return
        idx = idx[active]
        T = S.T.to_numpy()[idx]
        gas_T = S.gT.to_numpy()[idx] if solver.gas is not None else np.full(len(idx), np.nan)
        if self.model.features.species:
            x = S.gY.to_numpy()[idx] * self.scene.gas.oxygen.molar_mass / M_O2
        else:
            x = np.full(len(idx), np.nan)
        d = 2 * S.radius.to_numpy()[idx]
        rx = self.model.reaction_index[idx]
        for k in range(len(idx)):
            self.rows.append((solver.t, int(rx[k]), int(idx[k]), float(T[k]), float(gas_T[k]), float(x[k]), float(d[k])))

    def finish(self, solver) -> dict:
        """Write reactions.csv and the plots; return the observables for run.json."""
        lines = ["time_s,reaction,id,T_K,gas_T_K,o2_mole_fraction,diameter_m"]
        lines += [f"{t:.9g},{r},{i},{T:.6g},{g:.6g},{x:.6g},{d:.6g}" for t, r, i, T, g, x, d in self.rows]
        (self.dir / "reactions.csv").write_text("\n".join(lines) + "\n")
        obs = reaction_observables(self.model, solver)
        self._plot(obs)
        return obs

    def _plot(self, obs: dict) -> None:
        if not self.rows:
            return
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        plots = self.dir / "plots"
        plots.mkdir(exist_ok=True)
        data = np.array(self.rows)
        fig, ax = plt.subplots(figsize=(7, 4))
        ax2 = None
        for k, r in enumerate(self.scene.reactions):
            sel = data[:, 1] == k
            if not sel.any():
                continue
            times = np.unique(data[sel, 0])
            mean = lambda col: np.array([np.nanmean(data[sel & (data[:, 0] == t), col]) for t in times])  # noqa: E731
            hot = np.array([np.nanmax(data[sel & (data[:, 0] == t), 3]) for t in times])
            ax.plot(times, mean(3), label=f"{r.group}: particle T (mean)")
            ax.plot(times, hot, ":", label=f"{r.group}: particle T (hottest tracked)")
            if self.model.features.gas:
                ax.plot(times, mean(4), "--", label=f"{r.group}: gas T at the particles")
            if r.type == "char_combustion":
                ax2 = ax2 or ax.twinx()
                ax2.plot(times, mean(5), color="tab:green", label="O2 mole fraction at the char")
                ax2.set_ylabel("O2 mole fraction")
                ax2.legend(loc="lower right", fontsize=8)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("temperature [K]")
        ax.legend(loc="upper left", fontsize=8)
        fig.tight_layout()
        fig.savefig(plots / "reactions.png", dpi=120)
        plt.close(fig)
        for r in obs.values():
            times = r.get("sublimation_times_s")
            if times:
                fig, ax = plt.subplots(figsize=(6, 4))
                ax.hist(np.array(times) * 1e3, bins=30)
                ax.set_xlabel("sublimation time [ms]")
                ax.set_ylabel("particles")
                ax.set_title(f"{r['fraction_sublimated']:.1%} of the particles sublimated before the exit")
                fig.tight_layout()
                fig.savefig(plots / "sublimation_times.png", dpi=120)
                plt.close(fig)


def reaction_observables(model, solver) -> dict:
    """Per reaction (keyed by its group), the figures of the module docstring."""
    S = solver.state
    scene = model.scene
    active = S.active.to_numpy().astype(bool)
    rx = model.reaction_index
    T = S.T.to_numpy()
    x = S.x.to_numpy()
    sums = S.rsum.to_numpy()
    inert = active & (rx < 0)
    out = {}
    for k, r in enumerate(scene.reactions):
        mine = rx == k
        live = mine & active
        row: dict = {"type": r.type, "particles": int(mine.sum()), "present": int(live.sum())}
        if r.type == "char_combustion":
            row.update(carbon_burnt_kg=float(sums[REACTED]), burnt_out=round(sums[GONE]))
            if live.any():
                row.update(T_mean_K=float(T[live].mean()), T_max_K=float(T[live].max()),
                           gas_T_at_char_K=float(S.gT.to_numpy()[live].mean()),
                           o2_at_char=float((S.gY.to_numpy()[live]).mean() * scene.gas.oxygen.molar_mass / M_O2))
            if inert.any():
                row["inert_T_mean_K"] = float(T[inert].mean())
        elif r.type == "polymerization":
            ids = np.flatnonzero(live)
            hot = ids[np.argsort(T[ids])[::-1][:HOTTEST]]
            row["hottest"] = [{"id": int(i), "T_K": float(T[i]), "x_m": [float(v) for v in x[i]]} for i in hot]
            if live.any():
                row.update(T_mean_K=float(T[live].mean()), T_max_K=float(T[live].max()))
        else:
            t0, t1 = S.rt0.to_numpy(), S.rt1.to_numpy()
            done = mine & (t1 > 0)
            left = mine & (t1 < 0)
            times = (t1 - t0)[done]
            n_out = int(done.sum() + left.sum())
            row.update(sublimated=int(done.sum()), escaped=int(left.sum()),
                       fraction_sublimated=float(done.sum() / n_out) if n_out else float("nan"),
                       mass_sublimated_kg=float(sums[REACTED]), mass_escaped_kg=float(sums[MASS_ESCAPED]),
                       mass_fraction_sublimated=float(sums[REACTED] / max(sums[REACTED] + sums[MASS_ESCAPED], 1e-300)),
                       sublimation_times_s=[float(v) for v in times])
            if len(times):
                row.update(sublimation_time_mean_s=float(times.mean()), sublimation_time_median_s=float(np.median(times)),
                           sublimation_time_p90_s=float(np.percentile(times, 90)),
                           sublimation_time_max_s=float(times.max()))
            row["escaped_count_total"] = round(sums[ESCAPED])
        out[r.group] = row
    return out
