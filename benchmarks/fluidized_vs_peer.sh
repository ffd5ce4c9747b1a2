#!/usr/bin/env bash
# `fluidized_tube --t-end 0.3 --no-render` against the 10k peer bed in float64, and
# optionally an older tree's fluidized_tube, alternating within one call (this VM is noisy: compare
# only figures of one run of this script). Prints each run's particle-steps/s and its phase profile.
#   benchmarks/fluidized_vs_peer.sh WORKDIR [ROUNDS] [BASE]
# BASE: an older tree laid out as an installed package (git archive REV | tar -x -C BASE, then
# kernels/ and scenes/ copied into BASE/tidem/), run with PYTHONPATH=BASE python -P. The peer bed takes
# PEER_STEPS steps (default 10000, about 4 s: the bench's 2000 let a moment's slowing of the VM decide a
# round).
set -euo pipefail
work=${1:?usage: fluidized_vs_peer.sh WORKDIR [ROUNDS] [BASE]}
rounds=${2:-3}
base=${3:-}
here="$(cd "$(dirname "$0")/.." && pwd)"
py="$here/.venv/bin/python"
mkdir -p "$work"
cd "$work"  # not a source tree: with -P, python imports the tree named by PYTHONPATH, else the installed one
profile() {
  "$py" -c "
import json, sys
d = json.load(open(sys.argv[1]))
print('    ' + ', '.join(f'{k} {v[\"ms_per_step\"]:.3f}' for k, v in d['profile'].items()) + ' ms/step')" "$1/run.json"
}
peer() {
  "$py" -P -m tidem bench --sizes 10000 --precision float64 --steps "${PEER_STEPS:-10000}" 2>&1 | tail -1 | sed "s/^/round $1 peer bed:/"
}
for r in $(seq 1 "$rounds"); do
  # the peer bed first in odd rounds and last in even ones, so that a VM slowing through a round
  # biases neither side
  if [ $((r % 2)) = 1 ]; then peer "$r"; fi
  names=this
  [ -n "$base" ] && names=$([ $((r % 2)) = 1 ] && echo "base this" || echo "this base")
  for name in $names; do
    path=$([ "$name" = base ] && echo "$base" || echo "")  # this tree: the installed (editable) package
    rm -rf "$work/ft_$name"
    PYTHONPATH="$path" "$py" -P -m tidem scene fluidized_tube --t-end 0.3 --no-render --out "$work/ft_$name" 2>&1 \
      | grep finished | sed "s/^/round $r fluidized_tube ($name): /"
    profile "$work/ft_$name"
  done
  if [ $((r % 2)) = 0 ]; then peer "$r"; fi
done
