"""The mesh tube of `mesh_tube.py` with the two faces its gas grid closes and the analytic tube's leaves open
(the bottom faces of the cells on the tube's lower flanks, gas cells (8, 0, 7) and (11, 0, 7): exactly 2 of
each face's 4 rays cross the 48-gon, and a face closes at half) opened again: a diagnostic of where the
mesh tube's difference from the analytic tube comes from (docs/validation.md, "A tube drawn as a mesh").

    python benchmarks/mesh_scenes/mesh_tube.py OUT 1 2 3                  (writes OUT/mesh_tube.toml first)
    python benchmarks/mesh_scenes/mesh_tube_open_faces.py OUT SEED         (one run: OUT/open_s<SEED>)

then `mesh_tube.heat_row` of each run (the table of `mesh_tube.py`), e.g. with `python -c`.
"""

import sys
from pathlib import Path

import tidem.gas_geometry as gas_geometry

FACES = ((8, 0, 7), (11, 0, 7))  # z-faces: bottom faces of those cells
closing_cut = gas_geometry.gas_cut


def cut_with_faces_open(*args, **kwargs):
    cut = closing_cut(*args, **kwargs)
    for face in FACES:
        assert cut.blocked[2][face], f"face {face} is open already: not fluidized_tube's grid"
        cut.blocked[2][face] = False
    return cut


def main(out: Path, seed: int) -> None:
    gas_geometry.gas_cut = cut_with_faces_open  # gas_walls calls it when the model holds no cut yet
    from tidem.cli import app

    sys.argv = ["tidem", "scene", str(out / "mesh_tube.toml"), "--no-render", "--quiet", "--set",
                f"particles[0].seed={seed}", "--out", str(out / f"open_s{seed}")]
    app()


if __name__ == "__main__":
    main(Path(sys.argv[1]), int(sys.argv[2]))
