#!/bin/bash
# Side by side on two cores: k = 1 (interval 20) for 0.3 s on one; on the other, meanwhile, k = 3 variants
# (0.3 s each) in turns: by default at gas.coupling_interval 7, 10 and 20; or those named, each NAME="--set ...".
# A variant's own `--set particles[0].coarse_grain=K` overrides the 3. SCENE=FILE runs another bed (default
# bubbling_tube_slab.toml). Each run's wall_s is in OUT/NAME_ROUND/run.json.
#   PATH=.venv/bin:$PATH [SCENE=FILE] benchmarks/coarse_grain/gas_step_speed.sh OUT [NAME="--set KEY=VALUE ..." ...]
set -e
out=${1:?usage: gas_step_speed.sh OUT [NAME="--set KEY=VALUE ..." ...]}
shift
variants=("$@")
[ ${#variants[@]} -gt 0 ] || variants=("k3_i7=--set gas.coupling_interval=7" "k3_i20=--set gas.coupling_interval=20"
                                      "k3_i10=--set gas.coupling_interval=10")
export TI_CPU_MAX_NUM_THREADS=1
scene=${SCENE:-$(dirname "$0")/bubbling_tube_slab.toml}
run() { local name=$1; shift; tidem scene "$scene" --no-render --quiet --set numerics.t_end=0.3 "$@" --out "$out/$name"; }
mkdir -p "$out"
run k1_i20 --set particles[0].coarse_grain=1 --set gas.coupling_interval=20 &
k1=$!
sleep 20
i=0
while kill -0 $k1 2>/dev/null; do
  i=$((i + 1))
  for v in "${variants[@]}"; do
    # shellcheck disable=SC2086  # the variant's sets split into words
    run "${v%%=*}_$i" --set particles[0].coarse_grain=3 ${v#*=}
  done
done
wait
for run in "$out"/*/run.json; do
  python3 -c "import json, sys; d = json.load(open(sys.argv[1])); print(sys.argv[1].split('/')[-2], d['status'], d['wall_s'])" "$run"
done
