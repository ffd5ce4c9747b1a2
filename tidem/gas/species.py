"""O2 on the gas grid, set-up side (the transport kernel is `kernels/species.py`): the molar
mass and the mole-fraction to mass-fraction conversion shared by the gas phase and the
reactions that consume O2."""

M_O2 = 0.031998  # kg/mol


def o2_mass_fraction(mole_fraction: float, molar_mass: float) -> float:
    """Y_O2 = x_O2 M_O2 / M_gas (mean molar mass of the gas held constant)."""
    return mole_fraction * M_O2 / molar_mass
