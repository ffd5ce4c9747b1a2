"""Closed-form and reference solutions that tidem's runs are compared with."""
