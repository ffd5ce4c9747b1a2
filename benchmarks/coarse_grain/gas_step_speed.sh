#!/bin/bash
# Side by side on two cores: k = 1 (interval 20) for 0.3 s on one; on the other, meanwhile, k = 3 at
# gas.coupling_interval 7, 10 and 20 (0.3 s each) in turns. Each run's wall_s is in OUT/NAME/run.json.
#   PATH=.venv/bin:$PATH benchmarks/coarse_grain/gas_step_speed.sh OUT
set -e
out=${1:?usage: gas_step_speed.sh OUT}
export TI_CPU_MAX_NUM_THREADS=1
scene=$(dirname "$0")/bubbling_tube_slab.toml
run() { tidem scene "$scene" --no-render --quiet --set numerics.t_end=0.3 --set "particles[0].coarse_grain=$1" \
  --set gas.coupling_interval=$2 --out "$out/$3"; }
mkdir -p "$out"
run 1 20 k1_i20 &
k1=$!
sleep 20
i=0
while kill -0 $k1 2>/dev/null; do
  i=$((i + 1)); run 3 7 "k3_i7_$i"; run 3 20 "k3_i20_$i"; run 3 10 "k3_i10_$i"
done
wait
for run in "$out"/*/run.json; do
  python3 -c "import json, sys; d = json.load(open(sys.argv[1])); print(sys.argv[1].split('/')[-2], d['status'], d['wall_s'])" "$run"
done
