"""Particles above the gas grid's open top (`tidem.runner.output.Output.above_top_note`): a bed that expands or
splashes out of the domain is named in run.json and by the CLI, a closed top never is."""

import pytest

from tests.conftest import make_scene
from tidem.runner.loop import run
from tidem.scene.load import validate
from tidem.sim.model import build_model

GRAINS = [[0.005, 0.005, 0.0185], [0.015, 0.005, 0.0185], [0.01, 0.015, 0.005]]


def thrown(walls):
    """Three grains in still air, two of them 1.5 mm under the top thrown up at 1 m/s: they pass the top
    z = 0.02 m after 1.2 ms and fall back (g) within 0.2 s; the third lies on the floor."""
    return make_scene(
        domain={"min": [0, 0, 0], "max": [0.02, 0.02, 0.02], "periodic": ["x", "y"], "walls": walls,
                "gravity": [0, 0, -9.81]},
        particles=[{"name": "p", "material": "steel", "diameter": {"value": 0.001}, "positions": GRAINS,
                    "velocities": [[0, 0, 1.0], [0, 0, 1.0], [0, 0, 0]]}],
        gas={"density": 1.2, "viscosity": 1.8e-5, "cell_size": 0.004},
        numerics={"t_end": 0.004},
        output={"interval": 0.001},
    )


@pytest.mark.parametrize("walls, above", [("auto", True), (["z-", "z+"], False)])
def test_particles_above_the_open_top_are_named(tmp_path, walls, above):
    result = run(build_model(validate(thrown(walls))), tmp_path, progress=False)
    assert result.status == "finished"
    note = result.summary.get("above_open_top")
    if not above:
        assert note is None
        return
    # snapshots at 0, 1, 2, 3, 4 ms: the thrown pair lies above z = 0.02 m from 1.2 ms on (z = 0.0185 + t - g t^2 / 2)
    assert (note["snapshots"], note["most"]) == (3, 2)
    assert note["first_s"] == pytest.approx(0.002, abs=1e-4)
    assert "raise domain.max[2]" in note["note"] and "67 %" in note["note"]
