"""Pouring: particles of a group appear at random places in a region at a set rate.

At time t a group with rate R [1/s] starting at t0 should have min(count, R (t - t0))
particles in the domain. Missing ones are placed at random points of the pour region that
clear every active particle, wall, tube and mesh wall (a moving mesh where it is at time t;
rejection sampling, at most 30 tries per particle and step); whatever does not fit waits for
the next step.
"""

from __future__ import annotations

import numpy as np

from tidem.particles.placement import clear_of_obstacles


class Pourer:
    """Activates poured particles as time goes on."""

    def __init__(self, model, state):
        self.model = model
        self.state = state
        self.groups = [dict(p) for p in model.pours]
        for g in self.groups:
            g["rng"] = np.random.default_rng(g["seed"] + 7919)
        self.lengths = np.array(model.grid.length)
        self.periodic = model.grid.periodic
        self._next_check = 0.0

    @property
    def done(self) -> bool:
        return all(g["inserted"] >= g["count"] for g in self.groups)

    def insert(self, t: float) -> int:
        """Insert what is due at time t; returns the number inserted."""
        if self.done or t < self._next_check:
            return 0
        self._next_check = t + 20 * self.model.dt  # batch insertions
        S, m = self.state, self.model
        x = active = meshes = None
        added = 0
        for g in self.groups:
            due = min(g["count"], int(g["rate"] * max(t - g["start"], 0.0))) - g["inserted"]
            if due <= 0:
                continue
            if x is None:
                x = S.x.to_numpy()
                active = S.active.to_numpy()
                v = S.v.to_numpy()
            if meshes is None:  # mesh walls where they are at time t
                meshes = [(w.points_at(t), w.triangles) for w in getattr(m, "meshes", None) or []]
            lo, hi = np.array(g["region"].min), np.array(g["region"].max)
            for k in range(due):
                i = g["first"] + g["inserted"]
                r = m.radius[i]
                for _ in range(30):
                    p = g["rng"].uniform(lo + r, hi - r)
                    if not clear_of_obstacles(p[None], r, [(q["p0"], q["n"]) for q in m.planes],
                                              [(q["c"], q["mask"], q["r"]) for q in m.tubes],
                                              self.lengths, self.periodic, meshes)[0]:
                        continue
                    near = active.astype(bool)
                    d = x[near] - p
                    for a in range(3):
                        if self.periodic[a]:
                            d[:, a] -= self.lengths[a] * np.round(d[:, a] / self.lengths[a])
                    if np.all(np.linalg.norm(d, axis=1) > m.radius[near] + r):
                        x[i] = p
                        v[i] = m.v0[i]
                        active[i] = 1
                        g["inserted"] += 1
                        added += 1
                        break
                else:
                    break
        if added:
            S.x.from_numpy(x)
            S.v.from_numpy(v)
            S.active.from_numpy(active)
        return added
