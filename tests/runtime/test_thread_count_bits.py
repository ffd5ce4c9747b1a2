"""Float64 runs give the same bits on any thread count: the contact passes sweep blocks of slabs in a
fixed order (`kernels/contact.py`), and the heat flows into the heated surfaces, which every block's
particles add to, are summed per block and then in block order (`kernels/surface_contact.py`; a heated
mesh's by blocks of particles, `mesh_pass`). Before those block rows the flows were atomic adds, and a
run on one thread and one on two differed in `surf_rate`'s last bits (a heated foil's temperature
follows it): fluidized_tube's smoke run with heated walls 0.12157686417634565 against ...567 W,
rotary_kiln's heated drum 45.830165673258946 against ...893 W at 0.05 s. The reactions' totals (heat
released, mass reacted) were atomic adds too, now booked per particle and summed in particle order."""

import os
import subprocess
import sys

import numpy as np
import pytest


def run(out, threads: int, args: list[str]) -> dict:
    """`tidem scene ARGS` on `threads` CPU threads, in a process of its own (Taichi's thread count is
    fixed per process); returns its checkpoint's arrays."""
    env = dict(os.environ, TI_CPU_MAX_NUM_THREADS=str(threads))
    done = subprocess.run([sys.executable, "-m", "tidem", "scene", *args, "--no-render", "--quiet", "--out", str(out)],
                          env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    # tidem takes its thread count from that variable and says nothing of it (Taichi warned that its
    # own argument overrode the variable, though both said the same)
    assert "overridden" not in done.stderr, done.stderr
    # nor Taichi's warnings at compile time (a len() inside a func, a long static unrolling)
    assert "Warning" not in done.stderr, done.stderr
    with np.load(out / "checkpoint.npz") as data:
        return {k: data[k] for k in data.files if k != "meta"}


@pytest.mark.parametrize("args", [
    ["fluidized_tube", "--smoke", "--set", "domain.wall_temperature=353.15"],  # a heated tube and heated walls
    ["rotary_kiln", "--t-end", "0.05"],  # a heated mesh drum
    ["olefin_polymerization", "--smoke"],  # reaction totals (kernels/reactions.py, rbook)
], ids=["tube_and_walls", "mesh", "reactions"])
def test_heated_surfaces_give_the_same_bits_on_one_thread_and_on_two(tmp_path, args):
    one, two = run(tmp_path / "one", 1, args), run(tmp_path / "two", 2, args)
    assert one["state/rsum"].max() > 0.0 if "state/rsum" in one else one["state/surf_rate"].max() > 0.0
    assert set(one) == set(two)
    assert [k for k in one if not np.array_equal(one[k], two[k])] == []
