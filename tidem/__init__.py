"""tidem: hot granular flows (DEM, heat, gas coupling) in Taichi."""

import os as _os

# Quiet Taichi before anything imports it: no network version check, no banner.
_os.environ.setdefault("TI_SKIP_VERSION_CHECK", "ON")
_os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "0")

__version__ = "0.1.0"
