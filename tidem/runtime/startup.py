"""Taichi start-up: quiet, cached, and initialised once per process.

`ensure_taichi` is the only place that calls `ti.init`. It skips Taichi's network version
check, drops the banner, keeps the offline kernel cache on, installs the lighter kernel frontend
(`taichi_frontend`), and re-initialises only when a different architecture or precision is asked
for (a test session shares one init).

Compile time against run speed: Taichi's IR optimization ("advanced optimization") triples
the time to compile a kernel and makes few kernels faster. `TIDEM_COMPILE` chooses:
`auto` (the default) compiles the kernels that run every step on every particle (forces,
integration, the neighbour build; `hot`) with it and every other kernel without it; `full`
optimizes every kernel; `fast` none (the test suite, which compiles many small scenes once
each). Measured on 2 cores: the fluidized-bed scene's cold kernel build 49 s with `full`, 17 s
with `auto`, 14 s with `fast`, and no measurable difference in its steps/s; the peer
benchmark bed's force kernel 10 % slower without it.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import time

import taichi as ti

from tidem.runtime import taichi_frontend
from tidem.runtime.thread_binding import bind_mode, bind_workers, process_threads

_current: tuple[str, str, int] | None = None
bound_workers: frozenset[int] = frozenset()  # the CPU workers the last start bound to cores
COMPILE_MODES = ("auto", "full", "fast")
_auto: dict[tuple[str, int], str] = {}  # what 'auto' started, by (precision, threads)
_fresh_size: tuple[int, int] | None = None  # _program_size() just after the last start


class BackendUnavailable(RuntimeError):
    """The requested Taichi backend cannot start on this machine."""


def compile_mode() -> str:
    """`TIDEM_COMPILE` (auto, full or fast; see the module docstring)."""
    mode = os.environ.get("TIDEM_COMPILE", "auto").strip().lower() or "auto"
    if mode not in COMPILE_MODES:
        raise ValueError(f"TIDEM_COMPILE={mode!r}: use one of {', '.join(COMPILE_MODES)}")
    return mode


def hot(kernel):
    """Mark a kernel that runs every step over every particle: with TIDEM_COMPILE=auto its first
    call, which compiles it, runs with Taichi's IR optimization on (off for every other kernel)."""
    if compile_mode() != "auto":
        return kernel
    compiled = False

    def call(*args):
        nonlocal compiled
        if compiled:
            return kernel(*args)
        cfg = ti.lang.impl.current_cfg()
        cfg.advanced_optimization = True
        try:
            return kernel(*args)
        finally:
            cfg.advanced_optimization = False
            compiled = True

    call.__doc__ = kernel.__doc__
    return call


def restart(arch: str = "cpu", precision: str = "float64", threads: int | None = None) -> str:
    """Start Taichi afresh: every field and compiled kernel of the program before goes (its newly
    compiled kernels to the offline cache), then `ensure_taichi(arch, precision, threads)`. A program
    as its start left it, on that architecture and precision, is kept.

    A kernel's cache key holds the ids of the fields it touches, and ids count up over a program's
    life: the same scene built again later in one program compiles again. Built first after a
    start, a scene has the keys it has when built first in any other process, and finds its
    kernels in the cache (the test suite starts each test so)."""
    global _current
    if _current is not None and not (_current[:2] == (arch, precision) and _program_size() == _fresh_size):
        ti.reset()
        _current = None
    return ensure_taichi(arch, precision, threads)


def running_arch() -> str | None:
    """The backend Taichi runs on ('cpu', 'cuda', 'vulkan'), None before `ensure_taichi` started it."""
    return None if _current is None else _current[0]


def _program_size() -> tuple[int, int]:
    """The program's field trees and compiled kernels: what a start leaves, and what use adds."""
    runtime = ti.lang.impl.get_runtime()
    return runtime.prog.get_snode_tree_size(), runtime.get_num_compiled_functions()


def _arch_for(name: str):
    return {"cpu": ti.cpu, "cuda": ti.cuda, "vulkan": ti.vulkan}[name]


def ensure_taichi(arch: str = "cpu", precision: str = "float64", threads: int | None = None) -> str:
    """Initialise Taichi for `arch` ('cpu', 'cuda', 'vulkan' or 'auto') and `precision`.

    Returns the architecture actually started. 'auto' tries CUDA, then Vulkan, and otherwise
    falls back to the CPU, saying so on stderr (Taichi's own `ti.gpu` probe is not used: it
    crashes the process on a machine without a GPU or display).
    """
    global _current, bound_workers, _fresh_size
    mode = compile_mode()
    bind_mode()  # TIDEM_BIND, checked before Taichi starts
    threads = threads or int(os.environ.get("TI_CPU_MAX_NUM_THREADS", os.cpu_count() or 1))
    if arch == "auto" and (precision, threads) in _auto:
        return ensure_taichi(_auto[precision, threads], precision, threads)
    if arch == "auto":
        for candidate in ("cuda", "vulkan"):
            try:
                _auto[precision, threads] = ensure_taichi(candidate, precision, threads)
                return candidate
            except BackendUnavailable:
                pass
        started = _auto[precision, threads] = ensure_taichi("cpu", precision, threads)
        print("tidem: no GPU found, running on the CPU", file=sys.stderr)
        return started
    key = (arch, precision, threads)
    if _current == key:
        return arch
    if _current is not None:
        ti.reset()
    taichi_frontend.install()
    fp = ti.f32 if precision == "float32" else ti.f64  # 'mixed' stores only the contact history in float32
    existing = process_threads()
    buf = io.StringIO()
    # Taichi reads TI_CPU_MAX_NUM_THREADS itself, and warns on its C++ log (past the redirect) when an
    # argument overrides it: pass the argument only where it differs
    same = os.environ.get("TI_CPU_MAX_NUM_THREADS", "").strip() == str(threads)
    thread_arg = {} if same else {"cpu_max_num_threads": threads}
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        ti.init(
            arch=_arch_for(arch),
            default_fp=fp,
            default_ip=ti.i32,
            offline_cache=True,
            log_level=ti.ERROR,
            **thread_arg,
        )
    started = _started_arch()
    clear_stale_cache_lock(ti.lang.impl.current_cfg().offline_cache_file_path)
    ti.lang.impl.current_cfg().advanced_optimization = mode == "full"
    if started != arch:
        ti.reset()
        _current = None
        raise BackendUnavailable(f"Taichi could not start the '{arch}' backend here (got '{started}')")
    _current = key
    bound_workers = frozenset()
    if started == "cpu":
        bound_workers = bind_workers(threads, process_threads() - existing, _busy_loop)
    _fresh_size = _program_size()
    return started


STALE_LOCK_S = 600.0  # a live process holds Taichi's cache lock for a cache read or write (seconds at most)


def clear_stale_cache_lock(cache_dir: str, now: float | None = None) -> bool:
    """Remove Taichi's offline-cache lock `ticache.lock` in `cache_dir` when it is older than
    STALE_LOCK_S: a process killed while it held the lock leaves it behind, and from then on every
    process fails to take it ("Lock ... failed") and compiles every kernel anew (17 s instead of
    about 1 s for the bubbling bed's kernels). Says so on stderr; True if one was removed."""
    lock = os.path.join(cache_dir, "ticache.lock")
    try:
        age = (time.time() if now is None else now) - os.path.getmtime(lock)
        if age < STALE_LOCK_S:
            return False
        os.remove(lock)
    except OSError:  # none there, or gone meanwhile, or not ours to remove
        return False
    print(f"tidem: removed a stale Taichi kernel-cache lock ({lock}, {age / 3600:.1f} h old, left by a killed "
          "process); compiled kernels are read from the cache again", file=sys.stderr)
    return True


def _busy_loop() -> None:
    """Some milliseconds of a parallel loop on every CPU worker (`tidem.runtime.thread_binding`)."""
    from tidem.kernels.busy import busy_loop

    busy_loop(1 << 16)


def _started_arch() -> str:
    name = str(ti.lang.impl.current_cfg().arch).split(".")[-1]
    return {"x64": "cpu", "arm64": "cpu"}.get(name, name)
