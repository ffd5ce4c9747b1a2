"""Contact laws against analytic results (Hertz theory; Chung & Ooi 2011 tests 1 and 2;
restitution of the linear and hysteretic laws; energy conservation)."""

import math

import numpy as np
import pytest

from tests.conftest import make_scene

# Chung & Ooi (2011) test 1 material: E = 4.8e10 Pa, nu = 0.2, rho = 2800 kg/m3, R = 0.01 m, v = 10 m/s.
GLASS = {"density": 2800.0, "youngs_modulus": 4.8e10, "poisson_ratio": 0.2, "restitution": 1.0, "friction": 0.0}
R = 0.01
V = 10.0


def hertz(m_eff, r_eff, e_star, v):
    d_max = (15 * m_eff * v**2 / (16 * e_star * math.sqrt(r_eff))) ** 0.4
    f_max = 4.0 / 3.0 * e_star * math.sqrt(r_eff) * d_max**1.5
    t_c = 2.868 * (m_eff**2 / (r_eff * e_star**2 * v)) ** 0.2
    return d_max, f_max, t_c


def record_impact(solver, overlap_of, max_steps=20000):
    """Step until the first contact ends; return (contact time, peak force, peak overlap)."""
    S = solver.state
    t_start = None
    f_peak = d_peak = 0.0
    for _ in range(max_steps):
        solver.step()
        d = overlap_of(S)
        if d > 0:
            if t_start is None:
                t_start = solver.t - solver.dt
            f_peak = max(f_peak, float(np.linalg.norm(S.f[0].to_numpy())))
            d_peak = max(d_peak, d)
        elif t_start is not None:
            return solver.t - solver.dt - t_start, f_peak, d_peak
    raise AssertionError("contact did not end")


def test_chung_ooi_1_sphere_sphere_elastic(solver_for):
    gap = 1e-5
    raw = make_scene(
        materials={"glass": GLASS},
        particles=[{"name": "p", "material": "glass", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[-R - gap, 0, 0], [R + gap, 0, 0]], "velocities": [[V / 2, 0, 0], [-V / 2, 0, 0]]}],
        numerics={"dt_fraction": 0.02, "t_end": 1.0},
    )
    s = solver_for(raw)
    t_c, f_peak, d_peak = record_impact(s, lambda S: 2 * R - (S.x[1][0] - S.x[0][0]))
    m = 2800 * 4 / 3 * math.pi * R**3
    e_star = 4.8e10 / (2 * (1 - 0.2**2))
    d_max, f_max, t_ref = hertz(m / 2, R / 2, e_star, V)
    assert d_peak == pytest.approx(d_max, rel=0.02)
    assert f_peak == pytest.approx(f_max, rel=0.02)
    assert t_c == pytest.approx(t_ref, rel=0.02)


def test_chung_ooi_2_sphere_wall_elastic(solver_for):
    """Sphere against a rigid-like wall (wall material much stiffer): E* -> E/(1-nu^2)."""
    raw = make_scene(
        domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "walls": ["z-"], "wall_material": "wall",
                "gravity": [0.0, 0.0, 0.0]},
        materials={"glass": GLASS, "wall": {**GLASS, "youngs_modulus": 4.8e16}},
        particles=[{"name": "p", "material": "glass", "diameter": {"distribution": "mono", "value": 2 * R},
                    "positions": [[0, 0, -0.1 + R + 1e-5]], "velocities": [[0, 0, -V]]}],
        numerics={"dt_fraction": 0.02, "t_end": 1.0},
    )
    s = solver_for(raw)
    t_c, f_peak, d_peak = record_impact(s, lambda S: R - (S.x[0][2] + 0.1))
    m = 2800 * 4 / 3 * math.pi * R**3
    e_star = 1.0 / ((1 - 0.2**2) / 4.8e10 + (1 - 0.2**2) / 4.8e16)
    d_max, f_max, t_ref = hertz(m, R, e_star, V)
    assert d_peak == pytest.approx(d_max, rel=0.02)
    assert f_peak == pytest.approx(f_max, rel=0.02)
    assert t_c == pytest.approx(t_ref, rel=0.02)


@pytest.mark.parametrize("law", ["linear", "hysteretic"])
def test_restitution_sweep(solver_for, law):
    """Rebound speed / impact speed equals the restitution coefficient within 1 %.

    The linear dashpot pulls at the end of a contact; the step in which the overlap closes
    applies that pull for a whole step, an O(dt) error of up to 2 zeta omega_0 dt, so the
    linear law needs a finer step (dt_fraction 0.002) for 1 %.
    """
    es = [0.1, 0.3, 0.5, 0.7, 0.9]
    mats = {}
    groups = []
    for k, e in enumerate(es):
        mats[f"m{k}"] = {**GLASS, "youngs_modulus": 1e7, "restitution": e}
        groups.append({"name": f"g{k}", "material": f"m{k}", "diameter": {"distribution": "mono", "value": 2 * R},
                       "positions": [[-R - 1e-4, 0.05 * k, 0], [R + 1e-4, 0.05 * k, 0]],
                       "velocities": [[0.5, 0, 0], [-0.5, 0, 0]]})
    raw = make_scene(
        domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.3, 0.1], "walls": "none", "gravity": [0.0, 0.0, 0.0]},
        contact={"model": law}, materials=mats, particles=groups,
        numerics={"dt_fraction": 0.002 if law == "linear" else 0.02, "t_end": 1.0},
    )
    s = solver_for(raw)
    t_load = math.pi * math.sqrt((2800 * 4 / 3 * math.pi * R**3 / 2) / (1e7 * 2 * R / 2))
    while s.t < t_load or s.state.ncontact.to_numpy().any():
        s.step()
        assert s.t < 20 * t_load, "all pairs separate"
    v = s.state.v.to_numpy()
    for k, e in enumerate(es):
        rebound = (v[2 * k + 1, 0] - v[2 * k, 0]) / 1.0
        assert rebound == pytest.approx(e, rel=0.01), f"e = {e}"


def test_energy_conserved_elastic_frictionless(solver_for):
    """e = 1, no friction: kinetic energy between collisions drifts < 0.5 % over 10^4 steps."""
    rng = np.random.default_rng(3)
    pos = [[x, y, z] for x in (-0.06, -0.02, 0.02, 0.06) for y in (-0.06, -0.02, 0.02, 0.06) for z in (-0.04, 0.04)]
    vel = rng.normal(0, 15.0, (len(pos), 3)).tolist()
    raw = make_scene(
        domain={"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "gravity": [0.0, 0.0, 0.0],
                "walls": ["x-", "x+", "y-", "y+", "z-", "z+"]},
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 0.02},
                    "positions": pos, "velocities": vel}],
        numerics={"dt_fraction": 0.1, "t_end": 1.0},
    )
    s = solver_for(raw)
    e0 = s.energies()["kinetic_energy_J"]
    worst, collisions = 0.0, 0
    for k in range(10000):
        s.step()
        if k % 10 == 0:
            en = s.energies()
            if en["coordination"] == 0:
                worst = max(worst, abs(en["kinetic_energy_J"] / e0 - 1))
            else:
                collisions += 1
    assert collisions > 20, "the test must include collisions"
    assert worst < 0.005


@pytest.mark.parametrize("moving_first, precision", [(True, "float64"), (False, "float64"), (False, "mixed")])
def test_oblique_impact_conserves_momentum_and_spins_both_spheres_alike(solver_for, moving_first, precision):
    """Each contact is evaluated in its owner's row (in one slab, the lower scene index) and added to
    both spheres: whichever sphere owns the pair, an oblique frictional impact of equal spheres, one
    at rest, leaves total momentum unchanged and gives both spheres the same spin, r n x J_t (Newton's
    third law for the tangential impulse at the shared contact point). With precision 'mixed' the
    spring is kept in float32 and both spheres take the same float64 force."""
    r = 0.005
    x = [[-2.0 * r, 0.0, 0.0], [0.0, 0.6 * r, 0.0]]  # offset along y: an oblique hit
    v = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    if not moving_first:
        x, v = x[::-1], v[::-1]
    raw = make_scene(
        materials={"steel": {"density": 7800.0, "youngs_modulus": 2e9, "poisson_ratio": 0.3, "restitution": 0.8,
                             "friction": 0.4}},
        particles=[{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 2 * r},
                    "positions": x, "velocities": v}],
        numerics={"dt_fraction": 0.05, "t_end": 1.0, "precision": precision},
    )
    s = solver_for(raw)
    S = s.state
    p0 = S.v.to_numpy().sum(axis=0)
    touched = False
    for _ in range(20000):
        s.step()
        apart = np.linalg.norm(S.x[1].to_numpy() - S.x[0].to_numpy()) > 2 * r
        touched |= not apart
        if touched and apart:
            break
    assert touched and apart
    w = S.w.to_numpy()
    assert abs(w[0, 2]) > 1.0  # rad/s: friction spun them about z
    np.testing.assert_allclose(w[1], w[0], rtol=1e-9, atol=1e-9 * abs(w[0, 2]))
    np.testing.assert_allclose(S.v.to_numpy().sum(axis=0), p0, atol=1e-12)


def test_spring_rotation_keeps_the_length_in_the_new_tangent_plane():
    """rotate_into_plane (kernels/contact_laws.py): the spring ends normal to n with its length, for a
    turn of 1e-6 rad (a step's) and of 1 rad; a zero spring stays zero."""
    import taichi as ti

    from tidem.kernels.contact_laws import rotate_into_plane

    rng = np.random.default_rng(3)
    cases = []
    for angle in (1e-6, 1.0, 0.0):
        h = rng.normal(size=3)
        n_old = np.cross(h, rng.normal(size=3))
        n_old /= np.linalg.norm(n_old)  # h lies in the plane normal to n_old
        axis = np.cross(n_old, rng.normal(size=3))
        axis /= np.linalg.norm(axis)
        n = n_old * math.cos(angle) + np.cross(axis, n_old) * math.sin(angle)
        cases.append((h if angle > 0 else np.zeros(3), n))
    h_in, n_in, out = (ti.Vector.field(3, ti.f64, shape=len(cases)) for _ in range(3))
    h_in.from_numpy(np.array([c[0] for c in cases]))
    n_in.from_numpy(np.array([c[1] for c in cases]))

    m = len(cases)

    @ti.kernel
    def rotate():
        for k in range(m):
            out[k] = rotate_into_plane(h_in[k], n_in[k])

    rotate()
    got = out.to_numpy()
    for (h, n), g in zip(cases, got):
        assert abs(g @ n) < 1e-14 * max(np.linalg.norm(h), 1.0)
        assert np.linalg.norm(g) == pytest.approx(np.linalg.norm(h), rel=1e-13, abs=0.0)
