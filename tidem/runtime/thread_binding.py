"""Binding Taichi's CPU worker threads to cores, one worker per core, as MPI launchers bind ranks.

Taichi's CPU back end runs each parallel loop on a pool of `cpu_max_num_threads` workers that
sleep between loops; the host thread wakes them for every loop (two or three times a step).
Left to the operating system, the workers of some processes ran much of the time at the speed of
one (on this project's 2-core machine, peer bed 10k: the median own pass of the contact forces of
a process 0.94-0.99 ms in some processes, 0.42-0.44 ms in others; one thread: 1.0 ms), most likely
two workers queued on one core, a woken thread being placed near the thread that woke it. Bound
one to each core, they ran at 1.27-1.41e7 particle-steps/s against 0.90-1.16e7 unbound
(`tidem bench --sizes 10000 --precision float64` with `TIDEM_BIND=none` against the default, five
alternating rounds, 2026-11-25).

`bind_workers` finds the pool's workers as the threads that `ti.init` started and that run a
parallel test loop, and binds the k-th to the k-th of the process's allowed CPUs (one logical CPU
per physical core before any second one). `TIDEM_BIND` chooses when:
- `auto` (the default): when there are as many workers as allowed CPUs (tidem's default thread
  count, or `taskset` and the thread count agreeing), so that runs that share a machine, each on
  a few threads, are not all bound to its first cores;
- `cores`: always, while there are at least as many CPUs as workers (a benchmark on a few
  cores of a larger machine, as `mpirun` binds its ranks);
- `none`: never.
It binds nothing, silently, where it cannot tell the workers apart (never a failure: at worst
the run is as fast as without).
"""

from __future__ import annotations

import os
from pathlib import Path

BIND_MODES = ("auto", "cores", "none")


def bind_mode() -> str:
    """`TIDEM_BIND`: auto (the default), cores or none (module docstring)."""
    mode = os.environ.get("TIDEM_BIND", "auto").strip().lower() or "auto"
    if mode not in BIND_MODES:
        raise ValueError(f"TIDEM_BIND={mode!r}: use one of {', '.join(BIND_MODES)}")
    return mode


def process_threads() -> set[int]:
    """Thread ids of this process (Linux; empty elsewhere)."""
    try:
        return {int(t) for t in os.listdir("/proc/self/task")}
    except OSError:
        return set()


def run_time_ns(tid: int) -> int:
    """CPU time a thread has run [ns] (0 once it is gone)."""
    try:
        return int(Path(f"/proc/self/task/{tid}/schedstat").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 0


def one_cpu_per_core(cpus: list[int], sysfs: Path = Path("/sys/devices/system/cpu")) -> list[int]:
    """The CPUs in order, the first logical CPU of each physical core before any second one
    (`sysfs`: where the kernel describes each CPU's topology)."""
    first, rest, seen = [], [], set()
    for cpu in cpus:
        try:
            top = sysfs / f"cpu{cpu}" / "topology"
            core = (top / "physical_package_id").read_text().strip(), (top / "core_id").read_text().strip()
        except OSError:
            core = ("cpu", str(cpu))
        (rest if core in seen else first).append(cpu)
        seen.add(core)
    return first + rest


def bind_workers(threads: int, new_threads: set[int], busy_loop) -> frozenset[int]:
    """Bind the `threads` pool workers among `new_threads` (those `ti.init` started) to distinct
    cores; `busy_loop()` runs a parallel Taichi loop long enough for every worker to take part.
    Returns the workers it bound (none where it bound nothing)."""
    mode = bind_mode()
    if threads < 2 or mode == "none" or not hasattr(os, "sched_setaffinity"):
        return frozenset()
    cpus = one_cpu_per_core(sorted(os.sched_getaffinity(0)))
    if len(cpus) < threads or (mode == "auto" and len(cpus) != threads):
        return frozenset()
    busy_loop()  # compiled by Taichi's compile threads, which must not count as workers
    workers: set[int] = set()
    for _attempt in range(5):  # a worker that woke late may find the loop done: try again
        before = {t: run_time_ns(t) for t in new_threads}
        busy_loop()
        workers |= {t for t in new_threads if run_time_ns(t) > before[t]}
        if len(workers) >= threads:
            break
    if len(workers) != threads:  # not told apart: leave the scheduler to place them
        return frozenset()
    try:
        for cpu, tid in zip(cpus, sorted(workers)):
            os.sched_setaffinity(tid, {cpu})
    except OSError:
        return frozenset()
    return frozenset(workers)
