"""Core: scenes, cameras and their framing, VTK capture into G-buffers, isosurfaces.

Everything above this layer (filters, styles, recipes, faces, apps, cli) works on what it
makes: a :class:`GBuffer` of float32 channels and its :class:`CameraInfo`.
"""

from .camera import VIEWS, CameraInfo
from .capture import CaptureSession, capture
from .frame import gbuffer_from_zbuffer, read_zbuffer
from .framing import framed_camera, named_view_camera, oblique_camera, terrain_birdseye_camera
from .gbuffer import GBuffer, check_gbuffer
from .isosurface import isosurface

__all__ = [
    "VIEWS",
    "CameraInfo",
    "CaptureSession",
    "GBuffer",
    "capture",
    "check_gbuffer",
    "framed_camera",
    "gbuffer_from_zbuffer",
    "isosurface",
    "named_view_camera",
    "oblique_camera",
    "read_zbuffer",
    "terrain_birdseye_camera",
]
