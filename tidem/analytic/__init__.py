"""Closed-form and reference solutions that tidem's runs are compared with (Ergun, Schumann,
Kruczek, packed beds, fluidized-bed heat correlations). Layer 0: imports nothing of tidem outside analytic/."""
