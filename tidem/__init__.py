"""tidem: hot granular flows (DEM, heat, gas coupling) in Taichi.

The Python API (`tidem.api`, docs/python_api.md): `tidem.load_scene`, `tidem.run`,
`tidem.read_run`. Layout: packages by subject, in layers; a module imports only from its own
package and from lower layers (tests/test_import_graph.py holds the table):

    0  version, scene/, io/, analytic/, runtime/
    1  walls/       box sides, walls, tubes, triangle meshes
    2  gas/         the gas grid, its fields and kernels' driver, mesh walls in the gas
    3  particles/   placement, pours, storage order, contact parameters; heat/  heat and reactions
    4  results/     observables and measurements of a run
    5  sim/         Model, State, Solver; render/  frames, movies, plots, the live view
    6  runner/      launch, run loop, output, checkpoints
    7  studies/     tradeoff, sweep, bench
    8  api, cli/

The Taichi kernels live in the top-level folder `kernels/`, installed as the subpackage
`tidem.kernels` (pyproject.toml's package-dir), so `tidem.kernels.contact` is the file
`kernels/contact.py`; they import nothing of tidem outside kernels/. docs/architecture.md gives
the data flow, where each scene key and physics model lives and how to add one.
"""

import os as _os

# Quiet Taichi before anything imports it: no network version check, no banner.
_os.environ.setdefault("TI_SKIP_VERSION_CHECK", "ON")
_os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "0")

from tidem.api import (Controls, InputError, OutputLost, RunFailed, RunFolder, RunInterrupted,  # noqa: E402
                       SceneError, load_scene, read_run, run)
from tidem.version import __version__  # noqa: E402

__all__ = ["load_scene", "run", "read_run", "Controls", "RunFolder", "RunFailed", "RunInterrupted", "SceneError", "InputError",
           "OutputLost", "__version__"]
