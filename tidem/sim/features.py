"""What a scene needs compiled: the one place scene physics becomes kernel flags. The Solver
builds its kernels from these flags with `ti.static(...)` branches, so a scene without, say,
rolling friction compiles no rolling code (`kernels()` lists what a run compiles, in
run.json's `active_models` and `tidem check`).
"""

from __future__ import annotations

from dataclasses import dataclass

from tidem.kernels import contact_laws as cl
from tidem.scene.schedule import is_scheduled


@dataclass(frozen=True)
class Features:
    """What the scene needs compiled: the one place scene physics becomes kernel flags."""

    law: int
    rolling: bool
    hysteretic: bool
    n_planes: int
    n_tubes: int
    recycle: bool
    contact_time: bool
    precision: str
    heat: bool = False
    gas: bool = False
    reactions: tuple[str, ...] = ()  # reaction types, in scene order
    species: bool = False  # O2 transported on the gas grid (char combustion)
    packed_bed_profiles: bool = False
    radiation: bool = False  # grey radiation between heated surfaces and the particles touching them
    foil: bool = False  # a heated-foil tube (fixed heat flux) with its own temperature per angle bin
    wall_foil: bool = False  # a heated-foil plane wall (fixed heat flux), one temperature per wall
    growth: bool = False  # particles that grow (polymerization with growth)
    averaging: bool = False  # time-averaged fields in cells and ring sectors ([averaging])
    coarse_grain: bool = False  # parcels standing for k^3 grains (particles[i].coarse_grain > 1)
    sink: bool = False  # an outlet that removes particles below a height (counted)
    n_meshes: int = 0  # triangle-mesh walls ([[meshes]])
    moving_meshes: bool = False  # a mesh that rotates or translates (its triangles moved every step)
    scheduled_motion: bool = False  # a mesh whose rotation speed or velocity follows a schedule (host-set pose)
    scheduled_plate: bool = False  # an outlet plate whose speed follows a schedule (host-set position)

    @property
    def float_bytes(self) -> int:
        """Bytes of a float in the fields and kernels: 8, or 4 with numerics.precision = 'float32'."""
        return 4 if self.precision == "float32" else 8

    @property
    def history_bytes(self) -> int:
        """Bytes of a float in the Verlet rows' contact history and hand-over (springs, maximum
        overlap, the force and heat flow handed to the partner): 4 with 'float32' and 'mixed'."""
        return 8 if self.precision == "float64" else 4

    @property
    def contacts(self) -> bool:
        """False for contact.model = 'none': no neighbour search and no contact forces."""
        return self.law != cl.NONE

    def kernels(self) -> list[str]:
        """What a run with these flags compiles, in words (run.json's `active_models`)."""
        if self.contacts:
            law = {cl.LINEAR: "linear", cl.HERTZ: "hertz_mindlin", cl.HYSTERETIC: "hysteretic"}[self.law]
            out = ["integrate", "broadphase(cell grid + Verlet list)", f"contact({law}, tangential history)"]
        else:
            out = ["integrate", "no contacts (gravity and gas forces only)"]
        heat = ("heat (contact-spot conduction, gas-lens conduction between neighbours, wall/tube conduction "
                "after Schluender)" if self.contacts else "heat (particle temperatures; no conduction without contacts)")
        optional = [
            (self.rolling, "rolling resistance (model C)"),
            (self.n_planes, f"plane walls ({self.n_planes})"),
            (self.n_tubes, f"tubes ({self.n_tubes})"),
            (self.n_meshes, f"mesh walls ({self.n_meshes}" + (", moving)" if self.moving_meshes else ")")),
            (self.recycle, "outlet recycle"),
            (self.sink, "outlet sink (particles below a height leave, counted)"),
            (self.contact_time, "contact-time observer"),
            (self.packed_bed_profiles, "packed-bed temperature profiles (against Schumann)"),
            (self.heat, heat),
            (self.radiation, "radiation from heated walls and tubes to the particles touching them"),
            (self.foil, "heated-foil tubes (fixed heat flux, foil temperature per angle bin)"),
            (self.wall_foil, "heated-foil walls (fixed heat flux, one foil temperature per wall)"),
            (self.gas, "gas (voidage, drag, pressure projection" + (", gas energy)" if self.heat else ")")),
            (self.species, "O2 transport on the gas grid"),
            *[(True, f"reaction: {kind.replace('_', ' ')}") for kind in dict.fromkeys(self.reactions)],
            (self.growth, "particle growth (neighbour list rebuilt on growth + motion)"),
            (self.averaging, "local averaging (cells" + (", tube ring sectors)" if self.n_tubes else ")")),
            (self.coarse_grain, "coarse graining (parcels of k^3 grains, per-grain scaling)"),
        ]
        return out + [text for wanted, text in optional if wanted]


def scene_features(scene, n_planes: int, n_tubes: int, meshes=()) -> Features:
    """The flags of a validated scene with `n_planes` planes, `n_tubes` tubes and `meshes`
    (`tidem.walls.mesh_walls.MeshWall`)."""
    mats = scene.materials
    law = scene.contact.model
    contacts = law != "none"
    return Features(
        law=cl.LAW_IDS[law],
        rolling=any(m.rolling_friction > 0 for m in mats.values()),
        hysteretic=law == "hysteretic",
        n_planes=n_planes,
        n_tubes=n_tubes,
        recycle=scene.outlet is not None and scene.outlet.type == "recycle",
        contact_time="contact_time" in scene.observables,
        precision=scene.numerics.precision,
        heat=scene.heat is not None,
        gas=scene.gas is not None,
        reactions=tuple(r.type for r in scene.reactions),
        species=any(r.type == "char_combustion" for r in scene.reactions),
        packed_bed_profiles="packed_bed_profiles" in scene.observables,
        radiation=scene.heat is not None and scene.heat.radiation and contacts,
        foil=scene.heat is not None and any(t.heat_flux is not None for t in scene.tubes),
        wall_foil=scene.heat is not None and any(w.heat_flux is not None for w in scene.walls),
        growth=any(r.type == "polymerization" and r.growth for r in scene.reactions),
        averaging=scene.averaging is not None,
        coarse_grain=any(g.coarse_grain != 1.0 for g in scene.particles),
        sink=scene.outlet is not None and scene.outlet.type == "sink",
        n_meshes=len(meshes) if contacts else 0,
        moving_meshes=contacts and any(m.moving for m in meshes),
        scheduled_motion=contacts and any(m.schedules.keys() - {"temperature"} for m in meshes),
        scheduled_plate=scene.outlet is not None and is_scheduled(scene.outlet.speed),
    )
