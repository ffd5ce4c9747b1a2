"""A scene's time per step by phase at several neighbour-list skins (`numerics.skin`), each from the same
developed state, the skins alternating over rounds: where the neighbour builds are a large part of a
bubbling bed's step, a wider skin trades builds for longer rows.

    python -P benchmarks/skin_profile.py SCENE RUN_DIR [STEPS [ROUNDS]] SKIN,SKIN,... [KEY=VALUE ...]

RUN_DIR holds a checkpoint of SCENE (made at any skin). For each skin the scene is built at that skin
(numerics.t_end raised past the checkpoint), the checkpoint's particles and gas are put into it, the
neighbour rows emptied (every skin then starts with the tangential springs at zero) and built anew. The first CHECK_STEPS steps check that the skin changes nothing but the order of sums: the
largest difference of any particle's position from the first skin's is printed (rounding, 1e-14 m or so;
a pair missed by a list would move its grains by a good part of an overlap). Then 100 warm-up steps and
STEPS timed ones (default 1500) are booked by phase as `tidem bench --profile --fused` does; ROUNDS
(default 2) repeats the skins in alternating order.
"""

import sys

import numpy as np

from tidem.cli.common import build_or_exit, load_scene, script_main
from tidem.runner import checkpoint
from tidem.runtime import startup
from tidem.studies.bench import profile_scene

CHECK_STEPS = 200


def fitted(arrays: dict, solver) -> dict:
    """The checkpoint's arrays in the shapes of `solver`'s fields: where the skin changed the row capacity or
    the slabs, zeros (the next build rewrites them); every row emptied."""
    copier = checkpoint._copier(solver)
    out = {}
    for name in copier.slots:
        shape = copier.shape(name)
        out[name] = arrays[name] if arrays[name].shape == shape else np.zeros(shape, arrays[name].dtype)
    out["state/nbr_n"] = np.zeros_like(out["state/nbr_n"])
    return out


def main(scene: str, run_dir: str, steps: int = 1500, rounds: int = 2, sets: list[str] = ()) -> None:
    try:
        skins, sets = [float(s) for s in sets[0].split(",")], list(sets[1:])
    except (IndexError, ValueError):
        sys.exit("skin_profile.py: give the skins as numbers after the run folder, e.g. 0.1,0.2,0.3")
    try:
        meta, arrays = checkpoint.load(run_dir)
    except checkpoint.CheckpointError as exc:
        sys.exit(f"skin_profile.py: {exc}")
    t_end = f"numerics.t_end={2.0 * meta['solver']['t'] + 1.0}"
    rows, checked = {}, {}

    def prepare(solver):
        checkpoint.restore(solver, meta, fitted(arrays, solver))
        solver.rebuild()  # the rows at this skin
        solver.advance(CHECK_STEPS)
        checked[solver.model.skin] = solver.state.x.to_numpy()[np.argsort(solver.state.ident.to_numpy())]

    for r in range(rounds):
        for skin in skins if r % 2 == 0 else skins[::-1]:
            loaded = load_scene(scene, [*sets, f"numerics.skin={skin}", t_end])
            startup.ensure_taichi("cpu", loaded.scene.numerics.precision, 2)
            model = build_or_exit(loaded)
            result = profile_scene(loaded, steps, 100, model, None, split=False, prepare=prepare)
            table = result["profile"]
            line = ", ".join(f"{k} {v['ms_per_step']:.3f}" for k, v in table.items() if v["ms_per_step"] >= 0.005)
            print(f"round {r + 1} skin {skin}: {line} ms/step", flush=True)
            if r == 0:
                x = list(checked.values())
                print(f"  after {CHECK_STEPS} steps the largest difference of a position from skin {skins[0]}'s: "
                      f"{np.abs(x[-1] - x[0]).max():.2e} m", flush=True)
            rows.setdefault(skin, []).append(table["total"]["ms_per_step"])
    base = np.mean(rows[skins[0]])
    for skin, totals in rows.items():
        print(f"skin {skin}: total {' / '.join(f'{t:.3f}' for t in totals)} ms/step, "
              f"{base / np.mean(totals):.3f}x the speed at skin {skins[0]}")


if __name__ == "__main__":
    script_main(main)
