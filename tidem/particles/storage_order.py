"""Storage order: the particles re-sorted into cell order as the bed flows (as LAMMPS' atom
sorting does), so that partners that sit close in space sit close in memory.

Fills and benchmark beds start in cell order (`tidem.particles.placement.spatial_key`), but a flowing or
bubbling bed mixes within seconds of bed time and the force and neighbour loops then read
their partners from all over memory. Every `numerics.sort_interval` neighbour rebuilds the
Solver calls `sort_storage` right before the rebuild (in scenes of at least
SORT_MIN_PARTICLES that neither pour nor react nor time contacts):

1. the new order: active particles first, by broad-phase cell (x, then y, then z, the order
   the neighbour build scans), ties kept in the present order (a stable sort);
2. every per-particle field of the State (`State.particle_fields`, rows of the Verlet list and
   of the wall slots included) is permuted, on the device (`kernels/storage_sort.py`, the order
   handed to it in `sorted_idx`); `ident` follows, so that outputs still name each
   particle by its index in the scene (snapshots' `id`, error messages);
3. partner indices in `nbr` are renumbered; each row keeps its order and its history: the
   neighbour build that follows finds every old partner in its new row by index
   (`kernels/broadphase.py`) and so carries every contact's history over.

The order depends on positions only, at fixed steps, so float64 runs stay deterministic and a
resumed run bit-identical (the rebuild count, which times the sorts, is in the checkpoint).
This is the CPU's order. On a GPU the Solver takes the broad phase's counting sort as the order
instead (ties in the order its atomics give), computed on the device too, since copying particle
fields to the host at each sort made it the largest cost of a 700 000-grain run
(`benchmarks/README.md`).
"""

from __future__ import annotations

import numpy as np

from tidem.particles.placement import spatial_key

SORT_MIN_PARTICLES = 1024  # smaller scenes fit in cache in any order and keep theirs
SCRATCH = ("nbr_new", "src", "sorted_idx", "pcell")  # rewritten by the next neighbour build


def sorts_storage(feat, particles: int, pours: bool, sort_interval: int) -> bool:
    """Whether a run re-sorts its storage (module docstring): scenes with contacts of at least
    SORT_MIN_PARTICLES particles whose outputs do not follow particles by storage index (pours,
    reactions, contact timing), with `numerics.sort_interval` > 0; `feat` as `tidem.sim.model.Features`."""
    return bool(sort_interval) and feat.contacts and particles >= SORT_MIN_PARTICLES \
        and not (pours or feat.reactions or feat.contact_time)


def new_order(x: np.ndarray, active: np.ndarray, lo, cell: float) -> np.ndarray:
    """Storage permutation: order[new] = old; active particles first, in cell order."""
    key = spatial_key(x, lo, cell)
    key = np.where(active, key, key.max(initial=0) + 1)
    return np.argsort(key, kind="stable")


def sort_storage(S, lo, cell, permute, n: int) -> bool:
    """Permute the State's per-particle fields into cell order (module docstring) with `permute`
    (`kernels/storage_sort.make_storage_permuter`), n the slots in use. Returns False, doing nothing,
    when the storage is already in that order."""
    order = new_order(S.x.to_numpy(), S.active.to_numpy().astype(bool), lo, cell)
    if np.array_equal(order, np.arange(len(order))):
        return False
    permute_storage(S, permute, order, n)
    return True


def permute_storage(S, permute, order: np.ndarray, n: int) -> None:
    """Store particle order[k] at k for k < n (order[:n] a permutation of 0..n-1): every per-particle
    field permuted and partners renumbered by `permute` (steps 2-3 of the module docstring). The
    neighbour list must be rebuilt before the next force evaluation (the slab lists). A pair stays in
    its owner's row: ownership follows slabs and `ident`, which a new numbering leaves alone."""
    full = np.arange(S.sorted_idx.shape[0], dtype=np.int32)
    full[:n] = order[:n]
    S.sorted_idx.from_numpy(full)
    permute(n)


def scene_order(S, values: np.ndarray) -> np.ndarray:
    """A per-particle array read from the State, put back into the scene's (the Model's) order."""
    out = np.empty_like(values)
    out[S.ident.to_numpy()] = values
    return out
