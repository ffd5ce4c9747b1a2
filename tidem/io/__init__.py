"""Run output: ParaView snapshots, time series, run summary."""
