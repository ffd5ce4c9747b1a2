#!/usr/bin/env python3
"""The whole pressure drop of a settled bed at low gas speed against Ergun integrated over the
bed's own voidage profile.

A periodic column (12 x 12 mm, 50 mm high) of 1 mm grains is filled on a lattice, let fall and
settle on the distributor (0.25 s, no gas); the settled grains are then fixed and air blows through
them at U = 0.1 m/s (about u_mf / 5) for 30 gas steps, at each gas cell size given, with each
`gas.voidage` ("cell" and "layered"). The reference is
Ergun's gradient at the voidage of thin horizontal slices of the bed (exact sphere slices, bins of
d/2 and of d/20), integrated over the height; the simulated drop is the mean inlet pressure less
the gas column's weight rho_g g H. Per pair of cell centres the script also prints the simulated
drop beside the reference over the same height, which shows where a shortfall lies (the bed
surface, the distributor layer).

Usage (from the repository root): python benchmarks/whole_bed_ergun.py [cell sizes in m ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tidem.analytic.ergun import ergun_gradient, whole_bed_ergun  # noqa: E402
from tidem.analytic.ergun import slice_voidage as tidem_slices  # noqa: E402

MU, RHO, D, U = 1.8e-5, 1.2, 0.001, 0.1
SAND = {"density": 2500.0, "youngs_modulus": 2e6, "poisson_ratio": 0.3, "restitution": 0.3, "friction": 0.3}
L = (0.012, 0.012, 0.05)


def column(**tables) -> dict:
    from tests.conftest import make_scene

    return make_scene(domain={"min": [0, 0, 0], "max": list(L), "periodic": ["x", "y"], "walls": ["z-"],
                              "gravity": [0, 0, -9.81]}, materials={"sand": SAND}, **tables)


def settle() -> np.ndarray:
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    raw = column(particles=[{"name": "bed", "material": "sand", "diameter": {"value": D}, "seed": 3,
                             "region": {"min": [0, 0, 0], "max": [L[0], L[1], 0.03]}}],
                 numerics={"max_overlap": 0.1})
    s = Solver(build_model(validate(raw)))
    while s.t < 0.25:
        s.step()
    x = s.state.x.to_numpy()[: s.n].copy()
    s.release()
    return x


def ergun(eps):
    return ergun_gradient(eps, U, D, MU, RHO)


def slice_voidage(x: np.ndarray, dz: float) -> np.ndarray:
    return tidem_slices(x[:, 2], D, L[0] * L[1], L[2], dz)


def reference(x: np.ndarray, dz: float) -> float:
    return whole_bed_ergun(x[:, 2], D, L[0] * L[1], L[2], U, MU, RHO, dz)


def blow(x: np.ndarray, cell: float, voidage: str = "layered"):
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    raw = column(particles=[{"name": "bed", "material": "sand", "diameter": {"value": D}, "fixed": True,
                             "positions": x.tolist()}],
                 gas={"cell_size": cell, "inlet_velocity": U, "coupling_interval": 1, "voidage": voidage},
                 numerics={"dt": 1e-4, "force_dt": True})
    s = Solver(build_model(validate(raw)))
    for _ in range(30):
        s.step()
    dp = s.gas.pressure_drop() - RHO * 9.81 * L[2]
    p = s.gas.G.p.to_numpy().mean(axis=(0, 1))
    eps = s.gas.G.eps.to_numpy().mean(axis=(0, 1))
    s.release()
    return dp, p, eps


def main(cells: list[float]) -> None:
    import taichi as ti

    ti.init(arch=ti.cpu, default_fp=ti.f64, cpu_max_num_threads=2, log_level=ti.ERROR)
    x = settle()
    half, fine = reference(x, D / 2), reference(x, D / 20)
    print(f"{len(x)} grains settled, top centre at {x[:, 2].max() * 1e3:.2f} mm; Ergun over the slice voidage: "
          f"{half:.2f} Pa (bins of d/2), {fine:.2f} Pa (d/20)")
    print("| gas cell | gas.voidage | simulated drop [Pa] | / Ergun (d/2 bins) | / Ergun (d/20 bins) |")
    print("|---|---|---|---|---|")
    profiles = {}
    for cell in cells:
        for voidage in ("cell", "layered"):
            dp, p, eps = blow(x, cell, voidage)
            profiles[cell, voidage] = (p, eps)
            print(f"| {cell * 1e3:g} mm ({cell / D:g} d) | {voidage} | {dp:.2f} | {dp / half:.3f} | {dp / fine:.3f} |")
    cell = max(cells)
    p, eps = profiles[cell, "layered"]
    h = L[2] / len(p)
    z_fine = (np.arange(int(round(L[2] / (D / 20)))) + 0.5) * D / 20
    eps_fine = slice_voidage(x, D / 20)
    print(f"\nper pair of cell centres, {cell * 1e3:g} mm cells, layered (cell voidage in brackets):")
    for k in range(len(p) - 1):
        if eps[k] > 0.99:
            break
        sel = (z_fine >= (k + 0.5) * h) & (z_fine < (k + 1.5) * h)
        sim = p[k] - p[k + 1] - RHO * 9.81 * h
        print(f"  {(k + 0.5) * h * 1e3:5.1f}-{(k + 1.5) * h * 1e3:5.1f} mm ({eps[k]:.3f}, {eps[k + 1]:.3f}): simulated "
              f"{sim:.2f} Pa, Ergun {float(ergun(eps_fine[sel]).sum() * D / 20):.2f} Pa")


if __name__ == "__main__":
    main([float(a) for a in sys.argv[1:]] or [0.002, 0.003, 0.004])
