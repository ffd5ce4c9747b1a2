#!/bin/bash
# Mesh walls on a GPU, in one command on a machine with an NVIDIA GPU and
# tidem importable (installed, or this tree on PYTHONPATH with tidem/kernels and tidem/scenes linked):
#   bash benchmarks/gpu_mesh_check.sh OUT
# Runs each scene with meshes for a short stretch of bed time on CUDA and then on every CPU core of
# that machine (`--no-render`), and writes OUT/gpu_mesh_check.txt: per scene and device the rate and
# the observables side by side (the GPU's atomic sums are not bit-reproducible, so the two drift apart
# over a flowing bed; over these short stretches they should agree to a few per cent):
#   rotary_kiln        turning drum with lifters, heated mesh (mesh springs, rolling, mesh heat)
#   hopper_discharge   bin of mesh walls emptying through a slot (outlet sink, discharge count)
#   moving_bed_hopper  tubes over a wedge-hopper mesh, hysteretic contacts, heat
#   wedge_spout        meshes in the gas: the cut gas grid, sealed cells, spout through a slot
# Each run has 150 s (a first compile of moving_bed_hopper's kernels takes about 70 s on 2 CPU cores);
# about 4 minutes in all on 2 CPU cores with ARCH=cpu (2026-11-29), unmeasured on a GPU.
# ARCH=cpu tries the script without a GPU (both columns then run on the CPU).
set -u
out=${1:?usage: gpu_mesh_check.sh OUT}
arch=${ARCH:-cuda}
runs=${TMPDIR:-/tmp}/gpu_mesh_runs
here=$(dirname "$0")
mkdir -p "$out" "$runs"
log=$out/gpu_mesh_check.log
tidem=(python3 -P -m tidem)
cores=$(nproc)
source "$here/step.sh"
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>&1 | tee -a "$log"
while read -r scene t_end; do
    name=$(basename "$scene" .toml)
    step "${name}_gpu" 150 "${tidem[@]}" scene "$scene" --arch "$arch" --t-end "$t_end" --no-render --quiet \
        --out "$runs/${name}_gpu"
    step "${name}_cpu" 150 env TI_CPU_MAX_NUM_THREADS="$cores" "${tidem[@]}" scene "$scene" --t-end "$t_end" \
        --no-render --quiet --out "$runs/${name}_cpu"
done <<SCENES
rotary_kiln 0.3
hopper_discharge 0.1
moving_bed_hopper 0.02
$here/mesh_scenes/wedge_spout.toml 0.1
SCENES
python3 "$here/gpu_mesh_summary.py" "$runs" | tee "$out/gpu_mesh_check.txt"
exit 0
