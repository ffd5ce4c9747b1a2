"""Taichi start-up: quiet, cached, and initialised once per process.

`ensure_taichi` is the only place that calls `ti.init`. It skips Taichi's network version
check, drops the banner, keeps the offline kernel cache on, and re-initialises only when a
different architecture or precision is asked for (a test session shares one init).
"""

from __future__ import annotations

import contextlib
import io
import os
import sys

import taichi as ti

_current: tuple[str, str, int] | None = None
_auto: dict[tuple[str, int], str] = {}  # what 'auto' started, by (precision, threads)


class BackendUnavailable(RuntimeError):
    """The requested Taichi backend cannot start on this machine."""


def _arch_for(name: str):
    return {"cpu": ti.cpu, "cuda": ti.cuda, "vulkan": ti.vulkan}[name]


def ensure_taichi(arch: str = "cpu", precision: str = "float64", threads: int | None = None) -> str:
    """Initialise Taichi for `arch` ('cpu', 'cuda', 'vulkan' or 'auto') and `precision`.

    Returns the architecture actually started. 'auto' tries CUDA, then Vulkan, and otherwise
    falls back to the CPU, saying so on stderr (Taichi's own `ti.gpu` probe is not used: it
    crashes the process on a machine without a GPU or display).
    """
    global _current
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
    fp = ti.f64 if precision == "float64" else ti.f32
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        ti.init(
            arch=_arch_for(arch),
            default_fp=fp,
            default_ip=ti.i32,
            cpu_max_num_threads=threads,
            offline_cache=True,
            log_level=ti.ERROR,
        )
    started = _started_arch()
    if started != arch:
        ti.reset()
        _current = None
        raise BackendUnavailable(f"Taichi could not start the '{arch}' backend here (got '{started}')")
    _current = key
    return started


def _started_arch() -> str:
    name = str(ti.lang.impl.current_cfg().arch).split(".")[-1]
    return {"x64": "cpu", "arm64": "cpu"}.get(name, name)
