"""The event queue of live controls: what the window (`tidem.render.live`), the browser view
(`tidem.render.serve`), a notebook or a test puts in, and the run loop takes out at step boundaries
(`tidem.runner.steering.Steering`). Thread-safe, and light to import (`tidem.Controls`).

Events: `set` (a scene key and a value: from the run's next step on the key holds it), `pause`,
`resume`, `step` (one step while paused), `show` (the field the views colour by), `look` (their
view) and `cut` (a slice: the share of the domain's depth along the view shown about its middle, 0
for all).
"""

from __future__ import annotations

import queue
from dataclasses import dataclass

SHOWN = ("temperature", "speed", "group", "radius", "contacts")
LOOKS = ("front", "side", "top")


@dataclass(frozen=True)
class Event:
    kind: str  # set, pause, resume, step, show, look, cut
    key: str = ""
    value: object = None


class Controls:
    """The event queue: thread-safe, so a browser's server thread may feed it while the run goes."""

    def __init__(self):
        self._queue: queue.Queue[Event] = queue.Queue()
        self.messages: list[str] = []  # what the run said back (a refused value), newest last
        self.applied: list[tuple[float, str, float]] = []  # (time, key, value) of each change in effect

    def put(self, kind: str, key: str = "", value=None) -> None:
        self._queue.put(Event(kind, key, value))

    def set(self, key: str, value: float) -> None:
        self.put("set", key, float(value))

    def pause(self) -> None:
        self.put("pause")

    def resume(self) -> None:
        self.put("resume")

    def step(self) -> None:
        self.put("step")

    def show(self, field: str) -> None:
        self.put("show", value=field)

    def look(self, view: str) -> None:
        self.put("look", value=view)

    def cut(self, share: float) -> None:
        self.put("cut", value=float(share))

    def take(self, timeout: float | None = None) -> list[Event]:
        """The events queued so far (waiting up to `timeout` s for a first one when given)."""
        out = []
        try:
            if timeout is not None:
                out.append(self._queue.get(timeout=timeout))
            while True:
                out.append(self._queue.get_nowait())
        except queue.Empty:
            return out
