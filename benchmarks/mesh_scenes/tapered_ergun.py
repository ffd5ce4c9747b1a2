"""Tapered packed beds between mesh walls against the one-dimensional Ergun integral, by gas cell size.

    python benchmarks/mesh_scenes/tapered_ergun.py [CELL ...] [--grain D] [--case NAME ...]
        (cells in m, default 0.004 0.003 0.002; grains of D m, default 0.001; cases, default all four)

Fixed grains (1 mm, or --grain) on a cubic lattice, air at 0.3 m/s over the inlet, 20 gas steps; the pressure drop
against `tidem.analytic.ergun.tapered_bed_ergun` (Ergun's gradient at each layer's voidage and at the
flow over the open cross-section there, plus the gas's weight), the flow read on the outlet faces:
- wedge: the bed of tests/gas/test_mesh.py (two plates leaning 11.3 degrees, a 24 mm slot, a 4 mm slab);
- channel: the same with the plates upright, 24 mm apart (a straight channel of mesh walls);
- cone: a 64-facet truncated cone from r = 12 mm on the distributor to 24 mm at 80 mm, with a lid from its
  rim to the side walls (so no gas passes outside it), filled up to 50 mm (`inside_mesh`), 35 000 grains;
- column: a square column 24 mm wide of box walls, no mesh (the reference of the method itself).
Prints one line per case and cell size: grains, drop, integral, ratio, and the share of the grains' volume
the gas holds (cells a mesh cuts to less than half are dropped, and so is the grains' volume in them).
"""

import argparse
import math
import sys
from pathlib import Path
from tempfile import TemporaryDirectory

import numpy as np
import pyvista as pv

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from tests.gas.test_mesh import tapered_drop, wedge_bed  # noqa: E402
from tidem.runtime.startup import ensure_taichi  # noqa: E402

CASES = ("wedge", "channel", "cone", "column")
R0, R1, H, FACETS, HALF = 0.012, 0.024, 0.08, 64, 0.026
SAND = {"density": 2500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3, "restitution": 0.9, "friction": 0.3}
GAS = {"inlet_velocity": 0.3, "coupling_interval": 1, "density": 1.2, "viscosity": 1.8e-5}


def polygon_area(r):
    return 0.5 * FACETS * r * r * math.sin(2 * math.pi / FACETS)


def cone_mesh(path: Path) -> None:
    """The truncated cone, open at both ends, and its lid at z = H out to the square |x|, |y| <= HALF."""
    a = 2 * np.pi * (np.arange(FACETS) + 0.5) / FACETS
    c, s = np.cos(a), np.sin(a)
    lo = np.c_[R0 * c, R0 * s, np.zeros(FACETS)]
    hi = np.c_[R1 * c, R1 * s, np.full(FACETS, H)]
    out = (HALF / np.maximum(abs(c), abs(s)))[:, None] * np.c_[c, s, np.zeros(FACETS)] + [0, 0, H]
    tri = []
    for i in range(FACETS):
        j = (i + 1) % FACETS
        tri += [[lo[i], lo[j], hi[j]], [lo[i], hi[j], hi[i]], [hi[i], hi[j], out[j]], [hi[i], out[j], out[i]]]
        if (abs(c[i]) > abs(s[i])) != (abs(c[j]) > abs(s[j])):  # the lid's corner between two rays
            tri += [[out[i], [math.copysign(HALF, c[i] + c[j]), math.copysign(HALF, s[i] + s[j]), H], out[j]]]
    tri = np.array(tri, float)
    pv.PolyData.from_regular_faces(tri.reshape(-1, 3), np.arange(len(tri) * 3).reshape(-1, 3)).save(str(path))


def cone_bed(folder: Path, cell: float, d: float = 0.001):
    from tests.conftest import make_scene

    cone_mesh(folder / "cone.stl")
    raw = make_scene(
        domain={"min": [-HALF, -HALF, 0], "max": [HALF, HALF, 0.1], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": d}, "fixed": True, "inside_mesh": 0,
                    "region": {"min": [-HALF, -HALF, 0], "max": [HALF, HALF, 0.05]}}],
        meshes=[{"file": str(folder / "cone.stl"), "material": "sand"}],
        gas=dict(GAS, cell_size=cell), numerics={"dt": 5e-5, "force_dt": True})
    return raw, (lambda z: polygon_area(R0 + (R1 - R0) * np.minimum(z, H) / H)), 0.1


def column_bed(cell: float, d: float = 0.001):
    from tests.conftest import make_scene

    raw = make_scene(
        domain={"min": [-0.012, -0.012, 0], "max": [0.012, 0.012, 0.08], "walls": "auto", "gravity": [0, 0, -9.81]},
        materials={"sand": SAND},
        particles=[{"name": "bed", "material": "sand", "diameter": {"value": d}, "fixed": True,
                    "region": {"min": [-0.012, -0.012, 0], "max": [0.012, 0.012, 0.05]}}],
        gas=dict(GAS, cell_size=cell), numerics={"dt": 5e-5, "force_dt": True})
    return raw, (lambda z: np.full_like(z, 0.024**2)), 0.08



def held_share(solver, grains: int, d: float) -> float:
    """The grains' volume the gas cells hold over their whole volume (1 without meshes)."""
    gas = solver.gas
    host = gas.host_fields()
    if gas.cut is None:
        return 1.0
    fluid = ~gas.cut.unreachable.astype(bool)
    held = ((1 - host["eps"]) * gas.open["cells"])[fluid].sum() * float(np.prod(gas.gg.h))
    return held / (grains * math.pi / 6 * d**3)


def main(cells: list[float], d: float, cases: list[str]) -> None:
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    ensure_taichi("cpu", "float64")
    with TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for case in cases:
            for cell in cells:
                if case in ("wedge", "channel"):
                    raw, area, pos = wedge_bed(folder, cell, d=d, straight=case == "channel")
                    top = 0.08
                else:
                    raw, area, top = cone_bed(folder, cell, d) if case == "cone" else column_bed(cell, d)
                    pos = None
                solver = Solver(build_model(validate(raw)))
                if pos is None:
                    pos = solver.state.x.to_numpy()
                drop, integral = tapered_drop(solver, area, pos, top, d)
                print(f"{case:7s} cell {cell * 1e3:.1f} mm: {len(pos)} grains, drop {drop:.2f} Pa, Ergun integral "
                      f"{integral:.2f} Pa, ratio {drop / integral:.3f}, "
                      f"grains' volume held {held_share(solver, len(pos), d):.3f}",
                      flush=True)
                solver.release()


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cells", nargs="*", type=float, default=[0.004, 0.003, 0.002])
    parser.add_argument("--grain", type=float, default=0.001)
    parser.add_argument("--case", nargs="+", choices=CASES, default=list(CASES))
    args = parser.parse_args()
    main(args.cells, args.grain, args.case)
