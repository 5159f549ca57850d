"""Core: scenes, cameras and their framing, VTK capture into G-buffers, isosurfaces.

Everything above this layer (filters, styles, recipes, faces, apps, cli) works on what it
makes: a :class:`GBuffer` of float32 channels and its :class:`CameraInfo`.
"""

from typing import TYPE_CHECKING

from .._atomic import lazy_exports

#: Public name -> module (relative to this package) that defines it: imported on first
#: use (``_atomic.lazy_exports``), so importing one module of the package does
#: not import them all.
_EXPORTS = {
    "VIEWS": "camera",
    "CameraInfo": "camera",
    "CaptureSession": "capture",
    "capture": "capture",
    "clear_capture_cache": "capture",
    "gbuffer_from_zbuffer": "frame",
    "read_zbuffer": "frame",
    "framed_camera": "framing",
    "named_view_camera": "framing",
    "oblique_camera": "framing",
    "terrain_birdseye_camera": "framing",
    "GBuffer": "gbuffer",
    "check_gbuffer": "gbuffer",
    "isosurface": "isosurface",
}

__all__ = [
    "VIEWS",
    "CameraInfo",
    "CaptureSession",
    "GBuffer",
    "capture",
    "check_gbuffer",
    "clear_capture_cache",
    "framed_camera",
    "gbuffer_from_zbuffer",
    "isosurface",
    "named_view_camera",
    "oblique_camera",
    "read_zbuffer",
    "terrain_birdseye_camera",
]

lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .camera import VIEWS, CameraInfo
    from .capture import CaptureSession, capture, clear_capture_cache
    from .frame import gbuffer_from_zbuffer, read_zbuffer
    from .framing import framed_camera, named_view_camera, oblique_camera, terrain_birdseye_camera
    from .gbuffer import GBuffer, check_gbuffer
    from .isosurface import isosurface
