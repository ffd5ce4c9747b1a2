"""Memory and backends: the expected peak that `tidem check` prints is within 20 %
of the peak resident memory measured for two bed sizes, a scene that would not fit is refused
before anything is allocated, with the numbers, and --arch auto falls back to the CPU saying so
in one line."""

import subprocess
import sys

import pytest

from tests.conftest import make_scene
from tidem.scene.errors import SceneError
from tidem.scene.load import load, validate
from tidem.sim import memory
from tidem.sim.model import build_model

PEAK = """
import sys
from tidem.cli.commands import app
from tidem.sim.memory import peak_resident_bytes
try:
    app(sys.argv[1:], standalone_mode=False)
except SystemExit:
    pass
print("PEAK_BYTES", peak_resident_bytes())
"""


def bed_toml(side: int) -> str:
    """A settled-bed box of about side^2 x 11 particles of 1 mm (periodic x and y)."""
    length = side * 0.0011
    return f"""name = "bed{side}"
[domain]
min = [0.0, 0.0, 0.0]
max = [{length}, {length}, 0.03]
periodic = ["x", "y"]
walls = ["z-"]
gravity = [0.0, 0.0, -9.81]
[materials.sand]
density = 2600.0
youngs_modulus = 1e7
restitution = 0.5
friction = 0.5
[[particles]]
name = "bed"
material = "sand"
diameter = {{ distribution = "mono", value = 0.001 }}
region = {{ min = [0.0, 0.0, 0.0], max = [{length}, {length}, 0.0121] }}
[output]
smoke_steps = 10
snapshots = 1
"""


@pytest.mark.parametrize("side", [30, 90])
def test_expected_peak_memory_within_20_percent_of_measured(tmp_path, side):
    scene = tmp_path / f"bed{side}.toml"
    scene.write_text(bed_toml(side))
    expected = build_model(load(str(scene), [])).peak_memory_bytes()
    done = subprocess.run([sys.executable, "-c", PEAK, "scene", str(scene), "--smoke", "--no-render", "--quiet",
                           "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=600)
    assert "finished" in done.stderr, done.stderr
    measured = int(done.stdout.split("PEAK_BYTES")[1])
    assert expected == pytest.approx(measured, rel=0.2)


def test_a_scene_that_would_not_fit_is_refused_with_the_numbers(monkeypatch):
    monkeypatch.setattr(memory, "available_memory_bytes", lambda: 100 * 2**20)
    with pytest.raises(SceneError) as err:
        build_model(validate(make_scene()))
    msg = str(err.value)
    assert "100 MiB available" in msg and "needs about 172 MiB" in msg and "runtime" in msg


def test_arch_auto_without_a_gpu_falls_back_to_the_cpu_saying_so():
    done = subprocess.run([sys.executable, "-c", "from tidem.runtime.startup import ensure_taichi; print(ensure_taichi('auto'))"],
                          capture_output=True, text=True, timeout=300)
    started = done.stdout.split()[-1]
    if started != "cpu":
        pytest.skip(f"this machine has a GPU ({started})")
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert lines == ["tidem: no GPU found, running on the CPU"]
