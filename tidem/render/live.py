"""Live view: a Taichi GUI window that shows the run while it goes on (`tidem scene --view`), with
its live controls.

Particles are drawn as discs projected on the plane of the scene's render view (front: x
right, z up; side: y right, z up; top: x right, y up; iso falls back to front), the nearest
drawn last, coloured by the run's field with the colour map and fixed range of its frames
(`tidem.render.settings`). Tubes (grey, with their periodic images), the domain outline, a
colour bar and the simulated time are drawn too. The window is redrawn at most `MAX_FPS` times
per second of wall time, with at most `MAX_POINTS` particles (a fixed random subset of a larger
bed), and never more often than keeps its drawing within `BUDGET` of the wall time (a redraw of
d seconds waits DISPLAY_SHARE d / BUDGET for the next: the display server draws it as well), so
drawing costs the run little.

Controls (`attach`): one slider per condition the run can change (`tidem.runner.steering.controls_for`:
the inlet velocity, heated tubes', walls' and meshes' temperatures, rotating meshes' speeds, the
outlet speed); moving one puts a `set` event in the run's queue. Keys: space pauses and resumes,
n (or the right arrow) takes one step while paused, f shows the next field, v the next view
(front, side, top), s the next slice (all, a quarter, a tenth of the depth about the middle), up and down pick a control and + and - raise or lower it by a twentieth of its
slider's span. Esc or closing the window ends the view and the run goes on headless. The last
message of the run (a refused value) is shown under the colour bar.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import time

import numpy as np

from tidem.render.frames import FIELDS, field_values, tube_images
from tidem.render.settings import default_range

MAX_FPS = 10
BUDGET = 0.03  # the share of wall time a view may take: after a refresh of d s, the next waits d / BUDGET s
DISPLAY_SHARE = 2.0  # the window's refresh costs as much again in the display server (another process): a
# window takes BUDGET / DISPLAY_SHARE in its own process (benchmarks/view_cost.py)
MAX_POINTS = 20_000  # particles drawn at most: a fixed random subset of a larger bed
MAX_PLOT = (960, 720)  # largest plot area [px]
MARGIN = 16  # px around the domain
TOP = 32  # px above the domain, for the time stamp
BAR = 120  # px of colour-bar panel right of the plot
PANEL = 210  # px right of the colour bar where Taichi draws the sliders (top right of the window)
SLIDER_H = 40  # px a slider takes
# (horizontal axis, vertical axis, depth axis, depth sign of the camera side) as in frames.place_camera
VIEW_AXES = {"front": (0, 2, 1, -1), "side": (1, 2, 0, 1), "top": (0, 1, 2, 1)}
KEYS_HELP = ["space: pause / resume", "n: one step (paused)", "f: next field", "v: next view", "s: slice",
             "up/down: pick a slider", "+ / -: move it"]
SLICES = (0.0, 0.25, 0.1)  # the slices the s key steps through: all, a quarter, a tenth of the depth
FIELD_CYCLE = ("temperature", "speed", "group", "radius", "contacts")
VIEW_CYCLE = ("front", "side", "top")


def display_problem() -> str | None:
    """Why no window can be opened here, or None when an X display answers."""
    name = os.environ.get("DISPLAY", "")
    if not name:
        return "no display ($DISPLAY is not set)"
    lib = ctypes.util.find_library("X11")
    if lib is None:
        return "no X11 library (libX11) to open a window"
    x11 = ctypes.CDLL(lib)
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    handle = x11.XOpenDisplay(name.encode())
    if not handle:
        return f"cannot open display '{name}'"
    x11.XCloseDisplay(handle)
    return None


def colour_table(colormap: str, n: int = 256) -> np.ndarray:
    """The colour map as n 0xRRGGBB integers."""
    import matplotlib

    rgb = (matplotlib.colormaps[colormap](np.linspace(0.0, 1.0, n))[:, :3] * 255).round().astype(np.uint32)
    return (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]


class LiveView:
    """The window; `update(solver)` draws when due and turns the window's keys and sliders into events."""

    def __init__(self, model, settings: dict):
        import taichi as ti

        self.ti = ti
        self.model = model
        self.settings = settings
        self.table = self.clim = None
        self.field = ""
        self._use_field(settings["field"], settings.get("range"), settings.get("colormap"))
        dom = model.scene.domain
        self.lo, self.hi = np.asarray(dom.min, float), np.asarray(dom.max, float)
        self.view = settings.get("view", "front") if settings.get("view", "front") in VIEW_AXES else "front"
        h, v = VIEW_AXES[self.view][:2]  # the window takes the first view's plot size and keeps it
        ext = self.hi - self.lo
        scale = min((MAX_PLOT[0] - 2 * MARGIN) / ext[h], (MAX_PLOT[1] - 2 * MARGIN) / ext[v])
        self.plot_w, self.plot_h = int(ext[h] * scale) + 2 * MARGIN, int(ext[v] * scale) + MARGIN + TOP
        self._use_view(self.view)
        self.res = (self.plot_w + BAR + PANEL, max(self.plot_h, 8 * SLIDER_H))
        self.gui = ti.GUI(f"tidem: {model.name}", res=self.res, background_color=0xFFFFFF)
        self.controls = self.steering = None
        self.sliders: list[tuple] = []  # (Control, slider widget, the value last sent)
        self.picked = 0
        self.slice = 0.0  # share of the depth shown about the middle (0: all)
        self.pick = shown_subset(model.capacity)
        self._next = -np.inf  # perf_counter time of the next redraw
        self._scene = None

    def _use_field(self, field: str, clim=None, colormap=None) -> None:
        self.field = field
        self.clim = tuple(clim) if clim else default_range(self.model, field)
        self.table = colour_table(colormap or FIELDS[field][1])

    def _use_view(self, view: str) -> None:
        """The view's axes and the scale that fits it into the window's plot."""
        self.view = view
        self.h, self.v, self.d, self.sign = VIEW_AXES[view]
        ext = self.hi - self.lo
        self.scale = min((self.plot_w - 2 * MARGIN) / ext[self.h], (self.plot_h - MARGIN - TOP) / ext[self.v])

    def attach(self, controls, steering) -> None:
        """Offer the run's live controls (`tidem.runner.steering`): sliders, and keys that put events in
        `controls`."""
        self.controls, self.steering = controls, steering
        for control in steering.table.values():
            widget = self.gui.slider(f"{control.label} [{control.unit}]", control.low, control.high,
                                     step=(control.high - control.low) / 200 or 1.0)
            widget.value = control.value
            self.sliders.append((control, widget, control.value))

    def to_window(self, p: np.ndarray) -> np.ndarray:
        """Plane coordinates (n, 3) [m] -> window coordinates (n, 2) in [0, 1]."""
        return np.stack([(MARGIN + (p[:, self.h] - self.lo[self.h]) * self.scale) / self.res[0],
                         (MARGIN + (p[:, self.v] - self.lo[self.v]) * self.scale) / self.res[1]], axis=1)

    def capture(self, solver) -> None:
        """Take the particles' positions, sizes and colours from the solver."""
        x, radius, colour = particles_coloured(solver, self.model, self.field, self.clim, self.table, self.pick,
                                               (self.d, self.slice))
        order = np.argsort(self.sign * x[:, self.d], kind="stable")  # far first, nearest last
        self._scene = (self.to_window(x[order]), radius[order] * self.scale, colour[order], solver.t)

    def draw(self, note: str = "") -> None:
        """Draw the last captured state and show it."""
        gui = self.gui
        pos, radius, colour, t = self._scene
        for tube in self.model.tubes:
            for c in tube_images(tube, self.lo, self.hi, self.model.grid.periodic):
                self._draw_tube(c, tube)
        if len(pos):
            gui.circles(pos, radius=np.maximum(radius, 1.0), color=colour)
        corners = self.to_window(np.array([self.lo, self.hi]))
        self._mask_outside(corners)
        gui.rect((corners[0, 0], corners[1, 1]), (corners[1, 0], corners[0, 1]), radius=1, color=0x000000)
        gui.text(f"t = {t:.4g} s", (corners[0, 0], 1.0 - 6 / self.res[1]), font_size=16, color=0x000000)
        self._draw_bar()
        if note:
            gui.text(note, ((self.plot_w + 8) / self.res[0], 0.1), font_size=14, color=0xC00000)
        if self.controls is not None:
            x = (self.plot_w + BAR + 8) / self.res[0]
            for row, line in enumerate(KEYS_HELP + ([f"+/- now: {self.sliders[self.picked][0].label}"] if self.sliders else [])):
                gui.text(line, (x, 0.3 - 0.03 * row), font_size=13, color=0x404040)
        gui.show()

    def _mask_outside(self, corners: np.ndarray) -> None:
        """Paint the window outside the domain white (tube images and periodic particles reach out)."""
        (x0, y0), (x1, y1) = corners
        boxes = np.array([[0, 0, 1, y0], [0, y1, 1, 1], [0, y0, x0, y1], [x1, y0, 1, y1]])
        a, c = boxes[:, :2], boxes[:, 2:]
        b, d = np.stack([c[:, 0], a[:, 1]], axis=1), np.stack([a[:, 0], c[:, 1]], axis=1)
        self.gui.triangles(np.vstack([a, a]), np.vstack([b, c]), np.vstack([c, d]), color=0xFFFFFF)

    def _draw_tube(self, centre: np.ndarray, tube: dict) -> None:
        r = tube["r"]
        if tube["mask"][self.d] == 0.0:  # seen end-on: a disc
            self.gui.circle(self.to_window(centre[None])[0], radius=r * self.scale, color=0x9A9A9A)
            return
        lo, hi = centre - r, centre + r  # seen side-on: a band across the domain
        axis = int(np.argmin(tube["mask"]))
        lo[axis], hi[axis] = self.lo[axis], self.hi[axis]
        a, b = self.to_window(np.array([lo, hi]))
        tri_a = np.array([[a[0], a[1]], [a[0], a[1]]])
        tri_b = np.array([[b[0], a[1]], [b[0], b[1]]])
        tri_c = np.array([[b[0], b[1]], [a[0], b[1]]])
        self.gui.triangles(tri_a, tri_b, tri_c, color=0x9A9A9A)

    def _draw_bar(self) -> None:
        gui, w = self.gui, self.res[0]
        n = len(self.table)
        x0, x1 = (self.plot_w + 20) / w, (self.plot_w + 45) / w
        y = 0.15 + 0.7 * np.arange(n + 1) / n
        a = np.stack([np.full(n, x0), y[:-1]], axis=1)
        c = np.stack([np.full(n, x1), y[1:]], axis=1)
        b = np.stack([np.full(n, x1), y[:-1]], axis=1)
        d = np.stack([np.full(n, x0), y[1:]], axis=1)
        gui.triangles(a, b, c, color=self.table)
        gui.triangles(a, c, d, color=self.table)
        lo, hi = self.clim
        gui.text(f"{hi:.3g}", (x1 + 0.01, 0.865), font_size=14, color=0x000000)
        gui.text(f"{lo:.3g}", (x1 + 0.01, 0.165), font_size=14, color=0x000000)
        gui.text(FIELDS[self.field][0], (x0 - 10 / w, 0.93), font_size=14, color=0x000000)

    def _keys(self) -> None:
        """Keys and sliders to events (module docstring); Esc or the window's close button ends the view."""
        ti, c = self.ti, self.controls
        for e in self.gui.get_events(ti.GUI.PRESS):
            if e.key == ti.GUI.ESCAPE:
                self.close()
                return
            if c is None:
                continue
            if e.key == ti.GUI.SPACE and self.steering.paused:
                c.resume()
            elif e.key == ti.GUI.SPACE:
                c.pause()
            elif e.key in ("n", ti.GUI.RIGHT):
                c.step()
            elif e.key == "f":
                c.show(_next(FIELD_CYCLE, self.field))
            elif e.key == "v":
                c.look(_next(VIEW_CYCLE, self.view))
            elif e.key == "s":
                c.cut(SLICES[(SLICES.index(self.slice) + 1) % len(SLICES)] if self.slice in SLICES else 0.0)
            elif e.key in (ti.GUI.UP, ti.GUI.DOWN) and self.sliders:
                self.picked = (self.picked + (1 if e.key == ti.GUI.DOWN else -1)) % len(self.sliders)
            elif e.key in ("+", "=", "-") and self.sliders:
                control, widget, _sent = self.sliders[self.picked]
                nudge = (control.high - control.low) / 20
                widget.value = widget.value + (nudge if e.key != "-" else -nudge)
        if self.gui is not None and not self.gui.running:
            self.close()
            return
        for i, (control, widget, sent) in enumerate(self.sliders):
            if widget.value != sent:
                c.set(control.key, widget.value)
                self.sliders[i] = (control, widget, widget.value)

    def _follow_display(self) -> None:
        """The field and view the controls asked for."""
        asked = self.steering.display if self.steering is not None else {}
        if asked.get("field", self.field) != self.field:
            self._use_field(asked["field"])
        if asked.get("view", self.view) != self.view:
            self._use_view(asked["view"])
        self.slice = asked.get("slice", self.slice)

    def update(self, solver, paused: bool = False) -> None:
        """Redraw when due (at most MAX_FPS a second); `paused`: the run is held by the controls."""
        if self.gui is None:
            return
        now = time.perf_counter()
        if now < self._next:
            return
        self._keys()
        if self.gui is None:
            return
        self._follow_display()
        self.capture(solver)
        notes = ["paused: space resumes, n steps"] if paused else []
        if self.controls is not None and self.controls.messages:
            notes.append(self.controls.messages[-1])
        self.draw(" | ".join(notes))
        self._next = next_refresh(now, now + DISPLAY_SHARE * (time.perf_counter() - now), paused)

    def close(self) -> None:
        if self.gui is not None:
            self.gui.close()
            self.gui = None


def next_refresh(start: float, end: float, paused: bool) -> float:
    """When a view that refreshed from `start` to `end` [perf_counter s] may refresh next: MAX_FPS, and
    within BUDGET of the wall time while the run goes (paused, only MAX_FPS)."""
    return start + max(1.0 / MAX_FPS, 0.0 if paused else (end - start) / BUDGET)


def shown_subset(capacity: int) -> np.ndarray | None:
    """The particles a view draws: all (None) up to MAX_POINTS, else a fixed random MAX_POINTS of them."""
    if capacity <= MAX_POINTS:
        return None
    return np.sort(np.random.default_rng(0).choice(capacity, MAX_POINTS, replace=False))


def particles_coloured(solver, model, field: str, clim, table: np.ndarray, pick: np.ndarray | None = None,
                       cut: tuple[int, float] | None = None):
    """(centres [n, 3], radii [n], colours 0xRRGGBB [n]) of the active particles (of those `pick` keeps, a
    sorted index array of the capacity; with `cut` = (axis, share) only those within share / 2 of the
    domain's depth along axis from its middle), coloured by `field` over the range `clim` with `table`."""
    S = solver.state
    active = S.active.to_numpy().astype(bool)
    idx = np.flatnonzero(active) if pick is None else pick[active[pick]]
    x = S.x.to_numpy()[idx]
    if cut is not None and cut[1] > 0.0:
        axis, share = cut
        lo, hi = model.scene.domain.min[axis], model.scene.domain.max[axis]
        inside = np.abs(x[:, axis] - 0.5 * (lo + hi)) <= 0.5 * share * (hi - lo)
        idx, x = idx[inside], x[inside]
    data = {"radius": S.radius.to_numpy()[idx]}
    if field == "speed":
        data["velocity"] = S.v.to_numpy()[idx]
    elif field == "temperature":
        data["temperature"] = S.T.to_numpy()[idx]
    elif field == "group":
        data["group"] = model.group[S.ident.to_numpy()[idx]]
    elif field == "contacts":
        data["contacts"] = S.ncontact.to_numpy()[idx]
    values = field_values(field, data)
    lo, hi = clim
    k = np.clip((values - lo) / (hi - lo), 0.0, 1.0) * (len(table) - 1)
    return x, data["radius"], table[k.round().astype(int)]


def _next(cycle: tuple, now: str) -> str:
    return cycle[(cycle.index(now) + 1) % len(cycle)] if now in cycle else cycle[0]
