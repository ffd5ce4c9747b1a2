#!/bin/bash
# The GPU figures of benchmarks/README.md in one command, on a machine with an NVIDIA GPU and tidem
# importable (installed, or this tree on PYTHONPATH with tidem/kernels and tidem/scenes linked):
#   bash benchmarks/gpu_check.sh OUT [SIZES]
# 1. the peer bed at 10k on CUDA, float64 (stops here if CUDA does not run it);
# 2. the peer bed at SIZES (default 200000,1000000) on CUDA, float32 and float64;
# 3. the first of SIZES, float64, on every CPU core of that machine (the side-by-side ratio);
# 4. fluidized_tube by phase on CUDA (`tidem bench --profile`), and its first 0.1 s as a run on CUDA
#    and on the CPU cores (run.json: particle-steps/s and the observables).
# Each step has its own time limit. OUT receives gpu_check.log (every step's output) and the JSON
# results; the runs' folders go to ${TMPDIR:-/tmp}/gpu_check_runs. ARCH=cpu tries the script without a GPU.
set -u
out=${1:?usage: gpu_check.sh OUT [SIZES]}
sizes=${2:-200000,1000000}
arch=${ARCH:-cuda}
runs=${TMPDIR:-/tmp}/gpu_check_runs
mkdir -p "$out" "$runs"
log=$out/gpu_check.log
tidem=(python3 -P -m tidem)
cores=$(nproc)
source "$(dirname "$0")/step.sh"
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>&1 | tee -a "$log"
step peer10k 60 "${tidem[@]}" bench --arch "$arch" --sizes 10000 --precision float64 --out "$out/peer10k.json"
grep -q particle_steps_per_s "$out/peer10k.json" 2>/dev/null || { echo "$arch does not run the peer bed; stopping"; exit 1; }
step peer_large 90 "${tidem[@]}" bench --arch "$arch" --sizes "$sizes" --precision both --out "$out/peer_large.json"
step peer_cpu 40 "${tidem[@]}" bench --threads "$cores" --sizes "${sizes%%,*}" --precision float64 \
    --out "$out/peer_cpu.json"
step profile 60 "${tidem[@]}" bench --arch "$arch" --profile fluidized_tube --steps 2000 --warmup 300 \
    --out "$out/profile.json"
step scene 60 "${tidem[@]}" scene fluidized_tube --arch "$arch" --t-end 0.1 --no-render --quiet --out "$runs/scene"
step scene_cpu 70 env TI_CPU_MAX_NUM_THREADS="$cores" "${tidem[@]}" scene fluidized_tube --t-end 0.1 --no-render \
    --quiet --out "$runs/scene_cpu"
for run in scene scene_cpu; do
    [ -f "$runs/$run/run.json" ] && cp "$runs/$run/run.json" "$out/$run.run.json"
done
exit 0
