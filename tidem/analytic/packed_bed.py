"""A packed bed heated (or cooled) by a gas in plug flow: the data that the Schumann solution
(`schumann.py`) and source 4's explicit scheme (`kruczek.py`) share.

Per unit bed volume: ha the gas-solid heat-transfer coefficient times the specific surface
[W/(m^3 K)], rho_c_solid = (1 - eps) rho_s c_s [J/(m^3 K)], rho_c_gas = eps rho_g c_g
[J/(m^3 K)]; per unit cross-section: g_c = G c_g, the heat-capacity flux of the gas
[W/(m^2 K)] (G the superficial mass flux). Plug flow, no axial conduction, constant
properties; the bed starts at T_0 and the gas enters at T_in from t = 0 on.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PackedBed:
    """Properties of a uniform packed bed (units in the module docstring)."""

    ha: float
    rho_c_solid: float
    g_c: float
    rho_c_gas: float
    t_in: float
    t_0: float

    def __post_init__(self):
        for key in ("ha", "rho_c_solid", "g_c"):
            if not getattr(self, key) > 0:
                raise ValueError(f"PackedBed.{key} must be > 0 (got {getattr(self, key)})")
        if self.rho_c_gas < 0:
            raise ValueError(f"PackedBed.rho_c_gas must be >= 0 (got {self.rho_c_gas})")

    @property
    def interstitial_speed(self) -> float:
        """Speed of the gas between the particles [m/s]: G c_g / (eps rho_g c_g) (infinite without holdup)."""
        return self.g_c / self.rho_c_gas if self.rho_c_gas > 0 else float("inf")

    def distance(self, z):
        """Schumann's dimensionless distance xi = ha z / (G c_g)."""
        return self.ha * z / self.g_c

    def time(self, z, t):
        """Schumann's dimensionless time eta = ha (t - z/v) / ((1 - eps) rho_s c_s), v the interstitial speed."""
        return self.ha * (t - z / self.interstitial_speed) / self.rho_c_solid
