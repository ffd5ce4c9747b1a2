"""Off-screen OpenGL for VTK: pick the window class explicitly and check that its library
exists, because VTK segfaults (instead of raising) when no GL library can be loaded."""

from __future__ import annotations

import ctypes.util
import os


class RenderUnavailable(RuntimeError):
    """No off-screen OpenGL library on this machine."""


_CHOICES = (
    ("OSMesa", "vtkOSOpenGLRenderWindow", "libosmesa6"),
    ("EGL", "vtkEGLRenderWindow", "libegl1 libgl1-mesa-dri"),
)


def prepare_offscreen() -> str:
    """Set VTK_DEFAULT_OPENGL_WINDOW to an available off-screen window; returns its name."""
    chosen = os.environ.get("VTK_DEFAULT_OPENGL_WINDOW")
    for lib, window, _pkg in _CHOICES:
        if chosen in (None, window) and ctypes.util.find_library(lib):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = window
            os.environ.setdefault("LP_NUM_THREADS", "1")  # llvmpipe: leave the cores to the simulation
            os.environ.setdefault("MESA_SHADER_CACHE_DIR", os.path.expanduser("~/.cache/mesa_shader_cache"))
            return window
    raise RenderUnavailable(
        "no off-screen OpenGL library found (VTK would crash without one); install OSMesa, e.g. "
        "'apt-get install -y --no-install-recommends libosmesa6', or run with --no-render")
