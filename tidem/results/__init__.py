"""Measurements of a run: the observables registry, the tables drawn from a solver's state
(tables), the time series' statistics (hydrodynamics), the sampled particle statistics, local
averages and packed-bed profiles. They take a Model and Solver as arguments and import neither.
Layer 4: may import heat/, particles/, gas/, walls/ and layer 0."""
