"""Particle radius and mass as the kernels read them: loaded per particle, or, where all particles
have the same (`tidem.model.Model.uniform_particles`), constants of the kernel, which then loads
nothing and folds the products of constants (the contact law's m* and R*, the list's reach)."""

import taichi as ti


def make_sizes(S, uniform: tuple[float, float] | None):
    """Return Taichi funcs (radius_of(i), mass_of(i)); `uniform`: (radius, mass) of every particle, or None."""
    same = uniform is not None
    r_all, m_all = uniform if same else (0.0, 0.0)

    @ti.func
    def radius_of(i):
        r = r_all
        if ti.static(not same):
            r = S.radius[i]
        return r

    @ti.func
    def mass_of(i):
        m = m_all
        if ti.static(not same):
            m = S.mass[i]
        return m

    return radius_of, mass_of
