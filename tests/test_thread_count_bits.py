"""Float64 runs give the same bits on any thread count: the contact passes sweep blocks of slabs in a
fixed order (`kernels/contact.py`), and the heat flows into the heated surfaces, which every block's
particles add to, are summed per block and then in block order (`kernels/surface_contact.py`). Before
those block rows the flows were atomic adds, and a run on one thread and one on two differed in the
heated walls' `surf_rate` (last bits; a heated foil's temperature follows that sum)."""

import os
import subprocess
import sys

import numpy as np


def run(out, threads: int) -> dict:
    """fluidized_tube's smoke run (300 steps) with its box walls at 80 C, on `threads` CPU threads, in a
    process of its own (Taichi's thread count is fixed per process); returns its checkpoint's arrays."""
    env = dict(os.environ, TI_CPU_MAX_NUM_THREADS=str(threads))
    done = subprocess.run([sys.executable, "-m", "tidem", "scene", "fluidized_tube", "--smoke", "--no-render", "--quiet", "--set", "domain.wall_temperature=353.15", "--out", str(out)],
                          env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    with np.load(out / "checkpoint.npz") as data:
        return {k: data[k] for k in data.files if k != "meta"}


def test_heated_walls_give_the_same_bits_on_one_thread_and_on_two(tmp_path):
    one, two = run(tmp_path / "one", 1), run(tmp_path / "two", 2)
    assert one["state/surf_rate"][-1] > 0.0  # the tube heats the bed
    assert set(one) == set(two)
    assert [k for k in one if not np.array_equal(one[k], two[k])] == []
