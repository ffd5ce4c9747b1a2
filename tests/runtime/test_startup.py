"""The compile policy of `tidem.runtime.startup`: TIDEM_COMPILE and the `hot` kernels; TIDEM_BIND's check."""

import pytest
import taichi as ti
from typer.testing import CliRunner

from tidem.cli.commands import app
from tidem.runtime.startup import hot


def test_hot_kernel_compiles_with_ir_optimization_and_the_rest_without(monkeypatch):
    monkeypatch.setenv("TIDEM_COMPILE", "auto")
    cfg = ti.lang.impl.current_cfg()
    monkeypatch.setattr(cfg, "advanced_optimization", False)
    seen = []
    kernel = hot(lambda n: seen.append(ti.lang.impl.current_cfg().advanced_optimization))
    kernel(1)
    kernel(2)
    assert seen == [True, False]  # only the first call compiles
    assert cfg.advanced_optimization is False


def test_hot_is_a_no_op_in_fast_mode(monkeypatch):
    monkeypatch.setenv("TIDEM_COMPILE", "fast")
    def plain(n):
        return n
    assert hot(plain) is plain


@pytest.mark.parametrize("variable, value, choices", [("TIDEM_COMPILE", "fastest", "auto, full, fast"),
                                                     ("TIDEM_BIND", "sockets", "auto, cores, none")])
def test_unknown_runtime_mode_is_a_clear_error(monkeypatch, variable, value, choices):
    monkeypatch.setenv(variable, value)
    result = CliRunner().invoke(app, ["scene", "sphere_impact", "--smoke", "--no-render", "--quiet"])
    assert result.exit_code == 2
    assert f"{variable}='{value}': use one of {choices}" in result.output
    assert "Traceback" not in result.output


def test_a_stale_kernel_cache_lock_is_removed_and_a_fresh_one_kept(tmp_path, capsys):
    """Taichi's cache lock left by a killed process (older than STALE_LOCK_S) goes, with one line
    on stderr; a lock another process may hold now stays; no lock, nothing happens."""
    import os
    import time

    from tidem.runtime.startup import STALE_LOCK_S, clear_stale_cache_lock

    lock = tmp_path / "ticache.lock"
    assert not clear_stale_cache_lock(str(tmp_path))
    lock.touch()
    assert not clear_stale_cache_lock(str(tmp_path)) and lock.exists()
    old = time.time() - 2 * STALE_LOCK_S
    os.utime(lock, (old, old))
    assert clear_stale_cache_lock(str(tmp_path)) and not lock.exists()
    assert "stale Taichi kernel-cache lock" in capsys.readouterr().err


def test_a_scene_built_again_after_a_restart_takes_its_kernels_from_the_cache(tmp_path, monkeypatch):
    """Taichi's cache keys hold the ids of the fields a kernel touches: the same scene built a second time
    in one program compiles every kernel again (new files in the cache), while built first after a
    `restart` it finds all of them there (no new file)."""
    from tests.conftest import make_scene
    from tidem.runtime.startup import restart
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    import taichi as ti

    monkeypatch.setenv("TI_OFFLINE_CACHE_FILE_PATH", str(tmp_path))
    ti.field(ti.f64, 1)[0] = 1.0  # a program in use: the next restart starts one on the new cache path
    raw = make_scene(domain={"walls": "auto", "gravity": [0.0, 0.0, -9.81]})

    def build_and_dump(again_in_same_program=False) -> int:
        restart()
        Solver(build_model(validate(raw))).advance(2)
        if again_in_same_program:
            Solver(build_model(validate(raw))).advance(2)
        restart()  # the program's kernels go to the cache
        return len(list(tmp_path.rglob("*.tic")))

    first = build_and_dump()
    assert first > 0
    assert build_and_dump() == first  # the same scene after a restart: every kernel from the cache
    assert build_and_dump(again_in_same_program=True) > first  # twice in one program: compiled anew
    monkeypatch.delenv("TI_OFFLINE_CACHE_FILE_PATH")
    ti.field(ti.f64, 1)[0] = 1.0
    restart()  # back on the suite's cache
