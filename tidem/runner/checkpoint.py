"""Checkpoints: the complete state of a run in one file, written atomically, and resume.

`checkpoint.npz` in the run folder holds every Taichi field of the solver (particle state,
neighbour list with its tangential and rolling springs, wall and tube contact slots,
temperatures, tube heat-flux bins, gas fields) as arrays, and a JSON entry `meta` with what
lives in Python: time, step, rebuild count, the gas phase's counters, each pour group's
insert count and random-number state, the run loop's next snapshot and sample times, the
snapshot list, the number of time-series rows, and the scene (after `--set`) it was made
with. The file is written under a temporary name, flushed to disk and renamed over the
previous one, so a kill during the write leaves the previous checkpoint intact.

Restoring into a freshly built Solver of the same scene puts back every bit of that state,
so a resumed float64 run continues exactly as the uninterrupted run would have.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np
from taichi.lang.field import Field

from tidem.kernels.field_copy import FieldCopier

FILE = "checkpoint.npz"
# 2: each pair in its owner's row only, the slabs (kernels/broadphase.py); 3: slabs across gravity
# (kernels/geometry.py, slab_axis_for), which changes the owners of a bed's pairs
FORMAT = 3
# Scene keys that may change between a run and its resume: output cadence, rendering, the
# end time, the overlap limit of the health check (it stops a run, it never moves one) and the descriptive
# text. Anything else would make the continuation a different run.
RESUMABLE_KEYS = ("output.", "render.", "numerics.t_end", "numerics.max_overlap", "description", "runtime")
# Rewritten before use (the conduction flag by every force pass, the blocks' shares of the surfaces' heat
# flows by every pass that conducts, the reactions' gas book and their totals' rows (rbook) by every reaction step, `sums` by every energy sum and, in the gas, `sums` and the direct solve's band by every pressure
# solve, the rest by every neighbour build): not kept. The quiet partners' groups (nbr_touch, nbr_end, nbr_gap) are not kept
# either: a restored run evaluates every listed pair until its next build, which gives the same bits (kernels/pair_contact.py).
# Nor the host-set poses of scheduled meshes and the outlet plate (`tidem.sim.conditions`), set anew before each step's
# forces: a run with live controls resumes from a checkpoint of one without, and the other way round.
TRANSIENT = ("conduct", "gas_book", "rbook", "src", "nbr_new", "nbr_count", "slab_fill", "slab_next", "flips", "flip_ft", "flip_mr", "flip_dmax",
             "cell_count", "cell_start", "cell_fill", "cell_block", "sort_tail", "pcell", "sorted_idx", "sums", "worst", "worst_at",
             "nbr_touch", "nbr_end",
             "nbr_gap", "band", "band_y", "surf_rate_block", "tube_bin_block", "tube_route_block", "mesh_pose", "plane_shift", "plane_u")


class CheckpointError(RuntimeError):
    """A checkpoint is missing, unreadable, or does not belong to the scene given."""


def _fields(solver) -> dict[str, Field]:
    """Every Taichi field of the solver but the transient ones, by a stable name ('state/x',
    'gas/u/2', ...)."""
    out = {}
    for name, value in sorted(vars(solver.state).items()):
        if isinstance(value, Field) and name not in TRANSIENT:
            out[f"state/{name}"] = value
    if solver.gas is not None:
        for name, value in sorted(vars(solver.gas.G).items()):
            if isinstance(value, Field) and name not in TRANSIENT:
                out[f"gas/{name}"] = value
            elif isinstance(value, list):
                for c, comp in enumerate(value):
                    out[f"gas/{name}/{c}"] = comp
    return out


def _copier(solver) -> FieldCopier:
    """The host copier of every kept field (`kernels/field_copy.py`: one kernel launch per element
    type, not a compiled kernel per field and direction), made at the solver's first checkpoint."""
    if solver.field_copier is None:
        solver.field_copier = FieldCopier(_fields(solver))
    return solver.field_copier


def prepare(solver) -> None:
    """Compile the checkpoint's read by taking it once (a run's set-up: its first checkpoint then
    costs the copy and the file only)."""
    _copier(solver).read()


def _python_state(solver) -> dict:
    meta = {"t": solver.t, "steps": solver.steps, "rebuilds": solver.rebuilds, "profile_t0": solver.profile_t0,
            "mesh_t_build": solver.mesh_t_build, "mesh_t_binned": solver.mesh_t_binned}
    if solver.gas is not None:
        g = solver.gas
        meta["gas"] = {k: getattr(g, k) for k in ("steps", "iterations", "residual", "divergence", "inlet_scale")}
    if solver.pourer is not None:
        p = solver.pourer
        meta["pour"] = {"next_check": p._next_check,
                        "groups": [{"inserted": g["inserted"], "rng": g["rng"].bit_generator.state} for g in p.groups]}
    return meta


def save(run_dir: Path, solver, loop: dict, scene_raw: dict) -> Path:
    """Write the checkpoint of `solver` (and the run loop's state `loop`) atomically."""
    run_dir = Path(run_dir)
    arrays = _copier(solver).read()
    meta = {"format": FORMAT, "precision": solver.model.features.precision, "solver": _python_state(solver),
            "loop": loop, "scene": scene_raw}
    arrays["meta"] = np.frombuffer(json.dumps(meta, default=float).encode(), dtype=np.uint8)
    path = run_dir / FILE
    tmp = run_dir / (FILE + ".tmp")
    with open(tmp, "wb") as fh:
        np.savez(fh, **arrays)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    return path


def load(run_dir: Path) -> tuple[dict, dict]:
    """(meta, arrays) of the checkpoint in `run_dir`; CheckpointError if there is none."""
    path = Path(run_dir) / FILE
    if not path.is_file():
        raise CheckpointError(f"{run_dir}: no {FILE} here; a run writes one at the end, on Ctrl-C or SIGTERM, and "
                              "every output.checkpoint_wall_s seconds")
    try:
        with np.load(path) as data:
            arrays = {k: data[k] for k in data.files}
        meta = json.loads(arrays.pop("meta").tobytes().decode())
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise CheckpointError(f"{path}: unreadable checkpoint ({exc})") from None
    if meta.get("format") != FORMAT:
        raise CheckpointError(f"{path}: checkpoint format {meta.get('format')} is not {FORMAT} (made by another "
                              "version of tidem): start a new run, or resume it with the version that made it")
    return meta, arrays


def changed_keys(before: dict, after: dict, prefix: str = "") -> list[str]:
    """Dotted keys whose values differ between two raw scenes."""
    keys = []
    for k in sorted(set(before) | set(after)):
        a, b = before.get(k), after.get(k)
        name = f"{prefix}{k}"
        if isinstance(a, dict) and isinstance(b, dict):
            keys += changed_keys(a, b, name + ".")
        elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b) and a != b:
            for i, (x, y) in enumerate(zip(a, b)):
                if isinstance(x, dict) and isinstance(y, dict):
                    keys += changed_keys(x, y, f"{name}[{i}].")
                elif x != y:
                    keys.append(f"{name}[{i}]")
        elif a != b:
            keys.append(name)
    return keys


def check_scene(meta: dict, scene_raw: dict, precision: str) -> None:
    """Refuse to resume with a scene that differs from the checkpoint's outside RESUMABLE_KEYS."""
    bad = [k for k in changed_keys(meta["scene"], scene_raw)
           if not (k + ".").startswith(RESUMABLE_KEYS)]  # "render" itself: a [render] table added or dropped
    if bad:
        raise CheckpointError(
            f"the scene differs from the one the checkpoint was made with in {', '.join(bad)}; only output, render, "
            "numerics.t_end, numerics.max_overlap and the description may change on resume (start a new run to "
            "change the others)")
    if meta["precision"] != precision:
        raise CheckpointError(f"the checkpoint is {meta['precision']}, the scene asks for {precision}")


def restore(solver, meta: dict, arrays: dict) -> None:
    """Put the checkpoint's state into a Solver built from the same scene."""
    copier = _copier(solver)
    missing = sorted(set(copier.slots) - set(arrays))
    if missing:
        raise CheckpointError(f"the checkpoint lacks {', '.join(missing[:5])}: it was made with other physics or by "
                              "another version of tidem; start a new run")
    for name in copier.slots:
        if arrays[name].shape != copier.shape(name):
            raise CheckpointError(f"{name}: checkpoint shape {arrays[name].shape} does not match the scene's "
                                  f"{copier.shape(name)} (made by another version of tidem, or for other "
                                  "capacities): start a new run")
    copier.write(arrays)
    solver.state.nbr_gap.fill(0.0)  # no quiet partner skipped until the next neighbour build
    s = meta["solver"]
    solver.t, solver.steps, solver.rebuilds, solver.profile_t0 = s["t"], s["steps"], s["rebuilds"], s["profile_t0"]
    solver.mesh_t_build = s.get("mesh_t_build", 0.0)  # the last neighbour build, for the moving meshes
    solver.mesh_t_binned = s.get("mesh_t_binned", 0.0)  # when the moving meshes were last binned
    if solver.gas is not None:
        for k, v in s["gas"].items():
            setattr(solver.gas, k, v)
        solver.gas.sync_from_fields()  # the scheduled inlet and wall temperatures the host keeps
    solver.conditions.sync_from_fields()
    if solver.pourer is not None:
        p = solver.pourer
        p._next_check = s["pour"]["next_check"]
        for g, saved in zip(p.groups, s["pour"]["groups"]):
            g["inserted"] = saved["inserted"]
            g["rng"].bit_generator.state = saved["rng"]


def describe(meta: dict) -> str:
    s = meta["solver"]
    return f"t = {s['t']:.6g} s, step {s['steps']}"

