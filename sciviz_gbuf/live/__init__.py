"""Live overlays of a PyVista plotter's own frames: the edge map over a subplot, from a CPU
route (an offscreen capture, or the frame's depth read back) or a GPU route (fragment shaders
inside the frame, :mod:`.gpu`), one manager choosing between them (:mod:`.overlay`).

The layer sits below the PyVista plugin (which offers it as ``pl.gbuf.enable_edge_enhancement``)
and above the styles and filters it draws with; the CPU route is the reference the GPU route
is tested against.
"""

from __future__ import annotations

from .contours import AXES, ContourField, LiveContours, contour_options
from .gpu import SOFTWARE_RENDERERS, GpuEdgePass, GpuUnavailable, gl_info, is_hardware
from .overlay import (
    CLIENT_SIDE_WARNING,
    GPU_STYLES,
    LIVE_STYLES,
    SOURCES,
    EdgeParams,
    LiveEdges,
    client_side_views,
    overlay_rgba,
)

__all__ = [
    "AXES",
    "CLIENT_SIDE_WARNING",
    "GPU_STYLES",
    "LIVE_STYLES",
    "SOFTWARE_RENDERERS",
    "SOURCES",
    "ContourField",
    "EdgeParams",
    "GpuEdgePass",
    "GpuUnavailable",
    "LiveContours",
    "LiveEdges",
    "client_side_views",
    "contour_options",
    "gl_info",
    "is_hardware",
    "overlay_rgba",
]
