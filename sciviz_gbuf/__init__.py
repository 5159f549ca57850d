"""sciviz_gbuf: comprehensible rendering of 3-D shapes with G-buffers for PyVista/VTK.

Capture float32 G-buffers of a PyVista scene once (:func:`capture`), then run any number of
image-space enhancements on them (:mod:`sciviz_gbuf.filters`), following Saito & Takahashi
(SIGGRAPH 1990) and Nienhaus & Döllner (WSCG 2003).

The names below are imported on first use (PEP 562), so ``import sciviz_gbuf`` (and the
command line's first line of output) does not wait for VTK, PyVista and numba to load.
PyVista finds the ``.gbuf`` accessor and Plotter component through the package's entry
points, without this import.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._atomic import lazy_exports

__version__ = "0.1.0"

#: Public name -> module (relative to this package) that defines it.
_EXPORTS = {
    "CameraInfo": "core.camera",
    "CaptureSession": "core.capture",
    "capture": "core.capture",
    "clear_capture_cache": "core.capture",
    "GBuffer": "core.gbuffer",
    "InputError": "errors",
    "OutputError": "errors",
    "RenderError": "errors",
    "SciVizGBufError": "errors",
    "birdseye_map": "recipes.birdseye",
    "sumi_e": "recipes.birdseye",
    "ct_enhance": "recipes.medical",
    "surface_analysis": "recipes.surface",
    "topographic_map": "recipes.terrain",
    "write_topographic_cog": "recipes.terrain",
    "write_topographic_png": "recipes.terrain",
    "ContourLabel": "recipes.labels",
    "contour_labels": "recipes.labels",
    "labels_to_geojson": "recipes.labels",
    "local_client": "writers.cog",
    "write_cog": "writers.cog",
    "Stroke": "filters.strokes",
    "vectorize": "filters.strokes",
    "edge_strokes": "filters.strokes",
    "write_svg": "writers.vector",
    "write_pdf": "writers.vector",
}
#: Subpackages and modules reachable as attributes (``sg.filters``) without their own import.
_SUBMODULES = (
    "apps", "cli", "compose", "core", "datasets", "errors", "filters", "pyvista_plugin",
    "readers", "recipes", "styles", "vtk_algorithms", "writers",
)  # fmt: skip

__all__ = [
    "CameraInfo",
    "CaptureSession",
    "ContourLabel",
    "GBuffer",
    "InputError",
    "OutputError",
    "RenderError",
    "SciVizGBufError",
    "Stroke",
    "__version__",
    "birdseye_map",
    "capture",
    "clear_capture_cache",
    "contour_labels",
    "ct_enhance",
    "edge_strokes",
    "labels_to_geojson",
    "local_client",
    "sumi_e",
    "surface_analysis",
    "topographic_map",
    "vectorize",
    "write_cog",
    "write_pdf",
    "write_svg",
    "write_topographic_cog",
    "write_topographic_png",
]  # = _EXPORTS and __version__ (tests/test_structure.py checks)


lazy_exports(__name__, _EXPORTS, _SUBMODULES)


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .core.camera import CameraInfo
    from .core.capture import CaptureSession, capture, clear_capture_cache
    from .core.gbuffer import GBuffer
    from .errors import InputError, OutputError, RenderError, SciVizGBufError
    from .filters.strokes import Stroke, edge_strokes, vectorize
    from .recipes.birdseye import birdseye_map, sumi_e
    from .recipes.labels import ContourLabel, contour_labels, labels_to_geojson
    from .recipes.medical import ct_enhance
    from .recipes.surface import surface_analysis
    from .recipes.terrain import topographic_map, write_topographic_cog, write_topographic_png
    from .writers.cog import local_client, write_cog
    from .writers.vector import write_pdf, write_svg
