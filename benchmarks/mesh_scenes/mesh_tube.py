"""fluidized_tube with its 15 mm tube drawn as a 48-facet mesh, against the analytic tube.

    python benchmarks/mesh_scenes/mesh_tube.py OUT [SEED ...]     (seeds default: 1 2 3)

Writes OUT/tube48.stl and OUT/mesh_tube.toml (the shipped scene with [[tubes]] replaced by
[[meshes]] at the same place and temperature, `convection_length` = the tube's diameter), runs
both scenes for each seed (`--no-render`, the shipped 0.8 s) unless OUT/<kind>_s<seed> already
holds a finished run, and prints per run the heat the tube gives the particles and the gas over
t >= heat.profile_start, as coefficients over the tube's area and T_wall - T_0, and the mean
pressure drop. The mesh's area is its 48-gon's, 0.06 % below pi D L.
"""

import csv
import json
import math
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pyvista as pv

from tidem.scene.load import resolve

FACETS = 48


def write_scene(out: Path) -> Path:
    """The mesh tube's STL and scene in `out`; the scene's path."""
    shipped = resolve("fluidized_tube")
    raw = tomllib.loads(shipped.read_text())
    tube = raw["tubes"][0]
    depth = raw["domain"]["max"][1] - raw["domain"]["min"][1]
    centre = (tube["center"][0], raw["domain"]["min"][1] + depth / 2, tube["center"][2])
    pv.Cylinder(center=centre, direction=(0, 1, 0), radius=tube["diameter"] / 2, height=depth, resolution=FACETS,
                capping=False).triangulate().save(str(out / "tube48.stl"))
    mesh = (f'[[meshes]]\nfile = "tube48.stl"\nmaterial = "{tube["material"]}"\nfriction = {tube["friction"]}\n'
            f'temperature = {tube["temperature"]}\nconvection_length = {tube["diameter"]}\n')
    text = re.sub(r"\[\[tubes\]\].*?\n\n", mesh + "\n", shipped.read_text(), count=1, flags=re.S)
    text = text.replace('"tube_heat", "tube_mean_alpha", ', "")
    path = out / "mesh_tube.toml"
    path.write_text(text)
    return path


def run(scene: str, folder: Path, seed: int) -> None:
    if (folder / "run.json").exists() and json.loads((folder / "run.json").read_text()).get("status") == "finished":
        return
    subprocess.run(["tidem", "scene", scene, "--no-render", "--quiet", "--set", f"particles[0].seed={seed}",
                    "--out", str(folder)], check=True)


def heat_row(folder: Path, key: str, area: float, d_t: float, start: float) -> str:
    with open(folder / "timeseries.csv") as fh:
        rows = list(csv.DictReader(fh))
    late = [r for r in rows if float(r["time_s"]) >= start]
    q_p = np.mean([float(r[f"{key}_heat_W"]) for r in late])
    q_g = np.mean([float(r[f"{key}_gas_heat_W"]) for r in late])
    dp = np.mean([float(r["gas_pressure_drop_Pa"]) for r in late])
    return (f"| {folder.name} | {q_p / area / d_t:.1f} | {q_g / area / d_t:.1f} | {(q_p + q_g) / area / d_t:.1f} | "
            f"{dp:.1f} |")


def main(out: Path, seeds: list[int]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    scene = write_scene(out)
    raw = tomllib.loads(resolve("fluidized_tube").read_text())
    tube, heat = raw["tubes"][0], raw["heat"]
    d_t = tube["temperature"] - heat["initial_temperature"]
    depth = raw["domain"]["max"][1] - raw["domain"]["min"][1]
    polygon = FACETS * tube["diameter"] * math.sin(math.pi / FACETS) * depth
    print("| run | particles alpha | gas alpha | total alpha, W/(m2 K) | pressure drop, Pa |\n|---|---|---|---|---|")
    for kind, name, key, area in (("mesh", str(scene), "meshes0", polygon),
                                  ("tube", "fluidized_tube", "tubes0", math.pi * tube["diameter"] * depth)):
        for seed in seeds:
            folder = out / f"{kind}_s{seed}"
            run(name, folder, seed)
            print(heat_row(folder, key, area, d_t, heat["profile_start"]))


if __name__ == "__main__":
    main(Path(sys.argv[1]), [int(s) for s in sys.argv[2:]] or [1, 2, 3])
