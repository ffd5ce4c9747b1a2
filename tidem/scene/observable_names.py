"""The observable names a scene may declare (`observables = [...]`) and what each needs of the
scene (a heated tube, a gas phase). Scene validation reads this table; `tidem.results.observables`
registers one compute function under each name (a test checks that the two agree).
"""

from __future__ import annotations

import difflib
from typing import Callable


def _heated_tube(scene) -> str | None:
    if scene.heat is None or not any(t.temperature is not None or t.heat_flux is not None for t in scene.tubes):
        return "needs [heat] and a tube with a `temperature` or a `heat_flux`"
    return None


def _heat(scene) -> str | None:
    return None if scene.heat is not None else "needs [heat]"


def _gas(scene) -> str | None:
    return None if scene.gas is not None else "needs [gas]"


def _moving_bed_tube(scene) -> str | None:
    if scene.outlet is None or scene.outlet.type != "moving_plate":
        return "needs a moving_plate outlet (its speed is the bed speed)"
    return _heated_tube(scene)


def _sink(scene) -> str | None:
    return None if scene.outlet is not None and scene.outlet.type in ("sink", "recycle") else \
        "needs an [outlet] of type 'sink' or 'recycle' (it counts the particles that leave)"


def _heated_mesh(scene) -> str | None:
    if scene.heat is None or not any(m.temperature is not None for m in scene.meshes):
        return "needs [heat] and a mesh with a `temperature`"
    return None


def _closed_bed_under_gravity(scene) -> str | None:
    g = scene.domain.gravity
    if g[0] != 0.0 or g[1] != 0.0 or g[2] >= 0.0:
        return f"needs gravity along -z (domain.gravity is {list(g)})"
    if scene.outlet is not None or any(p.pour is not None for p in scene.particles):
        return "needs a bed whose mass stays the same: no [outlet] and no poured group"
    return None


def _vertical_open(scene) -> str | None:
    return "needs z not periodic (heights are followed across the snapshots)" if "z" in scene.domain.periodic else None


def _heat_and_gas(scene) -> str | None:
    return None if scene.heat is not None and scene.gas is not None else \
        "needs a [heat] and a [gas] table (a bed heated by the gas)"


NEEDS: dict[str, Callable | None] = {
    "tube_heat": _heated_tube,
    "tube_mean_alpha": _heated_tube,
    "bed_height": None,
    "centre_of_mass": _closed_bed_under_gravity,
    "outlet_mass_flow": None,
    "discharge_rate": _sink,
    "wall_heat_transfer": _heated_mesh,
    "mean_temperature": _heat,
    "contact_time": None,
    "restitution": None,
    "pressure_drop": _gas,
    "pressure_fluctuation": _gas,
    "kinetic_energy": None,
    "granular_temperature": None,
    "dispersion": _vertical_open,
    "impact_heat": _heat,
    "packet_model": _moving_bed_tube,
    "packed_bed_profiles": _heat_and_gas,
}
"""Every observable name, in the order listed to the user, with what it needs of a scene."""


def unknown_name_message(name: str) -> str | None:
    """None for a known name; otherwise the error text with the closest valid name."""
    if name in NEEDS:
        return None
    close = difflib.get_close_matches(name, list(NEEDS), n=1, cutoff=0.5)
    hint = f"did you mean '{close[0]}'?" if close else f"valid names: {', '.join(NEEDS)}"
    return f"unknown observable '{name}'; {hint}"


def requirement(name: str, scene) -> str | None:
    """What `scene` lacks for observable `name` (a sentence), or None."""
    needs = NEEDS.get(name)
    return needs(scene) if needs is not None else None
