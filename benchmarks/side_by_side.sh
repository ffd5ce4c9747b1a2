#!/usr/bin/env bash
# tidem and LIGGGHTS on the same settled beds, alternating within one call.
# Needs: liggghts (apt-get install -y --no-install-recommends liggghts) and a folder prepared
# as in shared/bench/peers/README.md (settle.lgt -> settled10k.dump -> tile_bed.py bed10k/50k/200k).
# Usage: benchmarks/side_by_side.sh PEERS_DIR [ROUNDS]
# Environment: TIDEM (the tidem command, default `tidem`), BEFORE (an older tidem command to
# run in the same rounds, e.g. "env PYTHONPATH=/path/to/old/tree python -m tidem"),
# PRECISIONS (default "float64 float32"), SIZES (default "10k 50k 200k").
set -euo pipefail
peers=$(cd "${1:?peers folder with bed*.data and bench.lgt}" && pwd)
rounds=${2:-3}
tidem=${TIDEM:-tidem}
for n in ${SIZES:-10k 50k 200k}; do
  steps=$([ "$n" = 200k ] && echo 1000 || ([ "$n" = 50k ] && echo 2000 || echo 3000))
  for r in $(seq "$rounds"); do
    for prec in ${PRECISIONS:-float64 float32}; do
      if [ -n "${BEFORE:-}" ]; then
        $BEFORE bench --bed "$peers/bed$n.data" --precision $prec --steps "$steps" --threads 2 | tail -n 1 | sed "s/^/before   $n r$r /"
      fi
      $tidem bench --bed "$peers/bed$n.data" --precision $prec --steps "$steps" --threads 2 | tail -n 1 | sed "s/^/tidem    $n r$r /"
    done
    (cd "$peers" && mpirun --allow-run-as-root --bind-to core -np 2 liggghts -in bench.lgt -var data "bed$n.data" \
        -var nwarm 300 -var nsteps "$steps" -log "log.sbs_$n" > /dev/null)
    loop=$(grep "^Loop time" "$peers/log.sbs_$n" | tail -1 | awk '{print $4}')
    atoms=$(grep "^Loop time" "$peers/log.sbs_$n" | tail -1 | awk '{print $12}')
    python3 -c "print(f'liggghts $n r$r 2 ranks loop {float(\"$loop\"):.2f} s  {int(\"$atoms\") * $steps / float(\"$loop\"):.3g} particle-steps/s')"
  done
done
