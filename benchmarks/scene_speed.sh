#!/usr/bin/env bash
# Shipped scenes before and after a change, alternating, three seeds each:
# particle-steps/s and the scene's observables from run.json (their spread over the seeds is
# the yardstick for "unchanged"). No frames are rendered.
# Usage: BEFORE="env PYTHONPATH=/old/tree python -P -m tidem" benchmarks/scene_speed.sh OUT SCENE:T_END ...
#   e.g. benchmarks/scene_speed.sh /tmp/speed fluidized_tube:0.3 moving_bed_tubes:0.15
# Environment: TIDEM (the tidem command, default `tidem`), BEFORE (optional), SEEDS (default "1 2 3").
set -euo pipefail
out=$(mkdir -p "${1:?output folder}" && cd "$1" && pwd); shift
tidem=${TIDEM:-tidem}
for case in "$@"; do
  scene=${case%%:*}; t_end=${case##*:}
  for seed in ${SEEDS:-1 2 3}; do
    for version in before after; do
      cmd=$tidem; [ "$version" = before ] && cmd=${BEFORE:-}
      [ -z "$cmd" ] && continue
      dir="$out/$scene/$version/seed$seed"; mkdir -p "$(dirname "$dir")"
      (cd "$(dirname "$dir")" && $cmd scene "$scene" --t-end "$t_end" --no-render --quiet --out "$dir" \
        --set "particles[0].seed=$seed" > "$dir.log" 2>&1) || { echo "failed: $dir (see $dir.log)"; continue; }
      python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(f'{sys.argv[2]:18} {sys.argv[3]:6} seed {sys.argv[4]}  {d[\"particle_steps_per_s\"]:.3g} particle-steps/s  wall {d[\"wall_s\"]:.1f} s  steps {d[\"steps\"]}')" \
        "$dir/run.json" "$scene" "$version" "$seed"
    done
  done
done
python3 "$(dirname "$0")/scene_speed_table.py" "$out"
