"""What the bed height's definition does to the van Wachem bed: one run's snapshots read with several definitions.

    python benchmarks/van_wachem_2001/height_definitions.py RUN_DIR [T_START]

Per snapshot from T_START (default 1 s), above the distributor (z = 0):
- `p99 of centres`: the 99th percentile of the grains' centre heights (tidem's `bed_height_m`);
- `max of centres`: the highest centre (Lethe's definition for this case);
- `top of 99 % of the solids`: the height under which 99 % of the solids' volume lies, grains counted as
  spheres (each grain's volume spread over its own height);
- `voidage 0.8 surface`: the highest height at which the layer-averaged voidage of the gas grid, over the
  column's width and depth, is below 0.8 (a photograph's surface: where the dense phase ends), linearly
  interpolated between cell centres.
Prints each definition's time mean and 5 / 95 % quantiles next to the records' 124.8 mm [100.9, 147.2].
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from tidem.io.vtp import read_vti, read_vtp

RECORDS = (124.8, 100.9, 147.2)  # mm: time mean and 5 / 95 % (analysis.json)


def solids_top(z: np.ndarray, r: np.ndarray, share: float = 0.99) -> float:
    """The height under which `share` of the spheres' volume lies (sphere slices integrated exactly)."""
    grid = np.linspace(z.min() - r.max(), z.max() + r.max(), 2000)
    h = np.clip(grid[:, None] - (z - r)[None, :], 0.0, 2 * r[None, :])  # each sphere's cap under each level
    below = (np.pi * h * h * (3 * r[None, :] - h) / 3).sum(axis=1)
    return float(np.interp(share * below[-1], below, grid))


def voidage_surface(info: dict, eps: np.ndarray, limit: float = 0.8) -> float:
    layer = eps.mean(axis=(0, 1))
    z = info["origin"][2] + (np.arange(len(layer)) + 0.5) * info["spacing"][2]
    dense = np.nonzero(layer < limit)[0]
    if len(dense) == 0:
        return float("nan")
    k = dense[-1]
    if k + 1 >= len(layer):
        return float(z[k])
    return float(np.interp(limit, [layer[k], layer[k + 1]], [z[k], z[k + 1]]))


def main(run: Path, t_start: float) -> None:
    import xml.etree.ElementTree as ET

    def entries(pvd: Path) -> list[tuple[float, Path]]:
        root = ET.parse(pvd).getroot()
        return [(float(d.get("timestep")), pvd.parent / d.get("file")) for d in root.iter("DataSet")]

    heights: dict[str, list[float]] = {k: [] for k in ("p99 of centres", "max of centres", "top of 99 % of the solids",
                                                       "voidage 0.8 surface")}
    gas = dict(entries(run / "gas.pvd"))
    for t, path in entries(run / "snapshots.pvd"):
        if t < t_start:
            continue
        x, data = read_vtp(path)
        z, r = x[:, 2], data["radius"]
        heights["p99 of centres"].append(np.percentile(z, 99))
        heights["max of centres"].append(z.max())
        heights["top of 99 % of the solids"].append(solids_top(z, r))
        if t in gas:
            info, cells = read_vti(gas[t])
            heights["voidage 0.8 surface"].append(voidage_surface(info, cells["voidage"]))
    print(f"| definition | time mean [mm] | 5 % / 95 % [mm] | mean against the records' {RECORDS[0]} mm |")
    print("|---|---|---|---|")
    for name, values in heights.items():
        v = 1e3 * np.array(values)
        print(f"| {name} | {v.mean():.1f} | {np.percentile(v, 5):.1f} / {np.percentile(v, 95):.1f} | "
              f"{100 * (v.mean() / RECORDS[0] - 1):+.1f} % |")
    print(f"\n{len(heights['p99 of centres'])} snapshots from t = {t_start:g} s")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(Path(sys.argv[1]), float(sys.argv[2]) if len(sys.argv) > 2 else 1.0)
