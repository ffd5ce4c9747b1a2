"""Particle radius and mass as the kernels read them: loaded per particle, or, where all particles
have the same (`tidem.sim.model.Model.uniform_particles`), constants of the kernel, which then loads
nothing and folds the products of constants (the contact law's m* and R*, the list's reach)."""

import taichi as ti


def make_sizes(S, uniform: tuple[float, float] | None):
    """Return Taichi funcs (radius_of(i), mass_of(i)); `uniform`: (radius, mass) of every particle, or None."""
    same = uniform is not None
    r_all, m_all = uniform if same else (0.0, 0.0)
    return _reader(S.radius, r_all, same), _reader(S.mass, m_all, same)


def _reader(field, value: float, constant: bool):
    """A Taichi func of i: `value` where `constant`, else field[i]."""

    @ti.func
    def read(i):
        v = value
        if ti.static(not constant):
            v = field[i]
        return v

    return read
