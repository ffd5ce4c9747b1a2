#!/bin/bash
# The GPU check of the run loop in one command: the laboratory bed at full resolution (700 000 grains, k = 1,
# snapshots every 0.02 s, no frames) as a run, developed and then measured from a checkpoint, this
# tree against a baseline tree, and the synchronised profile of the same developed state.
#   bash benchmarks/gpu_run_loop.sh OUT BASE [DEVELOP_S]
# (The figures of 2026-11-27; a checkpoint of one version need not resume in another, so against a tree
# from before 2026-11-28 use gpu_lab_bed.sh, which runs BASE from its fill.)
# OUT receives run_loop.log and the JSON results; BASE is the baseline tree (tidem/, with
# tidem/kernels and tidem/scenes as folders, e.g. `git archive` of the older commit). Steps, each
# with its own time limit:
# 1. develop: this tree runs the scene from its fill towards t = 0.25 s and is stopped by SIGTERM after
#    DEVELOP_S seconds (default 180), which writes its checkpoint (the run's own rate, from the fill);
# 2. after / before: each tree resumes a copy of that checkpoint for 0.05 s of bed time (run.json:
#    particle-steps/s and the run's sampled profile);
# 3. profile: `tidem bench --profile --fused --resume` of the same checkpoint, every phase edge waited
#    for (the synchronised profile that the run's profile is compared with; PROFILE_S=0 leaves it out).
set -u
out=${1:?usage: gpu_run_loop.sh OUT BASE [DEVELOP_S]}
base=${2:?usage: gpu_run_loop.sh OUT BASE [DEVELOP_S]}
develop=${3:-180}
arch=${ARCH:-cuda}
runs=${TMPDIR:-/tmp}/gpu_run_loop
rm -rf "$runs"
mkdir -p "$out" "$runs"
log=$out/run_loop.log
scene=${SCENE:-lab_fluidized_bundle}  # SCENE=fluidized_tube ARCH=cpu tries the script without a GPU
sets=(--set "particles[0].coarse_grain=1" --set output.interval=0.02)
after=(env PYTHONPATH="$PWD:${PYTHONPATH:-}" python3 -P -m tidem)
before=(env PYTHONPATH="$(cd "$base" && pwd):${PYTHONPATH:-}" python3 -P -m tidem)
source "$(dirname "$0")/step.sh"
STEP_TAIL=4
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>&1 | tee -a "$log"
step develop "$develop" "${after[@]}" scene $scene --arch "$arch" "${sets[@]}" --t-end 0.25 --no-render --quiet \
    --out "$runs/dev"
cp "$runs/dev/run.json" "$out/develop.run.json" 2>/dev/null
t1=$(python3 -c "import json; print(round(json.load(open('$runs/dev/run.json'))['time_s'] + 0.05, 6))") || exit 1
cp -r "$runs/dev" "$runs/before"
cp -r "$runs/dev" "$runs/prof"
step after ${AFTER_S:-150} "${after[@]}" scene $scene --arch "$arch" "${sets[@]}" --resume "$runs/dev" --t-end "$t1" --no-render \
    --quiet
cp "$runs/dev/run.json" "$out/after.run.json" 2>/dev/null
step before ${BEFORE_S:-170} "${before[@]}" scene $scene --arch "$arch" "${sets[@]}" --resume "$runs/before" --t-end "$t1" \
    --no-render --quiet
cp "$runs/before/run.json" "$out/before.run.json" 2>/dev/null
[ "${PROFILE_S:-100}" -gt 0 ] && step profile "${PROFILE_S:-100}" "${after[@]}" bench --arch "$arch" --profile $scene "${sets[@]}" --resume "$runs/prof" --fused \
    --steps 1000 --warmup 100 --out "$out/profile.json"
python3 - "$out" <<'EOF'
import json, sys
from pathlib import Path
out = Path(sys.argv[1])
for name in ("develop", "after", "before"):
    path = out / f"{name}.run.json"
    if path.is_file():
        d = json.loads(path.read_text())
        prof = {k: round(v["ms_per_step"], 3) for k, v in d.get("profile", {}).items()}
        print(name, d["status"], "t", d.get("time_s"), "steps", d.get("steps"), "wall", round(d.get("wall_s", 0), 1),
              "p-s/s %.3g" % d.get("particle_steps_per_s", 0), prof)
path = out / "profile.json"
if path.is_file():
    d = json.loads(path.read_text())
    print("profile p-s/s %.3g" % d["particle_steps_per_s"], {k: round(v["ms_per_step"], 3) for k, v in d["profile"].items()})
EOF
