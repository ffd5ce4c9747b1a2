"""Whether the kernels being built take their sums in one fixed order or by atomics.

On the CPU every sum of a run is taken in one order (serial loops over particles or cells, the
slab passes of `kernels/contact.py`), so float64 runs are bit-reproducible on any thread count. On a
GPU a loop in one thread leaves thousands of threads idle (the bubbling bed's pressure solve took
5.8 ms a step in one CUDA thread, `benchmarks/README.md`), so there the same loops run one thread
per item with atomic sums, whose last bits vary from run to run.
"""

import taichi as ti


def in_order() -> bool:
    """True on Taichi's CPU backend (sums in a fixed order), False on a GPU (atomic sums)."""
    return ti.lang.impl.current_cfg().arch == ti.cpu


@ti.func
def raise_max(target: ti.template(), value):
    """target[None] = max(target[None], value), read first and written only where value is larger:
    thousands of GPU threads' atomic max on one float64 (a compare-and-swap loop) took 1.1 ms a step
    of the 10k peer bed on an H100 (`benchmarks/README.md`); after the read only the few that raise
    it write. The value only grows during a launch, so a thread that reads a larger one may skip."""
    if value > target[None]:
        ti.atomic_max(target[None], value)


def make_sums(atomic: bool):
    """Return Taichi funcs (add(field, j, value), raise_to(field, j, value)): field[j] += value and
    field[j] = max(field[j], value), as a plain load and store where one thread owns j in the pass (the
    slabs of `kernels/contact.py`; Taichi would make `field[j] += value` with an index it cannot prove
    private an atomic, a compare-and-swap loop per float, 20 ns a pair on the peer bed), else atomic."""

    @ti.func
    def add(field: ti.template(), j, value):
        if ti.static(atomic):
            ti.atomic_add(field[j], value)
        else:
            field[j] = field[j] + value

    @ti.func
    def raise_to(field: ti.template(), j, value):
        if ti.static(atomic):
            ti.atomic_max(field[j], value)
        else:
            field[j] = ti.max(field[j], value)

    return add, raise_to
