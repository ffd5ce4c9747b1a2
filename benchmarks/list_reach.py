"""What a scene's Verlet rows hold between neighbour builds, from a checkpoint: per particle the partners
that touched at the build, the quiet ones (apart then), how many of those a contact pass evaluates
(with them in one group: all of a row's where its nearest is within the pass's reach; in the groups of
`kernel_settings.quiet_bounds`: up to the last group whose nearest is within reach), and how many lie
within three bounds on how far two grains may have closed since the build:
  * "twice the largest": 2 max_k |D_k| (the pass's reach, `kernels/pair_contact.py`);
  * "own + largest": |D_i| + max_k |D_k| (a per-particle reach);
  * "pairwise": |D_i| + |D_j| (needs the partner's displacement);
with D the displacements since the build; and how the grains' displacements spread (quantiles over
the largest). Then, over a few build intervals, how many steps the skin lasts by the largest
displacement, and by the displacements relative to the mean velocity at the build of each cell of
CELL m (with and without the bound on the difference between adjacent cells, which makes it exact).

    python -P benchmarks/list_reach.py SCENE RUN_DIR [STEPS [CELL]]

RUN_DIR holds a checkpoint.npz of SCENE. STEPS (default 400) steps for the row figures; CELL default 0.004.
"""

import sys
from pathlib import Path

import numpy as np

from tidem.cli.common import build_or_exit, load_scene
from tidem.particles.overlaps import min_image
from tidem.runner import checkpoint
from tidem.runner.launch import load_checkpoint
from tidem.runtime import startup
from tidem.sim.kernel_settings import quiet_bounds
from tidem.sim.solver import Solver


def displacements(S, n, x0, lengths, periodic):
    return min_image(S.x.to_numpy()[:n] - x0, lengths, periodic)


def rows(solver, steps, lengths, periodic):
    S, n = solver.state, solver.n
    slot = np.arange(S.nbr.shape[1])
    tot = np.zeros(7)
    bounds = quiet_bounds(solver.model)
    for _ in range(steps):
        solver.advance(1)
        cnt, touch, nbr = S.nbr_n.to_numpy()[:n], S.nbr_touch.to_numpy()[:n], S.nbr.to_numpy()[:n]
        d = np.linalg.norm(displacements(S, n, S.x_build.to_numpy()[:n], lengths, periodic), axis=1)
        x, r = S.x_build.to_numpy()[:n], S.radius.to_numpy()[:n]
        i, k = np.nonzero((slot >= touch[:, None]) & (slot < cnt[:, None]))
        j = nbr[i, k]
        gap = np.linalg.norm(min_image(x[j] - x[i], lengths, periodic), axis=1) - r[i] - r[j]  # at the build
        reach = 2 * d.max()
        row_min = np.full(n, np.inf)
        np.minimum.at(row_min, i, gap)
        group = sum(gap >= b for b in bounds)
        last = np.full(n, -1)  # each row's last group whose nearest partner is within reach
        for g in range(len(bounds) + 1):
            group_min = np.full(n, np.inf)
            np.minimum.at(group_min, i[group == g], gap[group == g])
            last = np.where(group_min <= reach, g, last)
        tot += [touch.sum(), len(i), (row_min[i] <= reach).sum(), (group <= last[i]).sum(), (gap <= reach).sum(),
                (gap <= d[i] + d.max()).sum(), (gap <= d[i] + d[j]).sum()]
    per = tot / (n * steps)
    print(f"per particle, mean of {steps} steps: touching {per[0]:.2f}, quiet {per[1]:.2f}; of those a pass "
          f"evaluates {per[2]:.2f} with the quiet partners in one group, {per[3]:.2f} in {len(bounds) + 1} (quiet_bounds); "
          f"within twice the largest displacement {per[4]:.2f}, own + largest {per[5]:.2f}, pairwise {per[6]:.2f}")
    print("displacement quantiles 0.5 / 0.9 / 0.99 / 0.999 of the largest:",
          " / ".join(f"{q:.2f}" for q in np.quantile(d, [0.5, 0.9, 0.99, 0.999]) / d.max()))


def intervals(solver, cell, lengths, periodic, builds=4):
    S, n, skin = solver.state, solver.n, solver.model.skin
    nc = np.maximum((lengths / cell).astype(int), 1)
    for _ in range(builds):
        solver.rebuild()
        x0, v0 = S.x.to_numpy()[:n], S.v.to_numpy()[:n]
        c = np.minimum(((x0 - solver.model.grid.lo) / (lengths / nc)).astype(int), nc - 1)
        cid = np.ravel_multi_index(c.T, nc)
        count = np.bincount(cid, minlength=nc.prod())
        V = np.stack([np.bincount(cid, v0[:, a], minlength=nc.prod()) for a in range(3)], 1)
        V /= np.maximum(count, 1)[:, None]
        grid, occupied = V.reshape(*nc, 3), (count > 0).reshape(nc)
        G = 0.0
        for shift in np.ndindex(3, 3, 3):
            moved = grid, occupied
            for a, s in enumerate(shift):
                moved = np.roll(moved[0], s - 1, a), np.roll(moved[1], s - 1, a)
            diff = np.linalg.norm(grid - moved[0], axis=-1)
            G = max(G, diff[occupied & moved[1]].max())
        found = [None, None, None]
        for step in range(1, 400):
            solver.advance(1)
            tau = step * solver.dt
            d = displacements(S, n, x0, lengths, periodic)
            rel = 2 * np.linalg.norm(d - V[cid] * tau, axis=1).max()
            for m, bound in enumerate((2 * np.linalg.norm(d, axis=1).max(), rel + G * tau, rel)):
                if found[m] is None and bound > skin:
                    found[m] = step
            if None not in found:
                break
        print(f"skin lasts {found[0]} steps by the largest displacement; relative to the {cell * 1e3:g} mm cells' "
              f"mean motion {found[1]} (exact: adjacent cells differ by up to {G:.2f} m/s), {found[2]} without that term")


def main(scene: str, run_dir: str, steps: int = 400, cell: float = 0.004) -> None:
    startup.ensure_taichi("cpu", "float64", 2)
    loaded = load_scene(scene, [])
    model = build_or_exit(loaded)
    solver = Solver(model)
    checkpoint.restore(solver, *load_checkpoint(Path(run_dir), loaded, model))
    solver.advance(50)
    g = model.grid
    lengths, periodic = np.array(g.length), list(g.periodic)
    rows(solver, steps, lengths, periodic)
    intervals(solver, cell, lengths, periodic)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *[f(a) for f, a in zip((int, float), sys.argv[3:])])
