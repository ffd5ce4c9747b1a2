"""The contact history carried across a neighbour build (`kernels/broadphase.py`, steps 3 and 4).

A rebuilt row lists its partners in a new order, some new, some gone; each pair that touches keeps
its history (tangential spring, rolling spring, largest overlap). `match_row(i)` finds, for each
partner that touches i, its slot in i's old row (`src[i, k]`: the old slot; -1 for a new pair and
for a partner apart, whose history is zero); a pair listed before in the partner's row (its owner
changed: one of the two crossed into another slab) takes its history from there, seen from the new
owner's side (springs change sign), through a buffer (`flip_*`, `src` = -2 - entry). It reads the
old rows only, so it runs in the loop that builds the new rows. `move_row(i)` then moves the row's
history into its new slots in place, in a loop of its own, so that no row changes while another
particle reads it.
"""

import taichi as ti


def make_history_carry(S, K: int, rolling: bool, hysteretic: bool):
    """Return the Taichi funcs (match_row(i), move_row(i)) over the State's rows (K slots: nbr, nbr_new,
    src, ft and, with `rolling` / `hysteretic`, mr / dmax; nbr_n, nbr_count, nbr_touch; the flip
    buffer and its count flips[None]; overflow[2] counts the pairs the buffer had no room for)."""
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    MOVED = K  # a `src` no slot has: the slot holds its new history (move_row)

    @ti.func
    def match_row(i):
        """src[i, k]: the new entry's slot in i's old row, -2 - its entry in the flip buffer when the
        partner's old row held the pair, -1 for a new pair and for a partner apart, whose history is zero
        (the build zeroed it): only the partners that touch are looked up. Reads the old rows only, so it runs
        in the loop that builds the new rows, row by row."""
        n_old = S.nbr_n[i]
        count = S.nbr_count[i]
        touching = ti.min(S.nbr_touch[i], count)  # (an inactive particle's nbr_touch is stale, its count 0)
        for k in range(touching, count):
            S.src[i, k] = -1
        for k in range(touching):
            j = S.nbr_new[i, k]
            found = -1
            for a in range(n_old):
                if S.nbr[i, a] == j:
                    found = a
                    break
            if found < 0:
                for m in range(S.nbr_n[j]):
                    if S.nbr[j, m] == i:  # the pair changed owner: its history, seen from i
                        b = ti.atomic_add(S.flips[None], 1)
                        if b < S.flip_ft.shape[0]:
                            S.flip_ft[b] = -S.ft[j, m]
                            if ti.static(rolling):
                                S.flip_mr[b] = -S.mr[j, m]
                            if ti.static(hysteretic):
                                S.flip_dmax[b] = S.dmax[j, m]
                            found = -2 - b
                        else:
                            ti.atomic_add(S.overflow[2], 1)
            S.src[i, k] = found

    @ti.func
    def history(i, k):
        """The history in slot k of i's row: tangential spring, rolling spring, largest overlap."""
        mr = zero3
        dmax = 0.0
        if ti.static(rolling):
            mr = S.mr[i, k]
        if ti.static(hysteretic):
            dmax = S.dmax[i, k]
        return S.ft[i, k], mr, dmax

    @ti.func
    def set_history(i, k, ft, mr, dmax):
        S.ft[i, k] = ft
        if ti.static(rolling):
            S.mr[i, k] = mr
        if ti.static(hysteretic):
            S.dmax[i, k] = dmax

    @ti.func
    def take_history(i, k, src):
        """Slot k of i's row takes its history from `src` (module docstring)."""
        if src >= 0:
            ft, mr, dmax = history(i, src)
            set_history(i, k, ft, mr, dmax)
        elif src == -1:
            set_history(i, k, zero3, zero3, 0.0)
        else:
            b = -2 - src
            mr = zero3
            dmax = 0.0
            if ti.static(rolling):
                mr = S.flip_mr[b]
            if ti.static(hysteretic):
                dmax = S.flip_dmax[b]
            set_history(i, k, S.flip_ft[b], mr, dmax)

    @ti.func
    def move_row(i):
        """Row i takes its new partners (nbr_new) and their history, in place (writes its own row only).
        The old partners are matched by now, so the row `nbr` first notes which new slot takes the
        history of each old slot (-1: none). A slot whose history no one takes is filled first, then
        the slot it took from, and so on along the chain; the slots left form cycles, each filled
        around from one saved history. `src` = MOVED marks a filled slot."""
        count = S.nbr_count[i]
        for a in range(ti.max(count, S.nbr_n[i])):
            S.nbr[i, a] = -1
        for k in range(count):
            if S.src[i, k] >= 0:
                S.nbr[i, S.src[i, k]] = k
        for p in range(count):
            if S.nbr[i, p] < 0:
                k = p
                while k < count:
                    src = S.src[i, k]
                    S.src[i, k] = MOVED
                    take_history(i, k, src)
                    k = src if src >= 0 else count
        for p in range(count):
            if S.src[i, p] != MOVED and S.src[i, p] != p:  # (a slot that keeps its history is left alone)
                ft, mr, dmax = history(i, p)
                k = p
                while S.src[i, k] != MOVED:
                    src = S.src[i, k]
                    S.src[i, k] = MOVED
                    if src == p:
                        set_history(i, k, ft, mr, dmax)
                    else:
                        take_history(i, k, src)
                        k = src
        for k in range(count):
            S.nbr[i, k] = S.nbr_new[i, k]
        S.nbr_n[i] = count


    return match_row, move_row
