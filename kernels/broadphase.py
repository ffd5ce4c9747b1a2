"""Broad phase: uniform cell grid by counting sort, Verlet neighbour list, history carry-over.

Algorithm (O(N) per rebuild):
1. count particles per cell (atomic add), exclusive prefix sum, scatter particle indices into
   cell order (counting sort);
2. for every particle i, scan the 27 cells around it (as nine runs of three cells along z,
   which are adjacent in the sorted index) and keep every j != i with
   |x_j - x_i| < r_i + r_j + skin (a *full* list: each pair appears in both rows, so the force
   loop writes only its own particle and needs no atomics, which keeps runs deterministic);
3. sort the row by partner index (so the result does not depend on thread timing), then
   carry each contact's history (tangential spring, rolling spring, maximum overlap) from the
   old row to the partner's slot in the new row. Both rows are sorted, so matching is a
   merge, and the history is moved in place: entries moving right are moved first in
   descending order, then entries moving left in ascending order, then new slots are zeroed.

4. for every entry (i, k) with partner j > i, find the slot of i in j's row (the count of j's
   partners below i, the row being sorted) and keep it in `src[i, k]` (the mirror slot; -1
   otherwise). The contact kernel evaluates a
   pair once, in the lower index's row, and hands the force to the partner through it
   (`kernels/contact.py`); `src` is scratch of step 3 until then. For partners j < i it is -1,
   and each force pass stamps it with its step while the pair touches (`kernels/contact.py`).
   `split[i]` counts the entries with j < i: the force pass's own loop starts there and the
   partner pass ends there.

A row longer than the capacity K is counted in `overflow`; the run loop turns that into an
error that names the setting to raise (never a silent drop).
"""

import taichi as ti

from .geometry import make_geometry


def make_neighbor_builder(grid, K: int, skin: float, rolling: bool, hysteretic: bool, S, growth: bool = False,
                          after=()):
    """Return the kernels `rebuild(n)`, which refreshes `S.nbr`, `S.nbr_n`, moves the contact history
    and finds the mirror slots `S.src` and `S.split` (steps 1-4, then the Taichi funcs f(n) in
    `after`, in one kernel launch), and `count_split(n)`, which finds `S.split` of the rows as they are.

    S: a namespace of Taichi fields (see `tidem.state.State`). With `growth` (particles that
    grow) each row also records the particle's radius at the build, `S.r_build`.
    """
    min_image, _wrap, cell_coord, cell_id = make_geometry(grid)
    cells = grid.cells
    per = grid.periodic
    n_cells = grid.n_cells
    # the neighbour cells along each axis: -1, 0, +1, or on a periodic axis of fewer than three
    # cells each of its cells once (0, +1 wrapped), so that no cell is scanned twice
    span = [(0, cells[a]) if per[a] and cells[a] < 3 else (-1, 2) for a in range(3)]

    @ti.func
    def count_cells(n):
        for c in range(n_cells):
            S.cell_count[c] = 0
        for i in range(n):
            if S.active[i]:
                c = cell_id(cell_coord(S.x[i]))
                S.pcell[i] = c
                ti.atomic_add(S.cell_count[c], 1)

    @ti.func
    def prefix_sum():
        run = 0
        ti.loop_config(serialize=True)
        for c in range(n_cells):
            S.cell_start[c] = run
            S.cell_fill[c] = run
            run += S.cell_count[c]

    @ti.func
    def scatter(n):
        for i in range(n):
            if S.active[i]:
                slot = ti.atomic_add(S.cell_fill[S.pcell[i]], 1)
                S.sorted_idx[slot] = i

    @ti.func
    def move_history(i, dst, src):
        S.ft[i, dst] = S.ft[i, src]
        if ti.static(rolling):
            S.mr[i, dst] = S.mr[i, src]
        if ti.static(hysteretic):
            S.dmax[i, dst] = S.dmax[i, src]

    @ti.func
    def build_rows(n):
        for i in range(n):
            if not S.active[i]:
                S.nbr_n[i] = 0
                continue
            xi = S.x[i]
            ri = S.radius[i]
            c0 = cell_coord(xi)
            count = 0
            for dx, dy in ti.ndrange(span[0], span[1]):
                c = c0 + ti.Vector([dx, dy, 0])
                inside = True
                for a in ti.static(range(2)):
                    if ti.static(per[a]):
                        c[a] = (c[a] + cells[a]) % cells[a]
                    elif c[a] < 0 or c[a] >= cells[a]:
                        inside = False
                if inside:
                    for part in ti.static(range(span[2][1] - span[2][0] if per[2] else 1)):
                        # the z column of cells is one run of sorted_idx (z varies fastest in cell_id);
                        # a periodic z takes it in parts, one per cell
                        z0, z1 = c0[2] - 1, c0[2] + 1
                        if ti.static(per[2]):
                            z0 = (c0[2] + part + span[2][0] + cells[2]) % cells[2]
                            z1 = z0
                        else:
                            z0, z1 = ti.max(z0, 0), ti.min(z1, cells[2] - 1)
                        first, last = cell_id(ti.Vector([c[0], c[1], z0])), cell_id(ti.Vector([c[0], c[1], z1]))
                        for s in range(S.cell_start[first], S.cell_start[last] + S.cell_count[last]):
                            # without a branch: write every candidate into the next free slot (the next one
                            # overwrites it unless it is kept), which spares the mispredicted jumps of an
                            # unpredictable test (a third of the candidates are kept)
                            j = S.sorted_idx[s]
                            d = min_image(S.x[j] - xi)
                            reach = ri + S.radius[j] + skin
                            S.nbr_new[i, ti.min(count, K - 1)] = j
                            count += ti.cast(d.norm_sqr() < reach * reach, ti.i32) * ti.cast(j != i, ti.i32)
            if count > K:
                ti.atomic_max(S.overflow[0], count)
                count = K
            # insertion sort of the row by partner index
            for a in range(1, count):
                key = S.nbr_new[i, a]
                b = a - 1
                while b >= 0 and S.nbr_new[i, b] > key:
                    S.nbr_new[i, b + 1] = S.nbr_new[i, b]
                    b -= 1
                S.nbr_new[i, b + 1] = key
            # match partners with the old (sorted) row
            n_old = S.nbr_n[i]
            a = 0
            for k in range(count):
                j = S.nbr_new[i, k]
                while a < n_old and S.nbr[i, a] < j:
                    a += 1
                S.src[i, k] = a if (a < n_old and S.nbr[i, a] == j) else -1
            for kk in range(count):  # entries moving right, descending
                k = count - 1 - kk
                src = S.src[i, k]
                if src >= 0 and src < k:
                    move_history(i, k, src)
            for k in range(count):  # entries moving left, ascending
                src = S.src[i, k]
                if src > k:
                    move_history(i, k, src)
            for k in range(count):
                if S.src[i, k] < 0:
                    S.ft[i, k] = ti.Vector([0.0, 0.0, 0.0])
                    if ti.static(rolling):
                        S.mr[i, k] = ti.Vector([0.0, 0.0, 0.0])
                    if ti.static(hysteretic):
                        S.dmax[i, k] = 0.0
                S.nbr[i, k] = S.nbr_new[i, k]
            S.nbr_n[i] = count
            S.x_build[i] = xi
            if ti.static(growth):
                S.r_build[i] = S.radius[i]

    @ti.func
    def count_below(i):
        """The entries of row i with partners j < i."""
        below = 0
        for k in range(S.nbr_n[i]):
            if S.nbr[i, k] < i:
                below += 1
        return below

    @ti.func
    def mirror_rows(n):
        for i in range(n):
            for k in range(S.nbr_n[i]):
                j = S.nbr[i, k]
                found = -1
                if j > i:
                    at = 0  # i's place in j's sorted row: the count of j's partners below i (no branch)
                    for m in range(S.nbr_n[j]):
                        at += ti.cast(S.nbr[j, m] < i, ti.i32)
                    if at < S.nbr_n[j]:
                        if S.nbr[j, at] == i:
                            found = at
                S.src[i, k] = found
            S.split[i] = count_below(i)

    @ti.kernel
    def count_split(n: ti.i32):
        """`split` from the rows alone (after a checkpoint restored them)."""
        for i in range(n):
            S.split[i] = count_below(i)

    @ti.kernel
    def rebuild(n: ti.i32):
        count_cells(n)
        prefix_sum()
        scatter(n)
        build_rows(n)
        mirror_rows(n)
        for then in ti.static(after):
            then(n)

    return rebuild, count_split
