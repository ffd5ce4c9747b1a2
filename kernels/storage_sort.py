"""A storage sort in place: every per-particle field permuted into the order in `S.sorted_idx`
without a copy through the host.

On a GPU the order is the broad phase's cell order (`kernels/broadphase.py` `cell_order`), whose ties
the counting sort's atomics decide: runs there are not bit-reproducible anyway (`kernels/ordered.py`).
On the CPU the host computes the order (`tidem.particles.storage_order`: a stable numpy sort, so that float64
runs stay bit-identical) and this kernel moves the fields: copying every field to the host and back
took 25 ms a sort of fluidized_tube's 13 000 grains, most of it a launch per field and direction,
and on a GPU about 1 kB a particle crossed the bus (0.7 GB for the 700 000-grain laboratory bed).
Each field is gathered into a scratch twin, field[order[k]] -> twin[k], and copied back, all fields
in one loop each way; partner indices in the Verlet rows are renumbered (renumber[order[k]] = k; a
slot past the row's length holds -1), each row keeping its order and history (steps 2-3 of
`tidem.particles.storage_order`).
"""

import taichi as ti


def _twin(field):
    """A scratch field of `field`'s type and shape."""
    if isinstance(field, ti.lang.matrix.MatrixField):
        if field.m == 1:
            return ti.Vector.field(field.n, field.dtype, shape=field.shape)
        return ti.Matrix.field(field.n, field.m, field.dtype, shape=field.shape)
    return ti.field(field.dtype, shape=field.shape)


UNROLL = 32  # Taichi's unrolling limit (ti.init's unrolling_limit, default 32)


def make_storage_permuter(S, names):
    """Return the kernel permute(n): the fields `names` of S (per-particle, [capacity] or
    [capacity, K] rows; `nbr` renumbered) stored in the order S.sorted_idx[0:n]. Allocates a scratch
    twin of each (the particle fields' memory once more)."""
    plain = [(getattr(S, name), _twin(getattr(S, name))) for name in names if name != "nbr"]
    # in groups of at most UNROLL: Taichi warns at compile time of a static loop over more (a run's first
    # start printed that warning twice)
    groups = [plain[a:a + UNROLL] for a in range(0, len(plain), UNROLL)]
    nbr_twin = _twin(S.nbr)
    renumber = ti.field(ti.i32, shape=S.x.shape[0])
    K = S.nbr.shape[1]

    @ti.func
    def copy_row(dst: ti.template(), i, src: ti.template(), j):
        """dst[i] = src[j]: one particle's value, or its row of a [capacity, K] field."""
        if ti.static(len(dst.shape) == 1):
            dst[i] = src[j]
        else:
            for k in range(dst.shape[1]):
                dst[i, k] = src[j, k]

    @ti.kernel
    def permute(n: ti.i32):
        for k in range(n):
            renumber[S.sorted_idx[k]] = k
        for i in range(n):  # gather: row i takes particle sorted_idx[i]'s values
            old = S.sorted_idx[i]
            for k in range(K):  # before nbr_n is permuted: each row's length where it was
                nbr_twin[i, k] = renumber[S.nbr[old, k]] if k < S.nbr_n[old] else -1
            for group in ti.static(groups):
                for field, twin in ti.static(group):
                    copy_row(twin, i, field, old)
        for i in range(n):
            copy_row(S.nbr, i, nbr_twin, i)
            for group in ti.static(groups):
                for field, twin in ti.static(group):
                    copy_row(field, i, twin, i)

    return permute
