"""Broad phase: uniform cell grid by counting sort, Verlet neighbour list, history carry-over.

Algorithm (O(N) per rebuild):
1. count particles per cell (atomic add), exclusive prefix sum, scatter particle indices into
   cell order (counting sort); note each particle's slab (`kernels/geometry.py`, `slab_layout`)
   and list the particles of each slab in index order (`slab_list` from `slab_start[s]`: a serial
   pass, so that the contact pass sweeps each slab in the same order on any thread count). On the
   CPU, for beds of up to SERIAL_PARTICLES, the whole of step 1 runs in the calling thread;
2. for every particle i, scan the 27 cells around it but the layer behind along the slab axis,
   whose particles own their pairs with i (slabs are one cell layer thick: 18 cells, as six runs of
   three cells along z, adjacent in the sorted index, or nine runs of two for a z slab axis; which
   candidates lie in i's slab and which in the next one follows from the cell runs), and keep
   every j != i with
   |x_j - x_i| < r_i + r_j + skin that i *owns*: a pair is listed once, in the row of the
   particle in the slab before the other's, or, in one slab (or in two slabs that are each other's
   successor), in the row of the lower `ident` (the particle's scene index, which a storage
   re-sort does not change); the contact pass (`kernels/contact.py`) evaluates it there and adds
   the reaction to the partner, which lies in the owner's slab or the next one;
3. sort the row in the scratch rows `nbr_new`: the partners that touch i first, then the others
   (which step 5 puts in their groups), each by partner index (so the result does not depend on
   thread timing). The contact pass's branch on contact then turns once in a row instead of at
   random: 9-12 % of the pass on the peer bed (`benchmarks/README.md`). Find each partner that touches
   i in the old row, or in the partner's old row where the pair changed owner (`src`, through the flip
   buffer `flip_*`; `kernels/history_carry.py`, `match_row`);
4. carry the history within the row, in place (`history_carry.move_row`);
5. note how many partners touch i (`nbr_touch`, listed first). The others, whose history is zeroed,
   follow in QUIET_GROUPS groups by their gap (below `bounds[0]`, up to `bounds[1]`, ..., beyond: with
   the run's bounds half the contact skin, the skin, and the partners listed for the gas lens alone),
   each group by partner index; note where each group ends (`nbr_end`) and its smallest gap (`nbr_gap`
   [m], float32): the contact passes skip a group while no particle has moved far enough to close that
   gap (`kernels/pair_contact.py`).
Steps 2 and 3 read the old rows only and run in one loop, row by row; step 4 is a loop of its own,
so that no row changes while another particle reads it. On this 2-core VM a bubbling bed's build
(fluidized_tube, 13 000 grains) went from ten parallel loops to two (step 2 with 3, step 4 with the
`after` funcs): each costs a wake-up of the thread pool, tens of microseconds on average
(`benchmarks/README.md`).

A row longer than the capacity K is counted in `overflow`; the run loop turns that into an
error that names the setting to raise (never a silent drop).
"""

import taichi as ti

from .geometry import make_geometry, make_slabs
from .history_carry import make_history_carry
from .ordered import in_order
from .sizes import make_sizes

SCAN_BLOCK = 1024  # cells a thread sums in the prefix sum of a large grid
# Beds of at most this many particles (capacity) count, sum and scatter them into cells in the calling
# thread on the CPU: each parallel loop costs a wake-up of the thread pool (tens of microseconds on
# average on a 2-core VM), more than these loops' work for such a bed (13 000 grains: 0.08 ms in one
# thread against 0.44 ms in seven parallel loops, `benchmarks/README.md`; the work grows with the bed).
SERIAL_PARTICLES = 32768
# The quiet partners of a row (apart at the build) in groups by their gap then (step 5): a contact pass
# evaluates a group only where the group's nearest partner may have closed that gap since.
QUIET_GROUPS = 3


def scan_blocks(n_cells: int) -> int:
    """Blocks of the cell grid's prefix sum (`S.cell_block`), one for a small grid."""
    return max(1, -(-n_cells // SCAN_BLOCK))


def make_neighbor_builder(grid, K: int, skin: float, rolling: bool, hysteretic: bool, S, growth: bool = False,
                          after=(), uniform: tuple[float, float] | None = None, slab_lists: bool | None = None,
                          bounds: tuple[float, ...] = ()):
    """Return the kernels (rebuild(n), cell_order(n)). `rebuild` refreshes `S.nbr`, `S.nbr_n`, the
    slabs (`S.slab`, `S.slab_list`, `S.slab_start`) and moves the contact history (steps 1-4, and the
    Taichi funcs f(i) in `after` on each particle in step 4's loop, in one kernel launch). `cell_order`
    writes the particles in cell order to `S.sorted_idx[0:n]` (step 1's counting sort, the inactive
    ones after the active, in any order): a storage sort's order on a GPU (`tidem.particles.storage_order`).

    S: a namespace of Taichi fields (see `tidem.sim.state.State`). With `growth` (particles that
    grow) each row also records the particle's radius at the build, `S.r_build`. `uniform`: (radius, mass)
    of every particle (`kernels/sizes.py`), or None. `slab_lists`: whether the contact passes sweep
    slab lists (`kernels/contact.py`; None: on the CPU, where they do); without, the serial pass that
    lists them is left out (on a GPU it ran in one thread: 700 000 particles a build). `bounds`: the gaps
    [m] that divide the quiet partners into QUIET_GROUPS groups (step 5; ascending, below `skin`).
    """
    assert len(bounds) == QUIET_GROUPS - 1 and list(bounds) == sorted(bounds), bounds
    if slab_lists is None:
        slab_lists = in_order()
    serial = in_order() and S.x.shape[0] <= SERIAL_PARTICLES  # the counting sort's loops in the calling thread
    min_image, _wrap, cell_coord, cell_id = make_geometry(grid)
    radius_of, _mass_of = make_sizes(S, uniform)
    n_slabs, slab_of, succ, pred = make_slabs(grid)
    cells = grid.cells
    per = grid.periodic
    n_cells = grid.n_cells
    n_scan = scan_blocks(n_cells)
    # the neighbour cells along each axis: -1, 0, +1, or on a periodic axis of fewer than three
    # cells each of its cells once (0, +1 wrapped), so that no cell is scanned twice
    span = [(0, cells[a]) if per[a] and cells[a] < 3 else (-1, 2) for a in range(3)]
    # Slabs are layers of cells (`slab_layout`): the layer behind i's along the slab axis is the slab
    # before i's, whose particles own their pairs with i, unless that slab is also the one after (two
    # slabs around a periodic axis) or i's own (one slab). Its cells are then not scanned.
    axis = grid.slab_axis
    layers = n_slabs >= (3 if per[axis] else 2)
    if layers:
        span[axis] = (0, 2)
    match_row, move_row = make_history_carry(S, K, rolling, hysteretic)
    capacity = S.x.shape[0]
    QUIET = 1e30  # nbr_gap of an empty quiet group

    @ti.func
    def count_cells(n):
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for c in range(n_cells):
            S.cell_count[c] = 0
        ti.loop_config(serialize=True)  # a few slabs
        for s in range(n_slabs + 1):
            S.slab_start[s] = 0
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for i in range(n):
            if S.active[i]:
                c = cell_id(cell_coord(S.x[i]))
                S.pcell[i] = c
                ti.atomic_add(S.cell_count[c], 1)
                s = slab_of(S.x[i])
                S.slab[i] = s
                ti.atomic_add(S.slab_start[s + 1], 1)

    @ti.func
    def cell_sums():
        """cell_start = cell_fill = the exclusive prefix sum of cell_count: in one pass where the grid
        is small, else in blocks of SCAN_BLOCK cells (the blocks' totals in parallel, their offsets in
        one pass, the cells in parallel again): a 1.8 M-cell grid in one GPU thread is a
        million-step loop at every build. Integer sums: the same numbers either way."""
        if ti.static(n_cells <= SCAN_BLOCK or serial):
            run = 0
            ti.loop_config(serialize=True)
            for c in range(n_cells):
                S.cell_start[c] = run
                S.cell_fill[c] = run
                run += S.cell_count[c]
        else:
            for b in range(n_scan):
                total = 0
                for c in range(b * SCAN_BLOCK, ti.min((b + 1) * SCAN_BLOCK, n_cells)):
                    total += S.cell_count[c]
                S.cell_block[b] = total
            run = 0
            ti.loop_config(serialize=True)
            for b in range(n_scan):
                total = S.cell_block[b]
                S.cell_block[b] = run
                run += total
            for b in range(n_scan):
                at = S.cell_block[b]
                for c in range(b * SCAN_BLOCK, ti.min((b + 1) * SCAN_BLOCK, n_cells)):
                    S.cell_start[c] = at
                    S.cell_fill[c] = at
                    at += S.cell_count[c]

    @ti.func
    def prefix_sums():
        cell_sums()
        ti.loop_config(serialize=True)
        for s in range(n_slabs):
            S.slab_start[s + 1] += S.slab_start[s]
            S.slab_fill[s] = S.slab_start[s]

    @ti.func
    def scatter(n):
        if ti.static(serial):
            ti.loop_config(serialize=True)
        for i in range(n):
            if S.active[i]:
                slot = ti.atomic_add(S.cell_fill[S.pcell[i]], 1)
                S.sorted_idx[slot] = i

    @ti.func
    def list_slabs(n):
        ti.loop_config(serialize=True)  # index order within each slab, whatever the thread count
        for i in range(n):
            if S.active[i]:
                s = S.slab[i]
                S.slab_list[S.slab_fill[s]] = i
                S.slab_fill[s] += 1

    @ti.func
    def build_rows(n):
        for i in range(n):
            if not S.active[i]:
                S.nbr_count[i] = 0
                continue
            xi = S.x[i]
            ri = radius_of(i)
            si = S.slab[i]
            ahead, behind = succ(si), pred(si)
            ident = S.ident[i]
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
                        z0, z1 = c0[2] + span[2][0], c0[2] + span[2][1] - 1
                        if ti.static(per[2]):
                            z0 = (c0[2] + part + span[2][0] + cells[2]) % cells[2]
                            z1 = z0
                        else:
                            z0, z1 = ti.max(z0, 0), ti.min(z1, cells[2] - 1)
                        first, last = cell_id(ti.Vector([c[0], c[1], z0])), cell_id(ti.Vector([c[0], c[1], z1]))
                        end = S.cell_start[last] + S.cell_count[last]
                        # with `layers`, the candidates before `ahead_from` lie in i's slab, the others in the next
                        ahead_from = end
                        if ti.static(layers and axis < 2):  # the whole run lies in the next layer, or none
                            ahead_from = ti.select(c[axis] == c0[axis], end, S.cell_start[first])
                        elif ti.static(layers and per[2]):
                            if ti.static(part == 1):  # (span[2] = (0, 2): part 0 is i's layer)
                                ahead_from = S.cell_start[first]
                        elif ti.static(layers):
                            ahead_from = ti.select(z1 > c0[2], S.cell_start[last], end)
                        for s in range(S.cell_start[first], end):
                            # without a branch: write every candidate into the next free slot (the next one
                            # overwrites it unless it is kept), which spares the mispredicted jumps of an
                            # unpredictable test
                            j = S.sorted_idx[s]
                            dist2 = min_image(S.x[j] - xi).norm_sqr()
                            rsum = ri + radius_of(j)
                            owned = False
                            if ti.static(layers):  # in i's slab the lower scene index owns a pair, in the next i
                                owned = (s >= ahead_from) | (ident < S.ident[j])
                            else:
                                sj = S.slab[j]
                                tie = (sj == si) | ((sj == ahead) & (sj == behind))
                                owned = ti.select(tie, ident < S.ident[j], sj == ahead)
                            # step 3's sort key: partner + (0 if it touches i, else capacity)
                            S.nbr_new[i, ti.min(count, K - 1)] = j + ti.select(dist2 < rsum * rsum, 0, capacity)
                            count += ti.cast(dist2 < (rsum + skin) * (rsum + skin), ti.i32) * ti.cast(owned, ti.i32)
            if count > K:
                ti.atomic_max(S.overflow[0], count)
                count = K
            for a in range(1, count):  # insertion sort by key (step 3)
                key = S.nbr_new[i, a]
                b = a - 1
                while b >= 0 and S.nbr_new[i, b] > key:
                    S.nbr_new[i, b + 1] = S.nbr_new[i, b]
                    b -= 1
                S.nbr_new[i, b + 1] = key
            touching = 0
            for a in range(count):
                key = S.nbr_new[i, a]
                touching += ti.cast(key < capacity, ti.i32)
                S.nbr_new[i, a] = ti.select(key >= capacity, key - capacity, key)
            S.nbr_count[i] = count
            S.nbr_touch[i] = touching
            group_rows(i, xi, ri, touching, count)
            S.x_build[i] = xi
            if ti.static(growth):
                S.r_build[i] = S.radius[i]
            match_row(i)

    @ti.func
    def group_rows(i, xi, ri, touching, count):
        """Step 5: the quiet partners (slots touching .. count - 1 of nbr_new, by index) in their groups by
        gap, each still by index (a stable counting sort through the scratch row `src`, which match_row
        writes after), with each group's end and smallest gap."""
        ends = ti.Vector([touching] * QUIET_GROUPS)  # where each quiet group ends in the row
        gaps = ti.Vector([QUIET] * QUIET_GROUPS, dt=ti.f32)  # each group's smallest gap
        for a in range(touching, count):
            j = S.nbr_new[i, a]
            gap = ti.cast(min_image(S.x[j] - xi).norm() - ri - radius_of(j), ti.f32)
            group = 0
            for b in ti.static(bounds):
                group += ti.cast(gap >= b, ti.i32)
            for g in ti.static(range(QUIET_GROUPS)):  # (selects: the groups follow no pattern to predict)
                gaps[g] = ti.select(group == g, ti.min(gaps[g], gap), gaps[g])
                ends[g] += ti.cast(group <= g, ti.i32)
            S.src[i, a] = j + group * capacity
        starts = ti.Vector([touching] * QUIET_GROUPS)  # where each group begins
        for g in ti.static(range(1, QUIET_GROUPS)):
            starts[g] = ends[g - 1]
        for a in range(touching, count):
            key = S.src[i, a]
            group = 0
            for g in ti.static(range(1, QUIET_GROUPS)):
                group += ti.cast(key >= g * capacity, ti.i32)
            at = starts[0]
            for g in ti.static(range(1, QUIET_GROUPS)):
                at = ti.select(group == g, starts[g], at)
            S.nbr_new[i, at] = key - group * capacity
            for g in ti.static(range(QUIET_GROUPS)):
                starts[g] += ti.cast(group == g, ti.i32)
        for g in ti.static(range(QUIET_GROUPS)):
            S.nbr_gap[i, g] = gaps[g]
            if ti.static(g < QUIET_GROUPS - 1):  # (the last group ends with the row)
                S.nbr_end[i, g] = ends[g]

    @ti.func
    def move_rows(n):
        """Step 4 (`kernels/history_carry.py`), then the `after` funcs: each particle's own work after a
        build, in the same loop."""
        for i in range(n):
            move_row(i)
            for then in ti.static(after):
                then(i)

    @ti.kernel
    def rebuild(n: ti.i32):
        count_cells(n)
        prefix_sums()
        scatter(n)
        if ti.static(slab_lists):
            list_slabs(n)
        S.flips[None] = 0
        build_rows(n)
        move_rows(n)
        # every particle is at its build position now: the next contact pass's quiet reach is its
        # rounding margin, not the displacement that called this build (`kernels/contact.py`)
        S.max_disp[None] = 0.0

    @ti.kernel
    def cell_order(n: ti.i32):
        count_cells(n)
        prefix_sums()
        scatter(n)
        S.sort_tail[None] = S.slab_start[n_slabs]  # the active particles fill sorted_idx up to there
        for i in range(n):
            if not S.active[i]:
                S.sorted_idx[ti.atomic_add(S.sort_tail[None], 1)] = i

    return rebuild, cell_order
