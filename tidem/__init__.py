"""tidem: hot granular flows (DEM, heat, gas coupling) in Taichi.

The Python API (`tidem.api`, docs/python_api.md): `tidem.load_scene`, `tidem.run`,
`tidem.read_run`. Layout: this folder holds the set-up and run side (scene -> Model -> State ->
Solver -> run loop -> outputs -> renderer); the Taichi kernels live in the top-level folder
`kernels/`, installed as the subpackage `tidem.kernels` (pyproject.toml's package-dir), so
`tidem.kernels.contact` is the file `kernels/contact.py`. docs/architecture.md gives the data
flow, where each physics model lives and how to add one.
"""

import os as _os

# Quiet Taichi before anything imports it: no network version check, no banner.
_os.environ.setdefault("TI_SKIP_VERSION_CHECK", "ON")
_os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "0")

from tidem.api import (InputError, OutputLost, RunFailed, RunFolder, RunInterrupted, SceneError,  # noqa: E402
                       load_scene, read_run, run)
from tidem.version import __version__  # noqa: E402

__all__ = ["load_scene", "run", "read_run", "RunFolder", "RunFailed", "RunInterrupted", "SceneError", "InputError",
           "OutputLost", "__version__"]
