"""What the averaging-length filter costs: fluidized_tube with and without `gas.averaging_length`, run alternately
in separate processes, and the ratio of their stepping wall times (run.json `wall_s`, set-up excluded).

    python benchmarks/grid_independence/filter_cost.py [--cell 0.003] [--length 0.012] [--t-end 0.3] [--rounds 2]
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path


def one_run(cell: float, length: float | None, t_end: float, folder: Path) -> float:
    cmd = [sys.executable, "-m", "tidem", "scene", "fluidized_tube", "--t-end", str(t_end), "--no-render", "--quiet",
           "--out", str(folder), "--set", f"gas.cell_size={cell}", "--set", "gas.coupling_interval=10"]
    if length is not None:
        cmd += ["--set", f"gas.averaging_length={length}"]
    subprocess.run(cmd, check=True)
    return json.loads((folder / "run.json").read_text())["wall_s"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cell", type=float, default=0.003)
    ap.add_argument("--length", type=float, default=0.012)
    ap.add_argument("--t-end", type=float, default=0.3)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    times: dict[str, list[float]] = {"cells": [], "filtered": []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for name, length in (("cells", None), ("filtered", args.length)):
                times[name].append(one_run(args.cell, length, args.t_end, Path(tmp) / f"{name}{r}"))
                print(f"round {r + 1} {name}: {times[name][-1]:.1f} s", flush=True)
    ratio = sum(times["filtered"]) / sum(times["cells"])
    print(f"fluidized_tube, {1e3 * args.cell:g} mm cells, {args.t_end:g} s: averaging_length {args.length:g} m takes "
          f"{ratio:.3f}x the stepping wall time of the cells' own averaging ({args.rounds} alternating rounds)")


if __name__ == "__main__":
    main()
