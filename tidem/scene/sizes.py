"""Particle sizes a validated scene can produce, for checks and set-up alike."""

from __future__ import annotations

from tidem.scene.schema import Scene


def gas_cell_sizes(gas) -> tuple[float, float, float]:
    """`gas.cell_size` per axis [m]: one size for every axis, or [x, y, z]."""
    size = gas.cell_size
    return tuple(size) if isinstance(size, tuple) else (size, size, size)


def gas_cell_counts(scene) -> tuple[int, int, int]:
    """Gas cells per axis: a whole number (at least 1) of cells of about `gas.cell_size`."""
    dom = scene.domain
    return tuple(max(1, round((dom.max[a] - dom.min[a]) / h)) for a, h in enumerate(gas_cell_sizes(scene.gas)))


def largest_diameter(dist) -> float:
    """Largest diameter a size distribution can produce [m]: its cut-off (an open normal or
    log-normal, allowed only with zero spread, gives its mean or median)."""
    if dist.distribution == "mono":
        return dist.value
    if dist.distribution == "uniform":
        return dist.max
    if dist.max is not None:
        return dist.max
    return dist.mean if dist.distribution == "normal" else dist.median


def largest_parcel(group) -> float:
    """Largest simulated diameter of a group [m]: its largest grain times `coarse_grain` (a
    parcel of k d stands for k^3 grains of diameter d)."""
    return group.coarse_grain * largest_diameter(group.diameter)


def parcel_count(group) -> int | None:
    """Simulated particles of a group: its positions, or `count` grains in parcels of k^3
    grains (at least one), or None for a region filled to the brim."""
    if group.positions is not None:
        return len(group.positions)
    if group.count is None:
        return None
    return max(1, round(group.count / group.coarse_grain**3))


def parcel_ratios(scene: Scene) -> dict[str, float]:
    """{particle material: k of its groups} where parcels collide with the kinetic-theory restitution
    (`contact.parcel_restitution = "kinetic_theory"`, `tidem.particles.contact_params`; one k per material,
    `tidem.scene.checks.parcel_restitution_checks`); empty under "grains" and without contacts."""
    if scene.contact.parcel_restitution != "kinetic_theory" or scene.contact.model == "none":
        return {}
    ratios: dict[str, float] = {}
    for g in scene.particles:
        if g.material in scene.materials:  # an unknown one is named by the cross checks
            ratios.setdefault(g.material, g.coarse_grain)  # the first group's k; the checks name the others
    return ratios


AVERAGING_GRAINS = 12.0  # the default averaging length in grain diameters (docs/design/averaging_length.md, section 4)


def largest_grain(scene: Scene) -> float:
    """Largest grain diameter of the scene's groups [m] (the grains a parcel stands for, not the parcel; growing
    grains at their start)."""
    return max(largest_diameter(g.diameter) for g in scene.particles)


def max_diameter(scene: Scene) -> float:
    """Largest particle diameter the scene can simulate [m] (parcels at their coarse-grained
    size), growing particles at their cap (k times the grains' cap for parcels)."""
    groups = {g.name: g for g in scene.particles}
    grown = [(groups[r.group].coarse_grain if r.group in groups else 1.0) * r.max_diameter for r in scene.reactions
             if r.type == "polymerization" and r.growth]
    return max([largest_parcel(g) for g in scene.particles] + grown)
