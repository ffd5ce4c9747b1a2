"""Conditions that change in time: a scene key given as a schedule instead of one number.

    inlet_velocity = { times = [0.0, 1.0, 1.5], values = [0.3, 0.3, 0.6], between = "ramp" }

`times` [s] rise strictly; `values` are the key's own (m/s, K, rad/s, ...), one per time. Between two
times the value is ramped linearly (`between = "ramp"`, the default) or held at the earlier value
until the next time (`"hold"`, a step). Before the first time the first value holds, after the last
the last. A schedule is a pure function of the simulated time, so a run resumed from a checkpoint
takes the same values at the same steps as the unbroken run.

A moving mesh's angle and offset are the integrals of its scheduled rotation speed and velocity
(`Schedule.integral`: exact for both forms, a trapezoid per ramped interval), so the mesh turns
through the same angle whatever the time step.
"""

from __future__ import annotations

import bisect
import math
from functools import cached_property
from typing import Annotated, Literal

import numpy as np
from pydantic import Discriminator, Field, Tag, model_validator

from tidem.scene.types import NonNegative, Number, Positive, Strict

Between = Literal["ramp", "hold"]
Betweens = Annotated[Annotated[Between, Tag("[one]")] | Annotated[list[Between], Tag("[each]")],
                     Discriminator(lambda v: "[each]" if isinstance(v, list) else "[one]")]
"""One mode for every interval, or a list of one per interval (a bad value gets one message)."""


class Schedule(Strict):
    """Values of a scene key at given times, ramped or held between them."""

    times: list[NonNegative] = Field(min_length=1)
    values: list[Number] = Field(min_length=1)
    between: Betweens = "ramp"

    @model_validator(mode="after")
    def _consistent(self):
        if len(self.times) != len(self.values):
            raise ValueError(f"'times' and 'values' need one entry each per point (got {len(self.times)} times and "
                             f"{len(self.values)} values)")
        for a, b in zip(self.times, self.times[1:]):
            if b <= a:
                raise ValueError(f"'times' must rise strictly ({b} follows {a}); e.g. times = [0.0, 0.5, 1.0]")
        if isinstance(self.between, list) and len(self.between) != len(self.times) - 1:
            raise ValueError(f"'between' as a list needs one entry per interval, {len(self.times) - 1} for "
                             f"{len(self.times)} times (got {len(self.between)})")
        return self

    def mode(self, k: int) -> str:
        """How the value goes from point k to point k + 1: "ramp" or "hold"."""
        return self.between if isinstance(self.between, str) else self.between[k]

    def _interval(self, t: float) -> int:
        """The last point at or before t (-1 before the first)."""
        return bisect.bisect_right(self.times, t) - 1

    def _ramped(self, k: int, t: float) -> float:
        ts, vs = self.times, self.values
        w = (t - ts[k]) / (ts[k + 1] - ts[k])
        return float(vs[k] + w * (vs[k + 1] - vs[k]))

    def _flat(self, k: int) -> bool:
        """Whether the value holds from point k on (before the first point, after the last, or held)."""
        return k < 0 or k == len(self.times) - 1 or self.mode(k) == "hold"

    def at(self, t: float) -> float:
        """The value at time t [s]."""
        k = self._interval(t)
        if k < 0:
            return float(self.values[0])
        return float(self.values[k]) if self._flat(k) else self._ramped(k, t)

    def integral(self, t: float) -> float:
        """The integral of the value from 0 to t [value x s] (t >= 0): exact, the value being constant
        (hold) or linear (ramp) between consecutive points."""
        cuts = [0.0] + [float(tk) for tk in self.times if 0.0 < tk < t] + [float(t)]
        total = 0.0
        for a, b in zip(cuts, cuts[1:]):
            k = self._interval(a)
            total += self.at(a) * (b - a) if self._flat(k) else 0.5 * (self.at(a) + self._ramped(k, b)) * (b - a)
        return total

    def peak(self) -> float:
        """The largest value (a ramp passes no value beyond its ends)."""
        return float(max(self.values))

    def lowest(self) -> float:
        return float(min(self.values))

    def first_above(self, limit: float, magnitude: bool = False) -> float | None:
        """The first time [s] at which the value (its magnitude) exceeds `limit` >= 0, or None if it never does."""
        size = abs if magnitude else float
        if size(self.values[0]) > limit:
            return 0.0
        for k in range(1, len(self.times)):
            v0, v1 = self.values[k - 1], self.values[k]
            if size(v1) > limit:
                if self.mode(k - 1) == "hold":
                    return float(self.times[k])
                target = -limit if magnitude and v1 < 0 else limit  # a ramp passes it once: size(v0) <= limit
                return float(self.times[k - 1] + (target - v0) / (v1 - v0) * (self.times[k] - self.times[k - 1]))
        return None


class VectorSchedule(Strict):
    """A vector key (a mesh's velocity [m/s]) at given times, ramped or held between them."""

    times: list[NonNegative] = Field(min_length=1)
    values: list[tuple[Number, Number, Number]] = Field(min_length=1)
    between: Betweens = "ramp"

    @model_validator(mode="after")
    def _consistent(self):
        self.components  # the same checks as a number's schedule
        return self

    @cached_property
    def components(self) -> tuple[Schedule, Schedule, Schedule]:
        """One number schedule per component, made once (a run asks every step)."""
        return tuple(Schedule(times=self.times, values=[v[c] for v in self.values], between=self.between)
                     for c in range(3))

    def at(self, t: float) -> tuple[float, float, float]:
        return tuple(s.at(t) for s in self.components)

    def integral(self, t: float) -> tuple[float, float, float]:
        return tuple(s.integral(t) for s in self.components)

    def peak(self) -> float:
        """The largest magnitude (the magnitude of a linear ramp peaks at one of its ends)."""
        return float(max(math.sqrt(sum(c * c for c in v)) for v in self.values))

    def first_above(self, limit: float) -> float | None:
        """The first time [s] the magnitude exceeds `limit` (found to 1e-6 of an interval), or None."""
        norm = [math.sqrt(sum(c * c for c in v)) for v in self.values]
        if norm[0] > limit:
            return 0.0
        for k in range(1, len(self.times)):
            if norm[k] > limit:
                if self.components[0].mode(k - 1) == "hold":
                    return float(self.times[k])
                lo, hi = float(self.times[k - 1]), float(self.times[k])
                for _ in range(40):  # the magnitude is convex along a ramp: bisect on its first passing
                    mid = 0.5 * (lo + hi)
                    lo, hi = (lo, mid) if math.dist(self.at(mid), (0, 0, 0)) > limit else (mid, hi)
                return hi
        return None


class NonNegativeSchedule(Schedule):
    values: list[NonNegative] = Field(min_length=1)


class PositiveSchedule(Schedule):
    values: list[Positive] = Field(min_length=1)


def _branch(v) -> str:
    return "[schedule]" if isinstance(v, (dict, Schedule, VectorSchedule)) else "[number]"


def scheduled(number_type, schedule_type):
    """A key that takes one number or a schedule table; the branch is chosen by the input's form, so a
    bad value gets one message (not one per branch)."""
    return Annotated[Annotated[number_type, Tag("[number]")] | Annotated[schedule_type, Tag("[schedule]")],
                     Discriminator(_branch)]


ScheduledNumber = scheduled(Number, Schedule)
ScheduledNonNegative = scheduled(NonNegative, NonNegativeSchedule)
ScheduledPositive = scheduled(Positive, PositiveSchedule)
ScheduledVec3 = scheduled(tuple[Number, Number, Number], VectorSchedule)


Scheduled = float | tuple | Schedule | VectorSchedule | None
"""What a scheduled key holds after validation: a number (a vector), a schedule, or None where unset."""


def is_scheduled(x: Scheduled) -> bool:
    return isinstance(x, (Schedule, VectorSchedule))


def value_at(x: Scheduled, t: float):
    """A key's value at time t [s]."""
    return x.at(t) if is_scheduled(x) else x


def start(x: Scheduled):
    """A key's value at t = 0."""
    return value_at(x, 0.0)


def peak(x: Scheduled) -> float | None:
    """A number key's largest value over the run."""
    return x.peak() if isinstance(x, Schedule) else x


def lowest(x: Scheduled) -> float | None:
    """A number key's smallest value over the run."""
    return x.lowest() if isinstance(x, Schedule) else x


def largest_magnitude(x: Scheduled) -> float:
    """The largest |value| (a vector's length) over the run; 0 where unset."""
    if x is None:
        return 0.0
    if isinstance(x, VectorSchedule):
        return x.peak()
    if isinstance(x, Schedule):
        return float(max(abs(v) for v in x.values))
    return float(np.linalg.norm(x)) if isinstance(x, tuple) else abs(float(x))


def integral(x: Scheduled, t: float):
    """The integral of a key's value from 0 to t (per component for a vector)."""
    if is_scheduled(x):
        return x.integral(t)
    return tuple(float(c) * t for c in x) if isinstance(x, tuple) else float(x) * t


def first_above(x: Scheduled, limit: float) -> float | None:
    """The first time [s] the key (a vector's length) exceeds `limit` (0 for a constant above it), or None."""
    if isinstance(x, Schedule):
        return x.first_above(limit, magnitude=True)
    if isinstance(x, VectorSchedule):
        return x.first_above(limit)
    return 0.0 if x is not None and largest_magnitude(x) > limit else None


def scheduled_keys(table, prefix: str = "") -> list[tuple[str, Schedule | VectorSchedule]]:
    """(dotted key, schedule) of every key of a validated scene (or table) given as a schedule."""
    out = []
    for name in type(table).model_fields:
        value = getattr(table, name)
        key = f"{prefix}{name}"
        if is_scheduled(value):
            out.append((key, value))
        elif isinstance(value, Strict):
            out += scheduled_keys(value, key + ".")
        elif isinstance(value, (list, tuple)):
            out += [pair for i, item in enumerate(value) if isinstance(item, Strict)
                    for pair in scheduled_keys(item, f"{key}[{i}].")]
        elif isinstance(value, dict):
            out += [pair for k, item in value.items() if isinstance(item, Strict)
                    for pair in scheduled_keys(item, f"{key}.{k}.")]
    return out


def summary_line(key: str, schedule: Schedule | VectorSchedule) -> str:
    """`tidem check`'s line on one schedule: its form, its span in time and its values."""
    values = ", ".join(f"{v:g}" if not isinstance(v, tuple) else "[" + ", ".join(f"{c:g}" for c in v) + "]"
                       for v in schedule.values)
    span = f"{schedule.times[0]:g}..{schedule.times[-1]:g} s" if len(schedule.times) > 1 else f"{schedule.times[0]:g} s"
    modes = schedule.between if isinstance(schedule.between, str) else "/".join(schedule.between)
    return f"schedule: {key} {modes}s over {len(schedule.times)} point(s), {span}: {values}"


def hold_from(current: float | Schedule, t_last: float, t_new: float, value: float) -> Schedule:
    """The schedule of a key that followed `current` (a number or a schedule) up to the step at `t_last` and
    holds `value` from the next step, at `t_new` > t_last, on: the points of `current` before t_new (a ramp
    still under way at t_last ends there, at its value then), then `value` held. A run that follows it from
    the start takes `current`'s values at every step up to t_last (to rounding inside a ramp cut short) and
    `value` from t_new on."""
    if not isinstance(current, Schedule):
        current = Schedule(times=[0.0], values=[float(current)])
    kept = [k for k, tk in enumerate(current.times) if tk < t_new]
    times = [float(current.times[k]) for k in kept]
    values = [float(current.values[k]) for k in kept]
    modes = [current.mode(k) for k in kept[:-1]]
    last = kept[-1] if kept else -1
    if kept and not current._flat(last) and t_last > times[-1]:  # a ramp under way: it ends at t_last
        modes.append("ramp")
        times.append(float(t_last))
        values.append(current.at(t_last))
    if not times:  # t_new precedes the first point: the first value held until t_new
        times, values = [0.0], [float(current.values[0])]
    modes.append("hold")
    times.append(float(t_new))
    values.append(float(value))
    return Schedule(times=times, values=values, between=modes if "ramp" in modes else "hold")
