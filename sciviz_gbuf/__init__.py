"""sciviz_gbuf: comprehensible rendering of 3-D shapes with G-buffers for PyVista/VTK.

Capture float32 G-buffers of a PyVista scene once (:func:`capture`), then run any number of
image-space enhancements on them (:mod:`sciviz_gbuf.filters`), following Saito & Takahashi
(SIGGRAPH 1990) and Nienhaus & Döllner (WSCG 2003).
"""

from __future__ import annotations

from .core.camera import CameraInfo
from .core.capture import CaptureSession, capture
from .core.gbuffer import GBuffer
from .errors import InputError, OutputError, RenderError, SciVizGBufError
from .recipes.birdseye import birdseye_map, sumi_e
from .recipes.medical import ct_enhance
from .recipes.surface import surface_analysis
from .recipes.terrain import topographic_map
from .writers.cog import local_client, write_cog

__version__ = "0.1.0"

__all__ = [
    "CameraInfo",
    "CaptureSession",
    "GBuffer",
    "InputError",
    "OutputError",
    "RenderError",
    "SciVizGBufError",
    "__version__",
    "birdseye_map",
    "capture",
    "ct_enhance",
    "local_client",
    "sumi_e",
    "surface_analysis",
    "topographic_map",
    "write_cog",
]

# Register PyVista's ``.gbuf`` dataset accessor and plotter component (also declared as entry
# points, so ``pv.Sphere().gbuf`` works without this import; idempotent).
from . import pyvista_plugin as _pyvista_plugin  # noqa: F401
