"""A storage sort on the device: every per-particle field permuted into the order in `S.sorted_idx`
(the broad phase's cell order, `kernels/broadphase.py` `cell_order`) without leaving the GPU.

The CPU sorts on the host (`tidem.storage_order`: a stable numpy sort, so that float64 runs stay
bit-identical); on a GPU that copied every particle field to the host and back at every sort (about
1 kB a particle: 0.7 GB for the 700 000-grain laboratory bed). Here each field is gathered into a
scratch twin, field[order[k]] -> twin[k], and copied back; partner indices in the Verlet rows are
renumbered (renumber[order[k]] = k; a slot past the row's length holds -1), each row keeping its
order and history, as the host sort does (steps 2-3 of `tidem.storage_order`). Within a cell the
order is the counting sort's, which atomics decide: runs on a GPU are not bit-reproducible anyway
(`kernels/ordered.py`).
"""

import taichi as ti


def _twin(field):
    """A scratch field of `field`'s type and shape."""
    if isinstance(field, ti.lang.matrix.MatrixField):
        if field.m == 1:
            return ti.Vector.field(field.n, field.dtype, shape=field.shape)
        return ti.Matrix.field(field.n, field.m, field.dtype, shape=field.shape)
    return ti.field(field.dtype, shape=field.shape)


def make_storage_permuter(S, names):
    """Return the kernel permute(n): the fields `names` of S (per-particle, [capacity] or
    [capacity, K] rows; `nbr` renumbered) stored in the order S.sorted_idx[0:n]. Allocates a scratch
    twin of each (the particle fields' memory once more)."""
    plain = [(getattr(S, name), _twin(getattr(S, name))) for name in names if name != "nbr"]
    nbr_twin = _twin(S.nbr)
    renumber = ti.field(ti.i32, shape=S.x.shape[0])
    K = S.nbr.shape[1]

    @ti.kernel
    def permute(n: ti.i32):
        for k in range(n):
            renumber[S.sorted_idx[k]] = k
        for i, k in ti.ndrange(n, K):  # before nbr_n is permuted: each row's length where it was
            old = S.sorted_idx[i]
            nbr_twin[i, k] = renumber[S.nbr[old, k]] if k < S.nbr_n[old] else -1
        for field, twin in ti.static(plain):
            if ti.static(len(field.shape) == 1):
                for k in range(n):
                    twin[k] = field[S.sorted_idx[k]]
            else:
                for k, j in ti.ndrange(n, field.shape[1]):
                    twin[k, j] = field[S.sorted_idx[k], j]
        for i, k in ti.ndrange(n, K):
            S.nbr[i, k] = nbr_twin[i, k]
        for field, twin in ti.static(plain):
            if ti.static(len(field.shape) == 1):
                for k in range(n):
                    field[k] = twin[k]
            else:
                for k, j in ti.ndrange(n, field.shape[1]):
                    field[k, j] = twin[k, j]

    return permute
