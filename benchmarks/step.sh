# Sourced by the device scripts (gpu_check.sh, gpu_run_loop.sh): step NAME SECONDS COMMAND... runs the
# command with a time limit (SIGTERM), appends its output to $log, prints its last ${STEP_TAIL:-12}
# lines and returns its exit status; its output is kept in $runs/NAME.log.
step() {
    local name=$1 limit=$2
    shift 2
    local t0=$SECONDS
    echo "== $name: $*" >>"$log"
    timeout "$limit" "$@" >"$runs/$name.log" 2>&1
    local rc=$?
    cat "$runs/$name.log" >>"$log"
    echo "== $name: rc $rc, $((SECONDS - t0)) s" | tee -a "$log"
    tail -n "${STEP_TAIL:-12}" "$runs/$name.log"
    return $rc
}
