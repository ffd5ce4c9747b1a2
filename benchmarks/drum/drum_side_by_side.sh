#!/bin/bash
# The rotating drum, tidem against LIGGGHTS (2 MPI ranks) with the same STL, from the same settled state,
# alternating (this machine drifts between processes). Needs LIGGGHTS (Debian: apt-get install liggghts).
#   benchmarks/drum/drum_side_by_side.sh WORKDIR [ROUNDS=2] [NWARM=2000] [NSTEPS=5000]
# WORKDIR keeps drum.stl and LIGGGHTS' settled state (settled.dump: 50 000 asked, 0.3 s of settling,
# about 11 minutes on 2 cores), so a second call only times. PYTHON: the interpreter with tidem (python).
set -euo pipefail
W=$1; ROUNDS=${2:-2}; NWARM=${3:-2000}; NSTEPS=${4:-5000}
PY=${PYTHON:-python}
HERE=$(cd "$(dirname "$0")" && pwd)
PEERS=$(cd "$HERE/../../../shared/bench/peers" && pwd)
MPI="mpirun --allow-run-as-root --bind-to core -np 2"
mkdir -p "$W"; cd "$W"
[ -f drum.stl ] || python3 "$PEERS/make_drum_stl.py"
if [ ! -f settled.dump ]; then  # drum.lgt up to its settling run, then the state
  sed -n '1,/^run *\${nsettle}/p' "$PEERS/drum.lgt" > settle.lgt
  echo "write_dump all custom settled.dump id type radius x y z vx vy vz" >> settle.lgt
  $MPI liggghts -in settle.lgt -var nfill 50000 -var nsettle 60000 -log log.settle > /dev/null
fi
$PY "$HERE/drum_peer.py" data settled.dump drum.data
cp "$HERE/drum_timed.lgt" .
for r in $(seq "$ROUNDS"); do
  $MPI liggghts -in drum_timed.lgt -var data drum.data -var nwarm "$NWARM" -var nsteps "$NSTEPS" -log "log.timed.$r" > /dev/null
  grep "Loop time" "log.timed.$r" | tail -1 | awk '{printf "LIGGGHTS: %d particles, %d steps in %.2f s = %.3g particle-steps/s, 2 ranks\n", $12, $9, $4, $12 * $9 / $4}'
  grep "Neighbor list builds" "log.timed.$r" | tail -1
  grep -E "^ +$((NWARM + NSTEPS)) " "log.timed.$r" | tail -1 | awk '{print "LIGGGHTS kinetic energy at the end", $3, "J"}'
  $PY "$HERE/drum_peer.py" time settled.dump drum.stl "$NWARM" "$NSTEPS" 2
done
