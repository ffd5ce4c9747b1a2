"""Observables computed from a finished run.

contact_time: for every particle, the duration of its first contact (first touch to first
release, measured by the force kernel), next to the Hertz prediction for a head-on impact
with its nearest particle at t = 0, t_c = 2.868 (m*^2 / (R* E*^2 v))^(1/5) (Johnson 1985),
v the initial relative speed along the line of centres.
"""

from __future__ import annotations

import numpy as np

from tidem.kernels import contact_laws as cl
from tidem.timestep import hertz_contact_time


def contact_times(model, solver) -> list[dict]:
    S = solver.state
    start = S.touch_start.to_numpy()
    end = S.touch_end.to_numpy()
    x0, v0, r, m = model.x0, model.v0, model.radius, model.mass
    rows = []
    for i in range(model.capacity):
        d = np.linalg.norm(x0 - x0[i], axis=1)
        d[i] = np.inf
        j = int(np.argmin(d)) if model.capacity > 1 else i
        row = {"particle": i, "partner": j,
               "contact_time_s": float(end[i] - start[i]) if start[i] >= 0 and end[i] >= 0 else None}
        if j != i:
            n = (x0[j] - x0[i]) / d[j]
            speed = float(np.dot(v0[i] - v0[j], n))
            if speed > 0:
                e_star = model.pair_params[model.material[i], model.material[j], cl.ESTAR]
                m_eff = m[i] * m[j] / (m[i] + m[j])
                r_eff = r[i] * r[j] / (r[i] + r[j])
                row["impact_speed_m_s"] = speed
                row["hertz_contact_time_s"] = hertz_contact_time(m_eff, r_eff, e_star, speed)
        rows.append(row)
    return rows
