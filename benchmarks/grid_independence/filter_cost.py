"""What the averaging-length filters and the cut tube cost: fluidized_tube with its tube as the staircase of cells
(`gas.tube_shape = "cells"`) over the cells' own averaging ("cells"), with the voidage filtered to
`gas.averaging_length` ("filtered"), with the drag's exchange filtered too (`gas.drag_averaging = "length"`,
"drag"), and with the voidage filtered and the tube cut into the gas grid (`gas.tube_shape = "cut"`, the default,
"cut_tube"), run alternately in separate processes, and the ratios of their stepping wall times (run.json
`wall_s`, set-up excluded) to the first variant's.

    python benchmarks/grid_independence/filter_cost.py [--cell 0.003] [--length 0.012] [--t-end 0.3] [--rounds 2]
        [--variants cells,filtered]
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

STAIRCASE = {"gas.tube_shape": "cells"}
VARIANTS = {"cells": {**STAIRCASE, "gas.averaging_length": "cells"}, "filtered": STAIRCASE,
            "drag": {**STAIRCASE, "gas.drag_averaging": "length"},
            "cut_tube": {"gas.tube_shape": "cut"}}  # each variant's keys over the length's


def one_run(cell: float, length: float, variant: str, t_end: float, folder: Path) -> float:
    cmd = [sys.executable, "-m", "tidem", "scene", "fluidized_tube", "--t-end", str(t_end), "--no-render", "--quiet",
           "--out", str(folder), "--set", f"gas.cell_size={cell}", "--set", "gas.coupling_interval=10"]
    for key, value in {"gas.averaging_length": length, **VARIANTS[variant]}.items():
        cmd += ["--set", f"{key}={value}"]
    subprocess.run(cmd, check=True)
    return json.loads((folder / "run.json").read_text())["wall_s"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cell", type=float, default=0.003)
    ap.add_argument("--length", type=float, default=0.012)
    ap.add_argument("--t-end", type=float, default=0.3)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--variants", default="cells,filtered", help=f"comma-separated, of {', '.join(VARIANTS)}")
    args = ap.parse_args()
    names = args.variants.split(",")
    if unknown := [n for n in names if n not in VARIANTS]:
        sys.exit(f"--variants: unknown {', '.join(unknown)} (known: {', '.join(VARIANTS)})")
    times: dict[str, list[float]] = {name: [] for name in names}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for name in names:
                times[name].append(one_run(args.cell, args.length, name, args.t_end, Path(tmp) / f"{name}{r}"))
                print(f"round {r + 1} {name}: {times[name][-1]:.1f} s", flush=True)
    for name in names[1:]:
        ratio = sum(times[name]) / sum(times[names[0]])
        print(f"fluidized_tube, {1e3 * args.cell:g} mm cells, {args.t_end:g} s, L = {args.length:g} m: {name} takes "
              f"{ratio:.3f}x the stepping wall time of {names[0]} ({args.rounds} alternating rounds)")


if __name__ == "__main__":
    main()
