"""Where a run's wall time goes: seconds per phase of the step (run.json's `profile`,
`tidem bench --profile SCENE`).

The Solver and the run loop hand each phase's end to `PhaseTimer.lap`, which books the time
since the previous lap and returns the new start. On the CPU backend a Taichi kernel returns
once it has finished, so the pair of clock reads (about 0.1 us) is the whole cost and the
timer is always on. On a GPU backend kernels run asynchronously: `sync=True` waits for the
device at every phase edge (exact, but it removes the overlap of host and device), so the
run loop enables it only for `tidem bench --profile`.
"""

from __future__ import annotations

import time

import taichi as ti

# "kick-drift": the first half kick and the drift; "contact forces": the two passes in which each
# pair's owner evaluates the contact for both particles (and the walls and tubes); "kick": the
# second half kick, which in scenes without reactions also adds the gas forces, and between
# outputs the next step's kick-drift (one kernel,
# `tidem.solver`: "kick-drift" then counts only the first step after each output); "forces and
# kick": the two in one kernel launch, as a run without reactions takes them (`tidem bench
# --profile` runs them as kernels of their own to tell them apart); "gas coupling": voidage, drag and heat
# exchange coefficients at each gas step (and the gas forces, with reactions).
PHASES = ("kick-drift", "neighbour build", "contact forces", "gas coupling", "gas flow", "pressure solve",
          "reactions", "inflow and outflow", "kick", "forces and kick", "checks", "output")
clock = time.perf_counter


class PhaseTimer:
    """Accumulated seconds per phase (PHASES) since construction or `reset()`."""

    def __init__(self, sync: bool = False):
        self.sync = sync
        self.reset()

    def reset(self) -> None:
        self.seconds = dict.fromkeys(PHASES, 0.0)

    def lap(self, phase: str, start: float) -> float:
        """Book the time since `start` to `phase`; returns now (the next phase's start)."""
        if self.sync:
            ti.sync()
        now = clock()
        self.seconds[phase] += now - start
        return now

    def table(self, steps: int) -> dict:
        """{phase: {seconds, ms_per_step, share}} of the phases that took any time, plus the total."""
        total = sum(self.seconds.values())
        rows = {name: {"seconds": s, "ms_per_step": 1e3 * s / max(steps, 1), "share": s / total if total else 0.0}
                for name, s in self.seconds.items() if s > 0.0}
        rows["total"] = {"seconds": total, "ms_per_step": 1e3 * total / max(steps, 1), "share": 1.0}
        return rows


def format_table(rows: dict) -> str:
    """The profile as aligned text lines (phase, ms per step, share)."""
    lines = [f"{'phase':<20} {'ms/step':>9} {'share':>7}"]
    for name, r in rows.items():
        lines.append(f"{name:<20} {r['ms_per_step']:>9.3f} {100 * r['share']:>6.1f}%")
    return "\n".join(lines)
