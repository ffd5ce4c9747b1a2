"""What the host's reads of a run cost: a checkpoint written (first and second time in a process),
restored into a fresh solver, a time-series sample and a snapshot, on one scene.

    python -P benchmarks/host_reads.py [SCENE] [SAMPLES]

Builds SCENE (default fluidized_tube), takes 10 steps, then times each. The first checkpoint and
restore include compiling their kernels (from Taichi's offline cache where it has them): what a run
pays once. Run an older tree the same way with PYTHONPATH=TREE python -P from outside the project
folder, one after the other within minutes (this machine's speed drifts; `benchmarks/README.md`).
"""

import sys
import tempfile
import time
from pathlib import Path

from tidem.runner import checkpoint
from tidem.runner.launch import prepare
from tidem.runner.output import Output
from tidem.scene.load import load
from tidem.sim.solver import Solver


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main(scene: str = "fluidized_tube", samples: int = 200) -> None:
    loaded = load(scene)
    work = Path(tempfile.mkdtemp())
    prepared = prepare(loaded, out=work / "run")
    solver = Solver(prepared.model)
    solver.advance(10)
    save = lambda: checkpoint.save(work, solver, {}, loaded.raw)  # noqa: E731
    first, second = timed(save), timed(save)
    fresh = Solver(prepared.model)
    meta, arrays = checkpoint.load(work)
    restore = timed(lambda: checkpoint.restore(fresh, meta, arrays))
    out = Output(prepared.out_dir, prepared.model)
    out.sample(solver)  # compiles what a sample launches
    per_sample = timed(lambda: [out.sample(solver) for _ in range(samples)]) / samples
    out.snapshot(solver)
    out.flush()
    per_snapshot = timed(lambda: [out.snapshot(solver) for _ in range(10)]) / 10
    out.close()
    print(f"{scene}: checkpoint first {first:.2f} s, second {second * 1e3:.1f} ms; restore {restore:.2f} s; "
          f"sample {per_sample * 1e3:.2f} ms; snapshot (copies, writes behind) {per_snapshot * 1e3:.2f} ms")


if __name__ == "__main__":
    main(*(sys.argv[1:2]), *(int(a) for a in sys.argv[2:3]))
