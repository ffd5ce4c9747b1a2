"""What `tidem check` prints beyond the model's own numbers: the parcels' restitution, the gas grid and how
its pressure is solved, the heated meshes' gas convection, and notes on settings a run would not honour as asked
(a gas grid too coarse for the bed, more snapshots than steps, an interval past t_end, a very long
run)."""

import math

from tidem.gas.geometry import (averaging_length, convection_walls, cut_share, cuts_tubes, gas_grid,
                                parcel_rows_max, staircase_share, voidage_layers)
from tidem.gas.tube_cut import tube_axis
from tidem.kernels.gas_band import band_width
from tidem.kernels.gas_smoothing import plan_filter
from tidem.particles.contact_params import kinetic_theory_restitution
from tidem.runner.output_size import cadence
from tidem.scene.sizes import AVERAGING_GRAINS, parcel_ratios

LONG_RUN = 100_000_000  # steps beyond which `tidem check` notes the run's length
SECTION_OFF = 0.1  # a tube blocking the gas more than this away from its section is noted


def parcel_restitution_text(scene) -> str:
    """`tidem check`'s words on the parcels' restitution under `contact.parcel_restitution = "kinetic_theory"`
    (each particle material with parcels: its e and the parcels' e_p); empty under "grains"."""
    parcels = {m: k for m, k in parcel_ratios(scene).items() if k != 1.0}
    shown = [f"{m} {scene.materials[m].restitution:g} -> {kinetic_theory_restitution(scene.materials[m].restitution, k):.3g} "
             f"(k = {k:g})" for m, k in parcels.items()]
    return f"; parcel restitution (kinetic theory): {', '.join(shown)}" if shown else ""


def cut_walls_text(model) -> str:
    """What cut the gas grid (`tidem check`'s line on the cut): the meshes, the tubes (`gas.tube_shape = "cut"`)
    or both."""
    tubes = "cut tubes" if cuts_tubes(model.scene) and model.tubes else ""
    return " and ".join(w for w in ("meshes" if model.meshes else "", tubes) if w)


def mesh_convection_lines(model) -> list[str]:
    """`tidem check`'s line per heated mesh that gives heat to the gas: the surface it shows the gas
    (`tidem.gas.mesh_convection`) against its area, and the cells that take it."""
    if model.scene.gas.tube_convection == "none" or model.gas_cut is None:
        return []
    walls = convection_walls(gas_grid(model.scene), model.tubes, model.meshes, model.gas_cut,
                             cuts_tubes(model.scene))
    lines = []
    for k, m in enumerate(model.meshes):
        if m.temperature is None:
            continue
        mine = (walls["wall_k"] == len(model.tubes) + k) & (walls["wall_A"] > 0) if walls is not None else False
        shown = float(walls["wall_A"][mine].sum()) if walls is not None else 0.0
        if shown == 0.0:
            lines.append(f"note: {m.name} gives the gas no heat: its surface lies in no gas cell of its own (cells "
                         "beside a heated tube are the tube's, and sealed cells have no gas)")
            continue
        lines.append(f"{m.name}: gives heat to the gas ({model.scene.gas.tube_convection}, length "
                     f"{m.convection_length:g} m) over {shown:.4g} m^2 in {int(mine.sum())} "
                     f"cells, {shown / m.stats['area']:.2f} x its area (1: a closed body, 2: a sheet in the gas)")
    return lines


def output_notes(model, snapshots: int) -> list[str]:
    """`tidem check`'s notes on output that will not be what the scene asks (at most one snapshot a step;
    an interval beyond t_end) and on a run of more than LONG_RUN steps."""
    out = model.scene.output
    steps = math.ceil(model.t_end / model.dt)
    asked = math.floor(model.t_end / cadence(model.scene, model.t_end)[0] + 1e-9)
    notes = []
    if asked > steps:
        notes.append(f"note: {asked} snapshots asked for, but a run writes at most one a step: {snapshots} in "
                     f"{steps} steps")
    if out.interval is not None and out.interval > model.t_end:
        notes.append(f"note: output.interval ({out.interval:g} s) is longer than t_end ({model.t_end:g} s): only "
                     "the snapshot at t = 0 is written (the final state is in checkpoint.npz)")
    if steps > LONG_RUN:
        notes.append(f"note: {steps:.3g} steps to t_end: at 1e7 particle-steps/s (2 CPU cores) about "
                     f"{steps * model.capacity / 1e7 / 86400:.3g} days; check numerics.dt and numerics.t_end")
    return notes


def gas_notes(model) -> list[str]:
    """`tidem check`'s notes on a gas grid too coarse to resolve the bed: fewer than 3 cells up, or one
    cell across a walled axis."""
    gg = gas_grid(model.scene)
    size = model.scene.gas.cell_size
    size = "[" + ", ".join(f"{h:g}" for h in size) + "]" if isinstance(size, tuple) else f"{size:g}"
    notes = [f"note: the gas grid has {gg.cells[2]} cell(s) up, so it does not resolve the bed's height; a smaller "
             f"gas.cell_size (now {size} m)"] if gg.cells[2] < 3 else []
    notes += [f"note: the gas grid has one cell across {'xy'[a]} between walls, so the gas flow does not resolve "
              f"it; a smaller gas.cell_size (now {size} m)" for a in range(2) if gg.cells[a] == 1 and not gg.periodic[a]]
    cut = model.gas_cut if cuts_tubes(model.scene) and model.tubes else None
    return notes + tube_section_notes(gg, model.tubes, cut)


def tube_section_notes(gg, tubes: list[dict], cut=None) -> list[str]:
    """`tidem check`'s note on the tubes that block the gas more than SECTION_OFF away from their section, and
    what would represent them better (one note per share): as the cells whose centre lies in them (the staircase,
    `gas.tube_shape = "cells"`), or cut into the grid (`cut`, "cut") where cells as wide as a tube seal it whole."""
    found: dict[tuple[str, bool], list[int]] = {}
    for k, tube in enumerate(tubes):
        share = staircase_share(gg, tube) if cut is None else cut_share(gg, tube, cut)
        if abs(share - 1.0) > SECTION_OFF:
            axis = tube_axis(tube)
            fine = 2.0 * tube["r"] >= 3.0 * max(gg.h[a] for a in range(3) if a != axis)
            found.setdefault((f"{share:.2f}", fine), []).append(k)
    notes = []
    for (share, fine), ks in found.items():
        if not fine:
            fix = "cells a third of the diameter or finer would resolve it"
        elif cut is None:
            fix = "gas.tube_shape = \"cut\" cuts the section into the cells (docs/design/cut_faces.md)"
        else:
            fix = "finer cells would resolve it"
        names = ", ".join(f"tubes[{k}]" for k in ks)
        one = len(ks) == 1
        if cut is None:
            shape = (f"{'is' if one else 'are'} the cells whose centre lies in {'it' if one else 'each'}, {share} "
                     "of the section on these cells")
        else:
            shape = (f"cut into these cells {'blocks' if one else 'block'} {share} of the section (the cells "
                     f"{'it' if one else 'each'} nearly fills are sealed whole)")
        notes.append(f"note: for the gas, {names} {shape}; {fix}")
    return notes


def gas_line(model) -> str:
    """`tidem check`'s line on the gas grid, the voidage its grains see and how the pressure is solved."""
    gas = model.scene.gas
    gg = gas_grid(model.scene)
    layers = voidage_layers(model)
    n = parcel_rows_max(model)
    rows = f" (one grain high; a parcel in up to {n} rows of its grains, gas.parcel_voidage)" if n > 1 else ""
    width = band_width(gg, cpu=True)
    cg = f"Jacobi-preconditioned CG (tolerance {gas.tolerance:g}, at most {gas.max_iterations} iterations)"
    solve = (f"directly on the CPU (banded Cholesky, half-bandwidth {width} cells), by {cg} on a GPU" if width else f"by {cg}")
    length = averaging_length(model.scene)
    key = "gas.averaging_length" if gas.averaging_length is not None else f"{AVERAGING_GRAINS:g} grain diameters, the default"
    if length is None:
        averaged = "averaged over two cells (the cells' own: gas.averaging_length = \"cells\")"
    elif plan_filter(gg.h, gg.cells, length) is None:
        averaged = f"averaged over two cells, already longer than the averaging length {length:g} m ({key})"
    else:
        drag = "; the drag and the gas velocity a grain reads too (gas.drag_averaging)" \
            if gas.drag_averaging == "length" else ""
        averaged = f"averaged over {length:g} m ({key}){drag}"
    return (f"gas: {'x'.join(map(str, gg.cells))} cells of {' x '.join(f'{h:.3g}' for h in gg.h)} m; voidage a grain "
            f"sees: {gas.voidage}" + (f", {layers} layers a cell" if layers > 1 else "") + rows + f", {averaged}; "
            f"pressure solved {solve}")
