#!/usr/bin/env bash
# Coarse-graining verification in the moving bed (docs/coarse_graining.md): the reduced
# moving_bed_tubes of benchmarks/tradeoff/ (one heated 27 mm tube, 8.4 mm slab, plate moving
# from 0.05 s, 0.12 s of bed time) with 1 mm grains, 22 000 of them at every k, k = 1 and 2,
# three seeds each.   usage: benchmarks/coarse_grain/moving_bed.sh OUT_DIR
set -euo pipefail
MB=(--set 'tubes=[{center=[0.0185,0.0,0.045],axis="y",diameter=0.027,material="steel",friction=0.4,temperature=373.15}]'
    --set 'domain.max=[0.037,0.0084,0.215]'
    --set 'particles[0].region={min=[0.0,0.0,0.0],max=[0.037,0.0084,0.085]}' --set 'particles[0].count=22000'
    --set 'particles[0].lattice="hexagonal"'
    --set outlet.start=0.05 --set heat.profile_start=0.05 --set numerics.t_end=0.12 --set output.snapshots=3)
tidem tradeoff moving_bed_tubes "${MB[@]}" --vary 'particles[0].coarse_grain=1,2' --vary 'particles[0].seed=1,2,3' \
  --reference 0 --out "$1"
