"""The checks of a scene's temperatures and heat across its tables (`tidem.scene.checks` gathers them):
temperatures need a [heat] table, heated particle materials their conductivity and heat capacity,
radiation the emissivities, and a temperature that looks like degrees Celsius gets a note."""

from __future__ import annotations

from tidem.scene.schedule import lowest
from tidem.scene.schema import Scene


def scene_temperatures(scene: Scene, fluxes: bool = False) -> list[tuple[str, float | None]]:
    """(key, value) of every temperature the domain, particle groups, walls, tubes and meshes set (None
    where unset; a schedule's lowest value); with `fluxes` each wall's and tube's heat_flux after its
    temperatures."""
    temps = [("domain.wall_temperature", scene.domain.wall_temperature)]
    temps += [(f"particles[{i}].temperature", g.temperature) for i, g in enumerate(scene.particles)]
    for name, items in (("walls", scene.walls), ("tubes", scene.tubes)):
        temps += [(f"{name}[{i}].temperature", w.temperature) for i, w in enumerate(items)]
        if fluxes:
            temps += [(f"{name}[{i}].heat_flux", w.heat_flux) for i, w in enumerate(items)]
    temps += [(f"meshes[{i}].temperature", m.temperature) for i, m in enumerate(scene.meshes)]
    return [(key, lowest(value)) for key, value in temps]


def heat_checks(scene: Scene) -> list[str]:
    """Temperatures need a [heat] table; heat needs conductivity and heat capacity of particles."""
    errs: list[str] = []
    temps = scene_temperatures(scene, fluxes=True)
    if scene.heat is None:
        if scene.render.field == "temperature":
            errs.append("render.field: 'temperature' needs a [heat] table (particles have no temperature without it)")
        errs += [f"{key}: temperatures need a [heat] table (add '[heat]' to switch heat transfer on)"
                 for key, value in temps if value is not None]
        return errs
    for name in sorted({g.material for g in scene.particles}):
        m = scene.materials.get(name)
        if m is None:
            continue
        for key in ("conductivity", "heat_capacity"):
            if getattr(m, key) is None:
                errs.append(f"materials.{name}.{key}: required with [heat] (particles of this material carry heat)")
    if scene.gas is not None:
        errs += [f"tubes[{i}].heat_flux: a heated-foil tube exchanges heat with the particles only, not with the "
                 "gas; in a scene with [gas] give the tube a fixed 'temperature' instead"
                 for i, t in enumerate(scene.tubes) if t.heat_flux is not None]
    if scene.heat.radiation:
        errs += radiation_checks(scene)
    return errs


COLD = 150.0  # K: a scene temperature below this is noted as possibly meant in degrees Celsius


def celsius_notes(scene: Scene) -> list[str]:
    """Notes on temperatures below COLD K, which look like degrees Celsius written where tidem reads kelvin
    (a note, not an error: a cryogenic bed is possible)."""
    if scene.heat is None:
        return []
    temps = [("heat.initial_temperature", scene.heat.initial_temperature), *scene_temperatures(scene)]
    if scene.gas is not None:
        temps += [("gas.inlet_temperature", lowest(scene.gas.inlet_temperature)),
                  ("gas.initial_temperature", scene.gas.initial_temperature)]
    return [f"{key} = {value:g} K; temperatures are in kelvin ({value:g} °C would be {value + 273.15:g} K)"
            for key, value in temps if value is not None and value < COLD]


def radiation_checks(scene: Scene) -> list[str]:
    """heat.radiation needs the emissivity of every particle material and of every heated surface."""
    default = scene.particles[0].material
    heated = [(f"particles[{i}]", g.material) for i, g in enumerate(scene.particles)]
    if scene.domain.wall_temperature is not None:
        heated.append(("domain", scene.domain.wall_material or default))
    heated += [(f"walls[{i}]", w.material or default) for i, w in enumerate(scene.walls)
               if w.temperature is not None or w.heat_flux is not None]
    heated += [(f"tubes[{i}]", t.material or default) for i, t in enumerate(scene.tubes)
               if t.temperature is not None or t.heat_flux is not None]
    errs = []
    for name in sorted({m for _, m in heated}):
        m = scene.materials.get(name)
        if m is not None and m.emissivity is None:
            users = ", ".join(who for who, mat in heated if mat == name)
            errs.append(f"materials.{name}.emissivity: required with heat.radiation = true (used by {users}); "
                        "give a value in (0, 1], e.g. 0.8 for sand, 0.3 for oxidised steel")
    return errs
