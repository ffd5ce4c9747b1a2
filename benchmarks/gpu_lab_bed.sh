#!/bin/bash
# On a GPU: the laboratory bed at full resolution (`lab_fluidized_bundle` at
# k = 1: 700 000 grains, snapshots every 0.02 s, overlaps up to 20 % of a radius, no frames, float64), run
# from the repository root:
#   bash benchmarks/gpu_lab_bed.sh OUT [PARTS]
# PARTS (default "full profile resume"), each with its own time limit (seconds in brackets):
# full     this tree runs the scene from its fill to T_END (default 1 s) [FULL_S, 420]: the observables
#          (run.json) and, from the snapshots' write times, the stepping rate over each stretch of bed time;
# profile  `tidem bench --profile --fused --resume` of full's last checkpoint [70]: every phase edge waited
#          for, the synchronised profile of the developed bed;
# resume   the same checkpoint run on for 0.05 s of bed time [90]: the run's rate and its sampled profile
#          (run.json), to compare with profile's;
# base     the tree BASE (`git archive` of an older commit, tidem/kernels and tidem/scenes as folders)
#          from its fill to BASE_T_END (default 0.3 s) [BASE_S, 200]: the older tree over the same stretches
#          of bed time (one version's checkpoint need not resume in another).
# OUT receives run_loop.log, summary.txt and the runs' run.json files; the runs go to ${TMPDIR:-/tmp}/gpu_lab_bed.
# ARCH=cpu SCENE=fluidized_tube SETS= T_END=0.05 tries the script without a GPU.
set -u
out=${1:?usage: gpu_lab_bed.sh OUT [PARTS]}
parts=" ${2:-full profile resume} "
arch=${ARCH:-cuda}
scene=${SCENE:-lab_fluidized_bundle}
t_end=${T_END:-1.0}
read -r -a sets <<<"${SETS-"--set particles[0].coarse_grain=1 --set output.interval=0.02 --set numerics.max_overlap=0.2"}"
runs=${TMPDIR:-/tmp}/gpu_lab_bed
mkdir -p "$out" "$runs"
log=$out/run_loop.log
tree() {  # tree SRC DEST: a package folder of SRC (tidem/ with kernels/ and scenes/ moved inside)
    rm -rf "$2" && mkdir -p "$2" && cp -r "$1/tidem" "$2/"
    [ -d "$1/kernels" ] && cp -r "$1/kernels" "$2/tidem/kernels"
    [ -d "$1/scenes" ] && cp -r "$1/scenes" "$2/tidem/scenes"
}
copy_run() {  # copy_run SRC DEST: a run folder without its snapshots (a resume appends to them)
    rm -rf "$2" && mkdir -p "$2" && find "$1" -maxdepth 1 -type f -exec cp {} "$2/" \;
}
tree . "$runs/after_tree"
tidem=(env PYTHONPATH="$runs/after_tree:${PYTHONPATH:-}" python3 -P -m tidem)
source "$(dirname "$0")/step.sh"
STEP_TAIL=4
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>&1 | tee -a "$log"
if [[ $parts == *" full "* ]]; then
    rm -rf "$runs/full"
    step full "${FULL_S:-420}" "${tidem[@]}" scene $scene --arch "$arch" "${sets[@]}" --t-end "$t_end" --no-render \
        --quiet --out "$runs/full"
fi
t1=$(python3 -c "import json; print(round(json.load(open('$runs/full/run.json'))['time_s'] + 0.05, 6))" 2>/dev/null)
if [[ $parts == *" profile "* ]]; then  # numerics.t_end past the checkpoint's time, which a resume needs
    copy_run "$runs/full" "$runs/prof"
    step profile 70 "${tidem[@]}" bench --arch "$arch" --profile $scene "${sets[@]}" --set "numerics.t_end=$t1" \
        --resume "$runs/prof" --fused --steps 1000 --warmup 100 --out "$out/profile.json"
fi
if [[ $parts == *" resume "* ]]; then
    copy_run "$runs/full" "$runs/resume"
    step resume 90 "${tidem[@]}" scene $scene --arch "$arch" "${sets[@]}" --resume "$runs/resume" --t-end "$t1" \
        --no-render --quiet
fi
if [[ $parts == *" base "* ]]; then
    tree "${BASE:?BASE= the older tree}" "$runs/base_tree"
    rm -rf "$runs/base"
    step base "${BASE_S:-200}" env PYTHONPATH="$runs/base_tree:${PYTHONPATH:-}" python3 -P -m tidem scene $scene \
        --arch "$arch" "${sets[@]}" --t-end "${BASE_T_END:-0.3}" --no-render --quiet --out "$runs/base"
fi
for run in full resume base; do
    [ -f "$runs/$run/run.json" ] && cp "$runs/$run/run.json" "$out/$run.run.json"
done
[[ $parts == *" full "* ]] && cp "$runs/full/timeseries.csv" "$out/full.timeseries.csv" 2>/dev/null
python3 "$(dirname "$0")/gpu_lab_bed_summary.py" "$runs" "$out" | tee "$out/summary.txt"
