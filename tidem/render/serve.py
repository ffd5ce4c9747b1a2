"""The browser view (`tidem scene SCENE --serve PORT`): the live view and its controls served on
localhost, for a machine without a display (a workstation reached over SSH: forward the port).

A server thread (Python's `http.server`, nothing to install) answers three requests:

- `GET /`: the page (`serve_page.html`): the bed in 3-D on a canvas (drag rotates, the wheel zooms,
  front/side/top buttons), coloured as the frames, with the time, a slider per live control
  (`tidem.runner.steering.controls_for`), pause, resume and step, the field, a slice about the
  middle of the view's depth, the changes made and the run's messages (a refused value);
- `GET /state`: the latest state as JSON (time, step, paused, field and range, each control's value,
  the changes in effect, the particles: centres and radii as base64 float32, colours as base64
  uint32, which the page decodes in one call each);
- `POST /event`: an event `{kind, key, value}` for the run's queue (`tidem.runner.controls.Controls`).

The state is taken on the run's thread, at most `MAX_FPS` times a second of wall time and only while
a page asks for it (within the last `IDLE_S` seconds), from at most `tidem.render.live.MAX_POINTS` particles (a fixed
random subset of a larger bed, `tidem.render.live.shown_subset`, so a 100 000-grain bed stays
responsive); the server thread only
hands out the last one.
"""

from __future__ import annotations

import base64
import json
import threading
import time
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources

import numpy as np

from tidem.render.frames import FIELDS
from tidem.render.live import VIEW_AXES, colour_table, next_refresh, particles_coloured, shown_subset
from tidem.render.settings import default_range
from tidem.scene.schedule import value_at

MAX_FPS = 5  # refreshes a second at most (and within tidem.render.live.BUDGET of the wall time)
IDLE_S = 2.0  # s without a request after which the run stops taking the state
KINDS = ("set", "pause", "resume", "step", "show", "look", "cut")


class ServeError(RuntimeError):
    """The port cannot be served (taken, or not allowed)."""


class BrowserView:
    """The served view; `update(solver)` takes the state for the page when due."""

    def __init__(self, model, settings: dict, port: int):
        self.model = model
        self.field = settings["field"]
        self.clim = tuple(settings.get("range") or default_range(model, self.field))
        self.table = colour_table(settings.get("colormap") or FIELDS[self.field][1])
        self.view = settings.get("view", "front")
        self.pick = shown_subset(model.capacity)
        self.controls = self.steering = None
        self._state = b"{}"
        self._lock = threading.Lock()
        self._next = -np.inf  # perf_counter time of the next capture
        self.asked = -np.inf  # when a page last asked for the state (perf_counter)
        page = resources.files("tidem.render").joinpath("serve_page.html").read_text()
        try:
            self.server = ThreadingHTTPServer(("127.0.0.1", port), _handler(self, page.encode()))
        except OSError as exc:
            raise ServeError(f"--serve {port}: cannot serve on 127.0.0.1:{port} ({exc.strerror or exc}); "
                             "choose another port, or 0 for a free one") from None
        self.port = self.server.server_address[1]
        self.url = f"http://127.0.0.1:{self.port}/"
        self._thread = threading.Thread(target=self.server.serve_forever, name="tidem-serve", daemon=True)
        self._thread.start()

    def attach(self, controls, steering) -> None:
        self.controls, self.steering = controls, steering

    def update(self, solver, paused: bool = False) -> None:
        """Take the state for the page when due (at most MAX_FPS a second)."""
        now = time.perf_counter()
        if now < self._next or (now - self.asked > IDLE_S and self._state != b"{}"):
            return
        asked = self.steering.display if self.steering is not None else {}
        if asked.get("field", self.field) != self.field:
            self.field = asked["field"]
            self.clim = default_range(self.model, self.field)
            self.table = colour_table(FIELDS[self.field][1])
        view = asked.get("view", self.view)
        share = float(asked.get("slice", 0.0))
        x, radius, colour = particles_coloured(solver, self.model, self.field, self.clim, self.table, self.pick,
                                               (VIEW_AXES.get(view, VIEW_AXES["front"])[2], share))
        state = {
            "name": self.model.name, "t": solver.t, "t_end": self.model.t_end, "steps": solver.steps,
            "paused": bool(paused), "field": self.field, "label": FIELDS[self.field][0], "range": list(self.clim),
            "colours": [f"#{int(c):06x}" for c in self.table[:: max(1, len(self.table) // 16)]],
            "view": view, "slice": share,
            "box": [list(self.model.scene.domain.min), list(self.model.scene.domain.max)],
            "shown": int(len(radius)), "active": int(solver.state.active.to_numpy().sum()),
            "controls": self._controls(solver.t),
            "applied": [list(c) for c in (self.controls.applied if self.controls is not None else [])],
            "messages": list(self.controls.messages[-3:]) if self.controls is not None else [],
            "x": _b64(x, np.float32), "r": _b64(radius, np.float32), "c": _b64(colour, np.uint32),
        }
        data = json.dumps(state).encode()
        with self._lock:
            self._state = data
        self._next = max(now + 1.0 / MAX_FPS, next_refresh(now, time.perf_counter(), paused))

    def _controls(self, t: float) -> list[dict]:
        if self.steering is None:
            return []
        return [{"key": c.key, "label": c.label, "unit": c.unit, "low": c.low, "high": c.high,
                 "value": float(value_at(self.steering.current[c.key], t))} for c in self.steering.table.values()]

    def state(self) -> bytes:
        self.asked = time.perf_counter()
        with self._lock:
            return self._state

    def event(self, message: dict) -> str | None:
        """Put a posted event in the queue; why not, or None."""
        kind = message.get("kind")
        if self.controls is None:
            return "this run takes no controls"
        if kind not in KINDS:
            return f"unknown event kind {kind!r} (one of {', '.join(KINDS)})"
        if kind == "set":
            try:
                self.controls.set(str(message["key"]), float(message["value"]))
            except (KeyError, TypeError, ValueError):
                return "a set event needs 'key' and a number 'value'"
        else:
            self.controls.put(kind, value=message.get("value"))
        return None

    def close(self) -> None:
        if self.server is not None:
            self.server.shutdown()
            self.server.server_close()
            self.server = None


def _b64(values: np.ndarray, dtype) -> str:
    """An array as base64 of its little-endian bytes (the page reads it as a typed array)."""
    return base64.b64encode(np.ascontiguousarray(values, dtype=np.dtype(dtype).newbyteorder("<")).tobytes()).decode()


def _handler(view: BrowserView, page: bytes):
    class Handler(BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802 - the http.server interface
            if self.path in ("/", "/index.html"):
                self._send(HTTPStatus.OK, page, "text/html; charset=utf-8")
            elif self.path.startswith("/state"):
                self._send(HTTPStatus.OK, view.state(), "application/json")
            else:
                self._send(HTTPStatus.NOT_FOUND, b"not found", "text/plain")

        def do_POST(self):  # noqa: N802
            if self.path != "/event":
                self._send(HTTPStatus.NOT_FOUND, b"not found", "text/plain")
                return
            try:
                message = json.loads(self.rfile.read(int(self.headers.get("Content-Length", 0))) or b"{}")
                problem = view.event(message) if isinstance(message, dict) else "expected a JSON object"
            except json.JSONDecodeError:
                problem = "expected JSON"
            if problem:
                self._send(HTTPStatus.BAD_REQUEST, problem.encode(), "text/plain")
            else:
                self._send(HTTPStatus.NO_CONTENT, b"", "text/plain")

        def _send(self, status, body: bytes, kind: str):
            self.send_response(status)
            self.send_header("Content-Type", kind)
            self.send_header("Cache-Control", "no-store")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            if body:
                self.wfile.write(body)

        def log_message(self, *_args):  # the terminal keeps the progress bar
            pass

    return Handler


class Views:
    """Several views of one run (`--view` and `--serve` together) as one."""

    def __init__(self, views: list):
        self.views = views

    def attach(self, controls, steering) -> None:
        for v in self.views:
            v.attach(controls, steering)

    def update(self, solver, paused: bool = False) -> None:
        for v in self.views:
            v.update(solver, paused)

    def close(self) -> None:
        for v in self.views:
            v.close()
