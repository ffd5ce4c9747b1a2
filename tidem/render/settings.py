"""The render settings of a run, resolved before it starts, colour range included.

Frames are rendered while the run goes on, so the colour range has to be known before the
first frame; it is then stored in run.json, and `tidem render RUN_DIR` uses the same range,
so frames rendered during the run and afterwards are identical. The scene's `render.range`
wins; otherwise the range follows from the scene alone:

- temperature: lowest to highest temperature the scene sets (initial particle temperatures,
  fixed-temperature walls, tubes and mesh walls). Conduction without heat sources obeys the
  maximum principle, so no particle ever leaves this range.
- speed: 0 to the largest speed the scene sets or can give by falling: initial particle
  speeds, wall and outlet plate speeds, the fastest point of a moving mesh wall, and the
  free-fall speed sqrt(2 |g| H) over the domain's extent H along gravity.
- radius: smallest to largest radius; group: 0 to the last group; contacts: 0 to 12 (the
  kissing number of equal spheres).

A range of zero width (one temperature, one size) is widened by 5 % each side (or 1 unit at 0).
"""

from __future__ import annotations

import math

import numpy as np

from tidem.scene.schedule import lowest, peak

CONTACTS_MAX = 12.0


def _widened(lo: float, hi: float) -> tuple[float, float]:
    if hi > lo:
        return lo, hi
    pad = 0.05 * abs(lo) or 1.0
    return lo - pad, hi + pad


def default_range(model, field: str) -> tuple[float, float]:
    """Colour range of `field` from the scene alone (see the module docstring)."""
    scene = model.scene
    if field == "temperature":
        temps = list(model.temperature0) if model.temperature0 is not None else []
        temps += [s["T"] for s in model.planes + model.tubes if s.get("T") is not None]
        temps += [m.temperature for m in model.meshes if m.temperature is not None]
        temps += [f(s["T_schedule"]) for s in model.planes + model.tubes if s.get("T_schedule") for f in (lowest, peak)]
        temps += [f(m.schedules["temperature"]) for m in model.meshes if "temperature" in m.schedules
                  for f in (lowest, peak)]
        return _widened(float(min(temps, default=0.0)), float(max(temps, default=0.0)))
    if field == "speed":
        g = np.asarray(scene.domain.gravity, dtype=float)
        extent = np.asarray(scene.domain.max, dtype=float) - np.asarray(scene.domain.min, dtype=float)
        g_norm = float(np.linalg.norm(g))
        fall = math.sqrt(2.0 * g_norm * abs(float(extent @ g)) / g_norm) if g_norm > 0 else 0.0
        speeds = [float(np.linalg.norm(model.v0, axis=1).max(initial=0.0)), fall]
        speeds += [float(np.linalg.norm(p["vel"])) for p in model.planes]
        speeds += [peak(p["speed_schedule"]) for p in model.planes if p.get("speed_schedule") is not None]
        speeds += [m.max_speed() for m in model.meshes]
        return _widened(0.0, max(speeds))
    if field == "radius":
        return _widened(float(model.radius.min()), float(model.radius.max()))
    if field == "group":
        return _widened(0.0, float(len(scene.particles) - 1))
    return 0.0, CONTACTS_MAX


def render_settings(model) -> dict:
    """The scene's [render] table with the field and colour range resolved (stored in run.json)."""
    settings = model.scene.render.model_dump(exclude_none=True)
    settings.setdefault("field", "temperature" if model.features.heat else "speed")
    settings["range"] = list(settings.get("range") or default_range(model, settings["field"]))
    return settings
