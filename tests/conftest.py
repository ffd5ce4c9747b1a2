"""A fresh Taichi program (CPU, float64) for each test, and scene helpers.

The suite compiles the kernels of many small scenes once each, so it compiles them without
Taichi's IR optimization (`TIDEM_COMPILE=fast`, see `tidem/runtime/startup.py`): a third of the compile
time for the same kernels. README's test command runs two pytest-xdist
workers, because compiling is single-threaded; each worker's kernels run on its share of the cores
(one thread each on 2 cores), not both on all of them. Each test starts on a fresh Taichi program
(`fresh_taichi`), so that the kernels of a scene another test (in either worker) built first come
from Taichi's kernel cache, which is allowed 1 GiB for that.
"""

import copy
import os

import pytest

os.environ.setdefault("TIDEM_COMPILE", "fast")
os.environ.setdefault("TI_ENABLE_PYBUF", "0")  # pytest's captured stdout would make Taichi print after every launch
if os.environ.get("PYTEST_XDIST_WORKER_COUNT"):  # the cores shared among the workers, not each worker on all of them
    workers = int(os.environ["PYTEST_XDIST_WORKER_COUNT"])
    os.environ.setdefault("TI_CPU_MAX_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // workers)))
# the suite's kernels fill more than Taichi's default 100 MB cache, which then drops the least recently used
# quarter at every restart, among them kernels a later test would have found
os.environ.setdefault("TI_OFFLINE_CACHE_MAX_SIZE_OF_FILES", str(1 << 30))

from tidem.runtime.startup import ensure_taichi, restart  # noqa: E402  (after TIDEM_COMPILE is set)

ensure_taichi("cpu", "float64")


@pytest.fixture(autouse=True)
def fresh_taichi():
    """Each test on a fresh Taichi program (CPU, float64): its scenes' kernels then have the cache keys
    they have in any test that builds the same scene first, in either xdist worker, and are compiled
    once per suite, not once per test (`tidem.runtime.startup.restart`)."""
    restart("cpu", "float64")


QUICK = ("tests/test_import_graph.py", "tests/scene/", "tests/io/", "tests/analytic/", "tests/walls/test_mesh_input.py",
         "tests/results/test_hydrodynamics.py", "tests/heat/test_packet_model.py", "tests/heat/test_impact_conduction.py",
         "tests/runtime/test_phases.py", "tests/cli/test_crash.py", "tests/render/test_settings.py",
         "tests/kernels/test_contact.py", "tests/kernels/test_heat.py", "tests/studies/test_seed_groups.py",
         "tests/kernels/test_gas.py::test_packed_bed_pressure_gradient_is_ergun")
"""The edit loop's selection (`pytest -n 2 -m quick`, README): the scene schema and its errors, the
layers, files, closed-form models, mesh files, the contact and heat kernels and a packed bed's gas;
about 1-3 minutes on 2 cores."""


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.nodeid.startswith(QUICK):
            item.add_marker(pytest.mark.quick)


def make_scene(**tables) -> dict:
    """A minimal valid raw scene (one steel material, no gravity, open box) with overrides."""
    raw = {
        "name": "test",
        "domain": {"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1], "walls": "none", "gravity": [0.0, 0.0, 0.0]},
        "materials": {"steel": {"density": 7800.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3,
                                "restitution": 1.0, "friction": 0.0}},
        "particles": [{"name": "p", "material": "steel", "diameter": {"distribution": "mono", "value": 0.01},
                       "positions": [[0.0, 0.0, 0.0]]}],
    }
    for key, value in tables.items():
        if isinstance(value, dict) and isinstance(raw.get(key), dict):
            merged = copy.deepcopy(raw[key])
            merged.update(value)
            raw[key] = merged
        else:
            raw[key] = value
    return raw


@pytest.fixture
def solver_for():
    """Build a Solver from a raw scene dict; released after the test."""
    from tidem.scene.load import validate
    from tidem.sim.model import build_model
    from tidem.sim.solver import Solver

    made = []

    def build(raw, **kw):
        solver = Solver(build_model(validate(raw), **kw))
        made.append(solver)
        return solver

    yield build
    for s in made:
        s.release()
