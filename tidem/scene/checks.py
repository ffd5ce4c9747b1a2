"""Checks that span several tables of a validated scene; each returns messages, never raises."""

from __future__ import annotations

import math
from itertools import combinations_with_replacement

from tidem.scene.heat_checks import heat_checks
from tidem.scene.schedule import is_scheduled
from tidem.scene.schema import Scene
from tidem.scene.sizes import (AVERAGING_GRAINS, gas_cell_counts, largest_diameter, largest_grain, max_diameter,
                               parcel_ratios)

AXES = "xyz"


def coarse_grain_checks(scene: Scene) -> list[str]:
    """Coarse-grained groups (a parcel of k d for k^3 grains; docs/design/coarse_graining.md):
    every model tidem has is scaled per grain, but conduction between parcels of different k
    has no consistent law (a pair's spot and lens scale with one k), so a scene with [heat]
    needs one k for all its groups."""
    ks = {g.coarse_grain for g in scene.particles}
    errors = parcel_restitution_checks(scene)
    if scene.heat is None or len(ks) == 1:
        return errors
    listed = ", ".join(f"particles[{i}].coarse_grain = {g.coarse_grain:g}" for i, g in enumerate(scene.particles))
    return errors + [f"particles[*].coarse_grain: with [heat] every group needs the same coarse_grain ({listed}); "
                     "conduction between parcels of different size ratios has no consistent scaling; give all groups "
                     "one value"]


def parcel_restitution_checks(scene: Scene) -> list[str]:
    """`contact.parcel_restitution = "kinetic_theory"` sets each pair of particle materials the restitution
    e_p = sqrt(1 - k (1 - e^2)) (`tidem.particles.contact_params.kinetic_theory_restitution`): one k per
    material, and k (1 - e^2) below 1, where e_p exists (nothing to check without contacts)."""
    k = parcel_ratios(scene)
    if not k:
        return []
    key = 'contact.parcel_restitution = "kinetic_theory"'
    errors = [f"particles[{i}].coarse_grain: with {key} the parcels of one material need one k "
              f"(materials.{g.material} has k = {k[g.material]:g} and {g.coarse_grain:g}); "
              "give the groups one coarse_grain or each its own material"
              for i, g in enumerate(scene.particles) if g.material in k and g.coarse_grain != k[g.material]]
    if errors:
        return errors
    mats = scene.materials
    for a, b in combinations_with_replacement(sorted(k), 2):
        e = 0.5 * (mats[a].restitution + mats[b].restitution)
        k_pair = 0.5 * (k[a] + k[b])
        if k_pair * (1 - e * e) >= 1.0:
            named = f"materials.{a}" if a == b else f"materials.{a} with materials.{b}"
            errors.append(f"particles[*].coarse_grain: with {key} parcels of k = {k_pair:g} and restitution "
                          f"{e:g} ({named}) have no restitution that dissipates what their "
                          f"grains do: k (1 - e^2) = {k_pair * (1 - e * e):.3g} must stay below 1; use "
                          f"coarse_grain below {1 / (1 - e * e):.3g} or contact.parcel_restitution = \"grains\"")
    return errors


def gas_checks(scene: Scene) -> list[str]:
    """The gas enters at the bottom and leaves at the top; cells must hold a few particles."""
    gas = scene.gas
    if gas is None:
        return []
    errs: list[str] = []
    dom = scene.domain
    if "z" in dom.periodic:
        errs.append("gas: the gas flows from the distributor (bottom) to the outlet (top); remove 'z' from domain.periodic")
    dmax = max_diameter(scene)
    counts = gas_cell_counts(scene)
    sizes = [(dom.max[a] - dom.min[a]) / counts[a] for a in range(3)]
    if min(sizes) < 2 * dmax:
        errs.append(f"gas.cell_size: cells of {min(sizes):g} m are smaller than 2 particle diameters ({2 * dmax:g} m), "
                    f"so the voidage is not a local average; use cell_size >= {3 * dmax:g} (about 3 diameters)")
    if gas.averaging_length not in (None, "cells"):
        own = 2 * max(h for h, n in zip(sizes, counts) if n > 1)  # eq. (1) of kernels/gas_smoothing.py
        if gas.averaging_length <= own:
            errs.append(f"gas.averaging_length: {gas.averaging_length:g} m is no longer than the averaging of the gas "
                        f"cells themselves (cloud-in-cell over two cells, {own:g} m), so it would change nothing; "
                        f"give more than {own:g} m, or remove the key for the default ({AVERAGING_GRAINS:g} grain diameters, "
                        f"{AVERAGING_GRAINS * largest_grain(scene):g} m, where longer than the cells' own)")
    for i, probe in enumerate(gas.pressure_probes):
        point = probe if isinstance(probe, tuple) else (None, None, probe)
        for a, value in enumerate(point):
            if value is not None and not dom.min[a] <= value <= dom.max[a]:
                errs.append(f"gas.pressure_probes[{i}]: {'xyz'[a]} = {value:g} m lies outside the domain's {'xyz'[a]} range "
                            f"{dom.min[a]:g}..{dom.max[a]:g} m; give the probe in the scene's coordinates")
        for j, tube in enumerate(scene.tubes if isinstance(probe, tuple) else []):
            across = [a for a in range(3) if AXES[a] != tube.axis]
            if math.dist([probe[a] for a in across], [tube.center[a] for a in across]) < 0.5 * tube.diameter:
                errs.append(f"gas.pressure_probes[{i}]: the point {list(probe)} lies inside tubes[{j}]; "
                            "place the probe in the gas, e.g. on the tube's surface or beside it")
    for i, nz in enumerate(gas.nozzles):
        for key, a in (("x", 0), ("y", 1)):
            r = getattr(nz, key)
            if r is not None and (r[0] < dom.min[a] or r[1] > dom.max[a]):
                errs.append(f"gas.nozzles[{i}].{key}: {list(r)} reaches outside the domain {dom.min[a]:g}..{dom.max[a]:g} m")
    scheduled = [key for key, value in [("gas.inlet_velocity", gas.inlet_velocity)] +
                 [(f"gas.nozzles[{i}].velocity", nz.velocity) for i, nz in enumerate(gas.nozzles)] if is_scheduled(value)]
    if gas.inlet_ramp > 0 and scheduled:
        errs.append(f"gas.inlet_ramp: {scheduled[0]} is a schedule, which holds the ramp itself; remove inlet_ramp "
                    "and start the schedule with the ramp, e.g. times = [0.0, 0.2], values = [0.0, 0.8]")
    if scene.heat is None and (gas.inlet_temperature is not None or gas.initial_temperature is not None):
        errs.append("gas: gas temperatures need a [heat] table (add '[heat]' to switch heat transfer on)")
    return errs


def observable_checks(scene: Scene) -> list[str]:
    """Observables the scene cannot give (e.g. pressure_drop without [gas])."""
    from tidem.scene.observable_names import requirement

    return [f"observables: '{name}' {need}" for name in scene.observables if (need := requirement(name, scene))]


def profile_checks(scene: Scene) -> list[str]:
    """The packed-bed profiles compare with Schumann's model: a fixed bed at one starting
    temperature, heated by a uniform gas stream switched on at t = 0 (the observable's own
    requirement, [heat] and [gas], is checked with the other observables)."""
    out = scene.output
    if "packed_bed_profiles" not in scene.observables:
        return [f"output.{key}: used only by the 'packed_bed_profiles' observable; add it to observables "
                "or remove the key" for key in ("profile_times", "profile_bins") if getattr(out, key) is not None]
    if scene.heat is None or scene.gas is None:
        return []
    key = "observables: 'packed_bed_profiles'"
    errs: list[str] = []
    moving = [g.name for g in scene.particles if not g.fixed]
    if moving:
        errs.append(f"{key} needs a fixed bed; set fixed = true in the particle groups {', '.join(moving)}")
    starts = {g.temperature or scene.heat.initial_temperature for g in scene.particles}
    if len(starts) > 1:
        errs.append(f"{key} needs every particle to start at one temperature (got {sorted(starts)} K)")
    if scene.gas.nozzles or scene.gas.inlet_ramp > 0 or is_scheduled(scene.gas.inlet_velocity):
        errs.append(f"{key} needs a uniform gas inlet switched on at once and held; remove gas.nozzles, "
                    "gas.inlet_ramp and any schedule of gas.inlet_velocity")
    if is_scheduled(scene.gas.inlet_temperature):
        errs.append(f"{key} compares with Schumann's model of a steady inlet temperature; give "
                    "gas.inlet_temperature as one number")
    return errs


def reaction_checks(scene: Scene) -> list[str]:
    """Each reaction names one particle group (one reaction per group) and has the phases it
    needs: heat for all, the gas for char combustion (with gas.oxygen) and sublimation."""
    errs: list[str] = []
    names = [g.name for g in scene.particles]
    seen: dict[str, int] = {}
    for i, r in enumerate(scene.reactions):
        key = f"reactions[{i}]"
        if r.group not in names:
            errs.append(f"{key}.group: no particle group named '{r.group}'; groups: {', '.join(names)}")
        elif r.group in seen:
            errs.append(f"{key}.group: group '{r.group}' already reacts in reactions[{seen[r.group]}]; one reaction per group")
        seen.setdefault(r.group, i)
        if scene.heat is None:
            errs.append(f"{key}: a {r.type} reaction needs a [heat] table (its heat goes into particle temperatures)")
        if r.type in ("char_combustion", "sublimation") and scene.gas is None:
            errs.append(f"{key}: a {r.type} reaction needs a [gas] table (it exchanges heat and species with the gas)")
        if r.type == "char_combustion" and scene.gas is not None and scene.gas.oxygen is None:
            errs.append(f"{key}: char combustion needs the oxygen the gas carries; add gas.oxygen = "
                        "{ mole_fraction = 0.21 }")
        if r.type == "polymerization" and r.growth and r.group in names:
            start = largest_diameter(scene.particles[names.index(r.group)].diameter)
            if r.max_diameter <= start:
                errs.append(f"{key}.max_diameter: {r.max_diameter:g} m is not above the group's largest diameter "
                            f"{start:g} m, so nothing could grow; raise it (e.g. {1.2 * start:.3g})")
        if r.type == "sublimation" and r.exit_height is not None:
            lo, hi = scene.domain.min[2], scene.domain.max[2]
            if not lo < r.exit_height <= hi:
                errs.append(f"{key}.exit_height: {r.exit_height} lies outside the domain's z range {lo}..{hi}")
    if scene.gas is not None and scene.gas.oxygen is not None and not any(
            r.type == "char_combustion" for r in scene.reactions):
        errs.append("gas.oxygen: only char combustion uses the oxygen; add a [[reactions]] table with "
                    "type = \"char_combustion\" or remove gas.oxygen")
    return errs


def no_contact_checks(scene: Scene) -> list[str]:
    """contact.model = 'none' (dilute, collision-free suspensions) has no walls to stop particles
    and no contact time to set the step."""
    if scene.contact.model != "none":
        return []
    errs = []
    if scene.domain.wall_sides():
        errs.append("contact.model: 'none' builds no contact forces, so particles would pass through the box walls; "
                    "set domain.walls = \"none\" (or choose a contact law)")
    for key in ("walls", "tubes", "meshes"):
        if getattr(scene, key):
            errs.append(f"{key}: contact.model = 'none' computes no wall, tube or mesh contacts; remove them or choose "
                        "a contact law")
    if scene.outlet is not None and scene.outlet.type == "moving_plate":
        errs.append("outlet: a moving plate needs contacts; remove it or choose a contact law")
    if scene.numerics.dt is None:
        errs.append("numerics.dt: contact.model = 'none' has no contact time to derive the step from; set numerics.dt "
                    "(e.g. a tenth of the drag relaxation time)")
    return errs


def averaging_checks(scene: Scene) -> list[str]:
    """Eq. 36 of source 3 (a particle counts where its centre lies) averages only over control
    volumes larger than a particle: cells and rings must exceed the largest diameter."""
    avg = scene.averaging
    if avg is None:
        return []
    from tidem.scene.averaging_layout import cell_grid

    errs: list[str] = []
    dmax = max_diameter(scene)
    _, sizes = cell_grid(scene)
    if min(sizes) <= dmax:
        errs.append(f"averaging.cell_size: cells of {sizes[0]:g} x {sizes[1]:g} m (x, z; rounded to fit the domain) "
                    f"are not larger than the largest particle diameter {dmax:g} m, so a cell is no local average "
                    f"(source 3 eq. 36); use cell_size >= [{2 * dmax:g}, {2 * dmax:g}] (2-3 diameters)")
    if avg.ring_width is not None and avg.ring_width < dmax:
        errs.append(f"averaging.ring_width: {avg.ring_width:g} m is less than the largest particle diameter {dmax:g} m "
                    f"(source 3 eq. 36); use ring_width >= {dmax:g} or leave it out (one diameter)")
    if not scene.tubes:
        errs += [f"averaging.{key}: ring sectors are averaged around tubes and the scene has none; remove the key"
                 for key in ("ring_width", "rings", "ring_sectors") if key in avg.model_fields_set]
    return errs


def tube_overlap_checks(scene: Scene) -> list[str]:
    """Tubes are solid cylinders: two may not overlap. Along one axis they overlap where their
    centre lines lie closer than the sum of the radii in the cross-section; an x tube and a y
    tube cross somewhere (both are infinite), so they overlap where their heights differ by less
    than the sum of the radii. On a periodic axis the nearest image counts."""
    dom = scene.domain
    errs: list[str] = []
    for i, a in enumerate(scene.tubes):
        for j in range(i + 1, len(scene.tubes)):
            b = scene.tubes[j]
            reach = 0.5 * (a.diameter + b.diameter)
            across = [k for k in range(3) if AXES[k] not in (a.axis, b.axis)]
            d = []
            for k in across:
                dk = b.center[k] - a.center[k]
                if AXES[k] in dom.periodic:
                    length = dom.max[k] - dom.min[k]
                    dk -= length * round(dk / length)
                d.append(dk)
            gap = sum(x * x for x in d) ** 0.5
            if gap < reach * (1 - 1e-9):
                how = ("their axes lie" if a.axis == b.axis else f"the {a.axis} and {b.axis} tubes cross, their "
                       "heights")
                errs.append(f"tubes[{i}] and tubes[{j}] overlap: {how} {gap:.4g} m apart, less than the sum of their "
                            f"radii {reach:.4g} m; move one (its center) or make them thinner")
    return errs


def mesh_checks(scene: Scene) -> list[str]:
    """What the [[meshes]] tables can be checked for without reading their files (the files
    are read by the Model: tidem.walls.mesh_load)."""
    errs = [f"particles[{i}].inside_mesh: there is no meshes[{g.inside_mesh}] ({len(scene.meshes)} [[meshes]] "
            f"in the scene)" for i, g in enumerate(scene.particles)
            if g.inside_mesh is not None and g.inside_mesh >= len(scene.meshes)]
    if scene.gas is not None:
        for k, m in enumerate(scene.meshes):
            if mesh_moves(m):
                errs.append(f"meshes[{k}]: a moving mesh in a scene with [gas] is not supported (the gas grid is cut "
                            "by the meshes once, at the start); remove its rotation/velocity (surface_velocity is "
                            "allowed) or the [gas] table")
            if m.temperature is not None and scene.heat is not None and scene.gas.tube_convection != "none" \
                    and m.convection_length is None:
                errs.append(f"meshes[{k}].convection_length: a heated mesh gives heat to the gas by "
                            f"gas.tube_convection = \"{scene.gas.tube_convection}\", whose bare-surface part needs "
                            "the length across the flow [m]: set it (the outer diameter of a tube drawn as a mesh), "
                            "or set gas.tube_convection = \"none\"")
    return errs


def mesh_moves(mesh) -> bool:
    """Whether a [[meshes]] entry rotates or translates at any time (a schedule counts, even one of zeros)."""
    speed = mesh.rotation.speed if mesh.rotation is not None else 0.0
    return is_scheduled(speed) or speed != 0.0 or is_scheduled(mesh.velocity) or any(mesh.velocity)


def cross_checks(scene: Scene) -> list[str]:
    """All problems that a single table cannot see, as 'key.path: message' lines."""
    errs: list[str] = []
    dom = scene.domain
    mats = scene.materials

    def need_material(path: str, name: str | None) -> None:
        if name is not None and name not in mats:
            errs.append(f"{path}: no material named '{name}'; defined: {', '.join(mats) or 'none'}")

    if not mats:
        errs.append("materials: define at least one material, e.g. [materials.sand]")
    need_material("domain.wall_material", dom.wall_material)
    if len(set(dom.periodic)) != len(dom.periodic):
        errs.append("domain.periodic: an axis is listed twice")
    if isinstance(dom.walls, list):
        for side in dom.walls:
            if side[0] in dom.periodic:
                errs.append(f"domain.walls: side '{side}' lies on the periodic axis {side[0]}; remove one of them")

    names = [g.name for g in scene.particles]
    for i, g in enumerate(scene.particles):
        p = f"particles[{i}]"
        if names.count(g.name) > 1:
            errs.append(f"{p}.name: '{g.name}' is used by more than one group")
        need_material(f"{p}.material", g.material)
        d = g.diameter
        if d.distribution == "uniform" and d.max <= d.min:
            errs.append(f"{p}.diameter: max ({d.max}) must be greater than min ({d.min})")
        if d.distribution in ("normal", "lognormal"):
            if d.sigma if d.distribution == "lognormal" else d.std:
                if d.max is None:
                    errs.append(f"{p}.diameter.max: a {d.distribution} distribution needs an upper cut-off 'max' (the neighbour search is sized from it)")
            if d.min is not None and d.max is not None and d.max <= d.min:
                errs.append(f"{p}.diameter: max ({d.max}) must be greater than min ({d.min})")
        for key, box in (("region", g.region), ("pour.region", g.pour.region if g.pour else None)):
            if box is not None and not dom.contains(box):
                errs.append(f"{p}.{key}: the box {list(box.min)}..{list(box.max)} reaches outside the domain {list(dom.min)}..{list(dom.max)}")
        for k, x in enumerate(g.positions or []):
            if any(c < lo or c > hi for c, lo, hi in zip(x, dom.min, dom.max)):
                errs.append(f"{p}.positions[{k}]: {list(x)} lies outside the domain")

    for i, w in enumerate(scene.walls):
        need_material(f"walls[{i}].material", w.material)
    for i, t in enumerate(scene.tubes):
        need_material(f"tubes[{i}].material", t.material)
        across = [a for a in range(3) if AXES[a] != t.axis]
        r = 0.5 * t.diameter
        for a in across:
            if AXES[a] in dom.periodic:
                continue
            if t.center[a] - r < dom.min[a] or t.center[a] + r > dom.max[a]:
                errs.append(
                    f"tubes[{i}] lies outside the domain: along {AXES[a]} it spans "
                    f"{t.center[a] - r:g}..{t.center[a] + r:g} m, the domain {dom.min[a]:g}..{dom.max[a]:g} m; "
                    "move its center or make it thinner"
                )
    for i, m in enumerate(scene.meshes):
        need_material(f"meshes[{i}].material", m.material)
    errs += tube_overlap_checks(scene)
    errs += mesh_checks(scene)
    if scene.outlet is not None:
        o = scene.outlet
        need_material("outlet.material", o.material)
        h = dom.min[2] if o.height is None else o.height
        if not dom.min[2] <= h <= dom.max[2]:
            errs.append(f"outlet.height: {h} lies outside the domain's z range {dom.min[2]}..{dom.max[2]}")
        if o.type == "recycle" and o.reinsert_height is not None and not dom.min[2] < o.reinsert_height < dom.max[2]:
            errs.append(f"outlet.reinsert_height: {o.reinsert_height} lies outside the domain's z range")
        if o.type == "moving_plate" and "z" in dom.periodic:
            errs.append("outlet: a moving plate needs a non-periodic z axis; remove 'z' from domain.periodic")
        if o.type == "moving_plate":
            stop = dom.min[2] if o.stop_height is None else o.stop_height
            if stop >= h:
                errs.append(f"outlet.stop_height: {stop} is not below the plate's start height {h}, so the plate "
                            "would never move; lower the domain's min z or set stop_height below height")
            elif stop < dom.min[2]:
                errs.append(f"outlet.stop_height: {stop} is below the domain (min z {dom.min[2]}); extend the domain")

    plate = scene.outlet is not None and scene.outlet.type == "moving_plate"
    sides = [s for s in dom.wall_sides() if not (plate and s == "z-")]
    n_surfaces = len(sides) + len(scene.walls) + len(scene.tubes) + plate
    if n_surfaces > 31:
        errs.append(f"walls and tubes: {n_surfaces} surfaces in all, at most 31 are supported; merge or drop some")

    errs += heat_checks(scene)
    errs += gas_checks(scene)
    errs += observable_checks(scene)
    errs += profile_checks(scene)
    errs += reaction_checks(scene)
    errs += no_contact_checks(scene)
    errs += averaging_checks(scene)
    errs += coarse_grain_checks(scene)

    dmax = max_diameter(scene)
    lens = 0.5 * scene.heat.fluid_layer if scene.heat is not None else 0.0  # the gas-lens reach (tidem.sim.model)
    cell = dmax * (1.0 + scene.numerics.skin + lens)
    for ax in dom.periodic:
        a = AXES.index(ax)
        length = dom.max[a] - dom.min[a]
        if dmax > 0 and length < 2 * cell:  # a particle would meet two images of one neighbour
            errs.append(
                f"domain.periodic: the domain is {length:g} m long along periodic axis {ax}, "
                f"less than twice the neighbour search reach ({2 * cell:g} m: the largest diameter times "
                f"1 + numerics.skin + half heat.fluid_layer); make it longer, lower numerics.skin or "
                f"drop '{ax}' from periodic"
            )
    return errs
