"""Files a run writes and reads back: ParaView snapshots (vtp + pvd), the time series, mesh output.
Layer 0: imports nothing of tidem outside io/."""
