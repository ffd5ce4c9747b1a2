#!/usr/bin/env python3
"""The rotating drum of `shared/bench/peers/` (drum.stl: radius 0.05 m along y, 15 mm long, 96
facets, 4 lifters; about 45 000 spheres of 1 mm, the peer bed's material; turning at 3 rad/s)
for tidem, from the state LIGGGHTS settled, so that both codes time the same steps from the same
state (`drum_side_by_side.sh`).

    python drum_peer.py data DUMP OUT.data       # LIGGGHTS data file of a dump (for drum_timed.lgt)
    python drum_peer.py time DUMP STL NWARM NSTEPS [THREADS]

`time` builds the drum scene in tidem (float64, dt 1e-6 s, skin 0.1 d, end walls y = 0 and
y = 0.015 m as analytic walls, the mesh turning about the y axis at 3 rad/s from t = 0, as
LIGGGHTS' move/mesh does from the start of its warm-up), takes NWARM steps, then times NSTEPS
and prints the particle-steps per second, the neighbour builds and the kinetic energy at the end
(LIGGGHTS' `ke` in its last thermo line: the two runs should agree to a few per cent).
"""

from __future__ import annotations

import sys
import time

import numpy as np

DENSITY, RADIUS, OMEGA = 2600.0, 0.0005, 3.0
LO, HI = (-0.052, 0.0, -0.052), (0.052, 0.015, 0.052)


def read_dump(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities [N, 3] of a LIGGGHTS custom dump (id type radius x y z vx vy vz)."""
    lines = open(path).read().splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("ITEM: ATOMS"))
    cols = lines[head].split()[2:]
    rows = np.array([line.split() for line in lines[head + 1:] if line.strip()], float)
    rows = rows[np.argsort(rows[:, cols.index("id")])]
    pick = lambda names: rows[:, [cols.index(c) for c in names]]  # noqa: E731
    return pick(("x", "y", "z")), pick(("vx", "vy", "vz"))


def write_data(dump: str, out: str) -> None:
    x, v = read_dump(dump)
    with open(out, "w") as f:
        f.write(f"drum state from {dump}\n\n{len(x)} atoms\n1 atom types\n\n")
        for a, name in enumerate("xyz"):
            f.write(f"{LO[a]:.9g} {HI[a]:.9g} {name}lo {name}hi\n")
        f.write("\nAtoms\n\n")
        for k, p in enumerate(x, 1):
            f.write(f"{k} 1 {2 * RADIUS:.9g} {DENSITY:.9g} {p[0]:.12g} {p[1]:.12g} {p[2]:.12g}\n")
        f.write("\nVelocities\n\n")
        for k, u in enumerate(v, 1):
            f.write(f"{k} {u[0]:.12g} {u[1]:.12g} {u[2]:.12g} 0 0 0\n")
    print(out, len(x), "atoms")


def drum_scene(x: np.ndarray, v: np.ndarray, stl: str) -> dict:
    return {
        "name": "drum_peer",
        "domain": {"min": list(LO), "max": list(HI), "walls": ["y-", "y+"], "gravity": [0.0, 0.0, -9.81]},
        "contact": {"model": "hertz_mindlin"},
        "materials": {"glass": {"density": DENSITY, "youngs_modulus": 1e7, "poisson_ratio": 0.3,
                                "restitution": 0.5, "friction": 0.5}},
        "particles": [{"name": "bed", "material": "glass", "diameter": {"distribution": "mono", "value": 2 * RADIUS},
                       "positions": x.tolist(), "velocities": v.tolist()}],
        "meshes": [{"file": stl, "rotation": {"center": [0.0, 0.0, 0.0], "axis": [0.0, 1.0, 0.0], "speed": OMEGA}}],
        "numerics": {"dt": 1e-6, "precision": "float64", "skin": 0.1},
    }


def time_tidem(dump: str, stl: str, nwarm: int, nsteps: int, threads: int) -> None:
    from tidem.runtime.startup import ensure_taichi

    ensure_taichi("cpu", "float64", threads)
    import taichi as ti

    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver
    from tidem.studies.bench import advance

    x, v = read_dump(dump)
    solver = Solver(build_model(validate(drum_scene(x, v, stl), "<drum>")))
    advance(solver, nwarm)
    ti.sync()
    builds = solver.rebuilds
    t0 = time.perf_counter()
    advance(solver, nsteps)
    ti.sync()
    loop = time.perf_counter() - t0
    print(f"tidem: {solver.n} particles, {nsteps} steps in {loop:.2f} s = {solver.n * nsteps / loop:.3g} "
          f"particle-steps/s, {solver.rebuilds - builds} neighbour builds, {threads} threads; kinetic energy at "
          f"the end {solver.energies()['kinetic_energy_J']:.4g} J")


if __name__ == "__main__":
    if sys.argv[1] == "data":
        write_data(sys.argv[2], sys.argv[3])
    else:
        time_tidem(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]),
                   int(sys.argv[6]) if len(sys.argv) > 6 else 2)
