"""Live controls of a running bed, the run side: the conditions a run offers (`controls_for`), and
`Steering`, which empties the event queue (`tidem.runner.controls.Controls`) at step boundaries.

A `set` event takes effect at the run's next step:
the key holds the new value from that step's time on, whatever it followed before (its constant or its
schedule; `tidem.scene.schedule.hold_from`). A value past a limit that holds at the start (the gas
Courant number at the inlet, a mesh turning too fast for the step, a temperature not above 0 K) is
refused with the limit, and the run goes on as it was.

Every change is written to the run folder as it happens: steering.csv (time, key, value) and
scene_steered.toml, the scene (after --set) with each steered key given as the schedule the run
followed and the name `<name>_steered`, so that `tidem scene RUN/scene_steered.toml` runs the same
sequence again (bit for bit in float64, but for rounding inside a ramp that a change cut short).
"""

from __future__ import annotations

import copy
import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path

import tomli_w

from tidem.gas.geometry import gas_grid
from tidem.gas.limits import MAX_COURANT
from tidem.particles.timestep import impact_speed
from tidem.runner.controls import LOOKS, SHOWN, Controls, Event
from tidem.scene.load import apply_override
from tidem.scene.schedule import hold_from, value_at
from tidem.walls.mesh_walls import STEP_SHARE

WATCHED_STEPS = 5  # steps between two looks at the queue (and the view) while a run is watched
CSV_NAME = "steering.csv"
SCENE_NAME = "scene_steered.toml"


@dataclass(frozen=True)
class Control:
    """A condition a live control can change: its scene key, words and unit for the controls, the range a
    slider spans, and the hard limits a value must keep (None: none)."""

    key: str
    label: str
    unit: str
    value: float
    low: float
    high: float
    floor: float | None = None
    ceiling: float | None = None
    why: str = ""  # what the ceiling is


def controls_for(model) -> list[Control]:
    """The conditions of a model that live controls offer (see the module docstring)."""
    scene, out = model.scene, []
    if scene.gas is not None:
        gas = scene.gas
        gg = gas_grid(scene)
        courant = MAX_COURANT * min(gg.h) / (gas.coupling_interval * model.dt) * gas.min_voidage
        why = (f"the gas Courant limit {MAX_COURANT} at voidage {gas.min_voidage:g} with gas cells of "
               f"{min(gg.h):.3g} m and a gas step of {gas.coupling_interval * model.dt:.3g} s")
        parts = [("gas.inlet_velocity", "inlet velocity", gas.inlet_velocity)]
        parts += [(f"gas.nozzles[{i}].velocity", f"nozzle {i} velocity", nz.velocity) for i, nz in enumerate(gas.nozzles)]
        for key, label, u in parts:
            now = float(value_at(u, 0.0))
            out.append(Control(key, label, "m/s", now, 0.0, min(courant, max(3.0 * now, 0.1)), 0.0, courant, why))
        if scene.heat is not None:
            now = float(value_at(gas.inlet_temperature or scene.heat.initial_temperature, 0.0))
            out.append(_temperature("gas.inlet_temperature", "gas inlet temperature", now))
    if scene.heat is not None:
        if scene.domain.wall_temperature is not None:
            out.append(_temperature("domain.wall_temperature", "box wall temperature",
                                    value_at(scene.domain.wall_temperature, 0.0)))
        for name, items in (("walls", scene.walls), ("tubes", scene.tubes), ("meshes", scene.meshes)):
            out += [_temperature(f"{name}[{i}].temperature", f"{name[:-1]} {i} temperature", value_at(w.temperature, 0.0))
                    for i, w in enumerate(items) if w.temperature is not None]
    r_min = float(model.radius.min())
    for k, m in enumerate(model.meshes):
        if m.rotates and m.reach_from_axis() > 0:
            closing = 0.0 if model.fixed.all() else impact_speed(scene, model.v0)
            fastest = max((STEP_SHARE * r_min / model.dt - closing), 0.0) / m.reach_from_axis()
            now = m.speed_at(0.0)
            span = min(max(3.0 * abs(now), 1.0), fastest)
            out.append(Control(f"meshes[{k}].rotation.speed", f"mesh {k} rotation speed", "rad/s", now, -span, span,
                               -fastest, fastest, "a particle closing on the mesh by more than "
                               f"{STEP_SHARE:g} of the smallest radius in one step"))
    plate = next((p for p in model.planes if p["name"] == "outlet plate"), None)
    if plate is not None:
        now = -plate["vel"][2]
        out.append(Control("outlet.speed", "outlet plate speed", "m/s", now, 0.0, 3.0 * now, 0.0, None))
    return out


def _temperature(key: str, label: str, now: float) -> Control:
    return Control(key, label, "K", float(now), max(1.0, 0.5 * now), 2.0 * now, 0.0, None)


def refusal(control: Control, value: float) -> str | None:
    """Why `value` is refused for `control`, or None."""
    if not math.isfinite(value):
        return f"{control.key}: {value} is not a number"
    if control.floor is not None and (value < control.floor or (control.unit == "K" and value <= 0.0)):
        bound = "above" if control.unit == "K" else "at least"
        return f"{control.key} = {value:g} {control.unit} refused: it must be {bound} {control.floor:g} {control.unit}"
    if control.ceiling is not None and abs(value) > control.ceiling:
        return (f"{control.key} = {value:g} {control.unit} refused: above {control.ceiling:.4g} {control.unit}, "
                f"{control.why}")
    return None


class Steering:
    """The run side of the controls: applies the queued events at step boundaries and records each change."""

    def __init__(self, model, solver, out_dir: Path, controls: Controls, raw: dict, source: Path | None = None):
        self.model, self.solver, self.controls = model, solver, controls
        self.dir = Path(out_dir)
        self.raw = steered_raw(raw, source)
        self.raw["name"] = f"{model.name}_steered"
        self.table = {c.key: c for c in controls_for(model)}
        self.current = {c.key: _scene_value(model.scene, c.key) for c in self.table.values()}
        self.changes: list[tuple[float, str, float]] = []
        self.paused = False
        self.steps_granted = 0  # single steps asked for while paused
        self.display: dict[str, object] = {}  # the field, view and slice the views show, as last asked
        if not (self.dir / CSV_NAME).exists():
            (self.dir / CSV_NAME).write_text("time_s,key,value\n")

    def poll(self) -> None:
        """Apply every queued event."""
        for event in self.controls.take():
            self.apply(event)

    def apply(self, event: Event) -> None:
        if event.kind == "set":
            self.change(event.key, float(event.value))
        elif event.kind == "pause":
            self.paused = True
        elif event.kind == "resume":
            self.paused = False
        elif event.kind == "step":
            self.steps_granted += 1
        elif event.kind == "show" and event.value in SHOWN:
            self.display["field"] = event.value
        elif event.kind == "look" and event.value in LOOKS:
            self.display["view"] = event.value
        elif event.kind == "cut" and isinstance(event.value, (int, float)) and 0.0 <= event.value <= 1.0:
            self.display["slice"] = float(event.value)
        else:
            self.controls.messages.append(f"unknown control event {event.kind} {event.value!r}")

    def change(self, key: str, value: float) -> None:
        """`key` holds `value` from the next step on (or the change is refused, with a message)."""
        control = self.table.get(key)
        problem = (f"{key}: not a live control of this run (controls: {', '.join(self.table)})" if control is None
                   else refusal(control, value))
        if problem:
            self.controls.messages.append(problem)
            return
        solver = self.solver
        t_new = float(solver.t + solver.dt)  # the next step's time, as the solver will compute it
        schedule = hold_from(self.current[key], solver.t, t_new, value)
        try:
            solver.conditions.install(key, schedule)
        except ValueError as exc:
            self.controls.messages.append(str(exc))
            return
        self.current[key] = schedule
        self.changes.append((t_new, key, value))
        apply_override(self.raw, (key, schedule.model_dump()))
        with open(self.dir / CSV_NAME, "a", newline="") as f:
            csv.writer(f).writerow([repr(t_new), key, repr(value)])
        tmp = self.dir / (SCENE_NAME + ".tmp")
        tmp.write_text(f"# {self.model.name} as steered live: tidem scene {SCENE_NAME} runs it again\n"
                       + tomli_w.dumps(self.raw))
        tmp.replace(self.dir / SCENE_NAME)
        self.controls.applied.append((t_new, key, value))

    @property
    def holding(self) -> bool:
        """Paused with no single step asked for."""
        return self.paused and not self.steps_granted

    def hold(self, view, solver, stop) -> float:
        """While holding: keep the view drawn and the queue emptied until resumed, stepped or stopped
        (`stop.signal`); returns the seconds held."""
        start = time.perf_counter()
        while self.holding and stop.signal is None:
            if view is not None:
                view.update(solver, paused=True)
            for event in self.controls.take(timeout=0.05):
                self.apply(event)
        return time.perf_counter() - start

    def next_steps(self, due) -> int:
        """Steps to take now: one granted while paused, else up to the next output or WATCHED_STEPS."""
        if self.paused:
            self.steps_granted -= 1
            return 1
        return due(WATCHED_STEPS)


def _scene_value(scene, key: str):
    """The value (number or schedule) a validated scene gives a dotted key such as tubes[0].temperature."""
    node = scene
    for part in key.replace("]", "").replace("[", ".").split("."):
        node = node[int(part)] if part.isdigit() else getattr(node, part)
    return node


def steered_raw(raw: dict, source: Path | None) -> dict:
    """A copy of the raw scene whose mesh files are absolute paths, so that it runs from the run folder."""
    out = copy.deepcopy(raw)
    folder = Path(source).parent if source is not None else Path.cwd()
    for mesh in out.get("meshes", []):
        if "file" in mesh:
            mesh["file"] = str((folder / mesh["file"]).resolve())
    return out

