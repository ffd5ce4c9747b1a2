"""Where a run's wall time goes: seconds per phase of the step (run.json's `profile`,
`tidem bench --profile SCENE`).

The Solver and the run loop hand each phase's end to `PhaseTimer.lap`, which books the time
since the previous lap and returns the new start. On the CPU backend a Taichi kernel returns
once it has finished, so the pair of clock reads (about 0.1 us) is the whole cost and the
timer is always on. On a GPU backend kernels run asynchronously: `sync=True` waits for the
device at every phase edge (exact, but it removes the overlap of host and device), so the
run loop enables it only for `tidem bench --profile`. A run on a GPU samples instead
(`sample_every`): one step in SAMPLE_EVERY waits for the device at every phase edge, and the
step's wall time of all steps is shared out among its phases as those sampled steps share it,
so that each phase is booked where its work is done rather than where the host next waited
(the largest-displacement read of every step, which otherwise books the previous step's
forces under "kick-drift"). Output waits for the device before it starts and books only its
own time.

The sampled steps must not keep step with the phases that come every few steps (the gas every
`gas.coupling_interval`, conduction every `heat.conduction_interval`): every 16th step sampled
the gas steps of a 20-step coupling 4x as often as they come (the multiples of 80), and the
GPU run's profile booked the gas at twice its time (benchmarks/README.md, 2026-11-28). A step is
sampled where the fractional part of step x (sqrt(5) - 1)/2 falls below 1/SAMPLE_EVERY (a Weyl
sequence): one step in SAMPLE_EVERY, and the same share of the multiples of any interval.
"""

from __future__ import annotations

import time

import taichi as ti

# "kick-drift": the first half kick and the drift; "storage sort": the particles re-sorted into
# cell order before every numerics.sort_interval-th neighbour build (`tidem.particles.storage_order`);
# "contact forces": the two passes in which each pair's owner evaluates the contact for both
# particles (and the walls and tubes); "kick": the
# second half kick, which (unless a reaction can remove particles) also adds the gas forces and the
# reactions, and between
# outputs the next step's kick-drift (one kernel,
# `tidem.sim.solver`: "kick-drift" then counts only the first step after each output); "forces and
# kick": the two in one kernel launch, as such a run takes them (`tidem bench
# --profile` runs them as kernels of their own to tell them apart); "gas coupling": voidage, drag and heat
# exchange coefficients at each gas step (and the gas forces, where reactions can remove particles);
# "reactions": their own kernel, only where they can remove particles.
PHASES = ("kick-drift", "storage sort", "neighbour build", "contact forces", "gas coupling", "gas flow", "pressure solve",
          "reactions", "inflow and outflow", "kick", "forces and kick", "checks", "output")
clock = time.perf_counter


SAMPLE_EVERY = 16  # a GPU run's sampled steps: the waits (~20 us each) cost under 1 % of a step
STEP_PHASES = tuple(p for p in PHASES if p != "output")
GOLDEN = (5.0 ** 0.5 - 1.0) / 2.0


def sampled_step(step: int, every: int) -> bool:
    """Whether step number `step` is one of a sampled profile's steps, one in `every` (module
    docstring: the fractional part of step x GOLDEN below 1/every, evenly spread over the
    multiples of every interval)."""
    return (step * GOLDEN) % 1.0 < 1.0 / every


class PhaseTimer:
    """Accumulated seconds per phase (PHASES) since construction or `reset()`; with `sync` every
    phase edge waits for the device, with `sample_every` > 0 one step in that many (module
    docstring)."""

    def __init__(self, sync: bool = False, sample_every: int = 0):
        self.sync = sync
        self.sample_every = sample_every
        self.reset()

    def reset(self) -> None:
        self.seconds = dict.fromkeys(PHASES, 0.0)
        self.sampled = dict.fromkeys(PHASES, 0.0)  # the sampled steps' phases, each waited for
        self.sampled_steps = 0
        self._sampling = False

    def begin_step(self, step: int) -> float:
        """The start of step number `step`: a sampled one first waits for the work in flight (booked
        with the steps' phases); returns the step's start."""
        self._sampling = bool(self.sample_every) and sampled_step(step, self.sample_every)
        if self._sampling:
            self.sampled_steps += 1
            return self._settle()
        return clock()

    def begin_output(self) -> float:
        """The start of output in a sampled run: waits for the steps' work in flight first (booked with
        them), so that output books its own time only."""
        return self._settle() if self.sample_every else clock()

    def _settle(self) -> float:
        """Wait for the work in flight, booked with the steps (shared out in `booked`); returns now."""
        start = clock()
        ti.sync()
        now = clock()
        self.seconds["kick-drift"] += now - start
        return now

    def lap(self, phase: str, start: float) -> float:
        """Book the time since `start` to `phase`; returns now (the next phase's start)."""
        if self.sync or self._sampling:
            ti.sync()
        now = clock()
        self.seconds[phase] += now - start
        if self._sampling:
            self.sampled[phase] += now - start
        return now

    def booked(self) -> dict:
        """Seconds per phase; with sampling the steps' phases' total shared out as the sampled steps
        share theirs (module docstring)."""
        sampled = sum(self.sampled[p] for p in STEP_PHASES)
        if not self.sampled_steps or sampled <= 0.0:
            return dict(self.seconds)
        steps_total = sum(self.seconds[p] for p in STEP_PHASES)
        out = {p: steps_total * self.sampled[p] / sampled for p in STEP_PHASES}
        out["output"] = self.seconds["output"]
        return {p: out[p] for p in PHASES}

    def table(self, steps: int) -> dict:
        """{phase: {seconds, ms_per_step, share}} of the phases that took any time, plus the total
        (with `sampled_steps` where the profile was sampled)."""
        seconds = self.booked()
        total = sum(seconds.values())
        rows = {name: {"seconds": s, "ms_per_step": 1e3 * s / max(steps, 1), "share": s / total if total else 0.0}
                for name, s in seconds.items() if s > 0.0}
        rows["total"] = {"seconds": total, "ms_per_step": 1e3 * total / max(steps, 1), "share": 1.0}
        if self.sampled_steps:
            rows["total"]["sampled_steps"] = self.sampled_steps
        return rows


def format_table(rows: dict) -> str:
    """The profile as aligned text lines (phase, ms per step, share)."""
    lines = [f"{'phase':<20} {'ms/step':>9} {'share':>7}"]
    for name, r in rows.items():
        lines.append(f"{name:<20} {r['ms_per_step']:>9.3f} {100 * r['share']:>6.1f}%")
    return "\n".join(lines)
