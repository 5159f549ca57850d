"""The one registry of image filters: name -> :class:`Filter` (the function, what it takes,
its default input), from which the VTK algorithms of :mod:`sciviz_gbuf.vtk_algorithms` are
generated (one ``vtkGBuffer<Name>`` class per entry).

Adding a filter is one module (the function, with its ``_*_kernels.py`` if it has numba code)
plus one line here. Filters that do not map one image to one image (two inputs, vectors) are
not listed: :func:`~sciviz_gbuf.filters.enhance`,
:func:`~sciviz_gbuf.filters.suppress_zeroth_order`, :func:`~sciviz_gbuf.filters.composite_map`,
:func:`~sciviz_gbuf.filters.contour_polylines`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .bands import color_bands
from .contours import contour_lines, hatching
from .edges import crease_edges, edge_map, id_edges, internal_edges, profile_edges
from .hillshade import hillshade
from .operators import (
    c1_discontinuity,
    diagonal_depth_discontinuity,
    diagonal_normal_discontinuity,
    normalize_gradient,
    second_order,
    sobel_gradient,
)
from .reflection import isophotes, reflection_angle, reflection_lines
from .relief import local_relief, texture_shade
from .shading import lambert
from .terrain_light import cast_shadows, openness, sky_view

__all__ = ["FILTERS", "TAKES", "Filter"]

#: What a filter takes: one image array (``func(image, *, mask=None, **params)``) or a whole
#: G-buffer (``func(gb, **params)``, result at the output size).
TAKES = ("array", "gbuffer")


@dataclass(frozen=True)
class Filter:
    """One image filter.

    Attributes
    ----------
    func : callable
        The filter; its name is the registry key and the VTK result array's name.
    takes : str
        One of :data:`TAKES`.
    default_input : str or None
        Array filters: the G-buffer channel read by default (None: the active scalars).
    components : int
        Array filters: components of the input image (3 for normals).
    needs_levels : bool
        ``interval=`` or ``levels=`` must be given (a dry run uses ``interval=1``).
    """

    func: Callable[..., np.ndarray]
    takes: str
    default_input: str | None = None
    components: int = 1
    needs_levels: bool = False

    @property
    def name(self) -> str:
        return self.func.__name__


def _entries(*filters: Filter) -> dict[str, Filter]:
    return {f.name: f for f in filters}


#: name -> :class:`Filter`.
FILTERS: dict[str, Filter] = _entries(
    # 1990 / 2003 operators on depth-like images
    Filter(sobel_gradient, "array", "sz"),
    Filter(second_order, "array", "sz"),
    Filter(c1_discontinuity, "array", "sz"),
    Filter(diagonal_depth_discontinuity, "array", "sz"),
    Filter(diagonal_normal_discontinuity, "array", "normal", components=3),
    Filter(normalize_gradient, "array"),
    # lines and shades of any scalar image
    Filter(contour_lines, "array", "depth", needs_levels=True),
    Filter(hatching, "array", "depth"),
    Filter(lambert, "array", "normal", components=3),
    # terrain
    Filter(hillshade, "array"),
    Filter(color_bands, "array", needs_levels=True),
    Filter(sky_view, "array"),
    Filter(openness, "array"),
    Filter(texture_shade, "array"),
    Filter(local_relief, "array"),
    Filter(cast_shadows, "array"),
    # edges and surface analysis of a whole G-buffer
    Filter(profile_edges, "gbuffer"),
    Filter(internal_edges, "gbuffer"),
    Filter(crease_edges, "gbuffer"),
    Filter(id_edges, "gbuffer"),
    Filter(edge_map, "gbuffer"),
    Filter(reflection_lines, "gbuffer"),
    Filter(reflection_angle, "gbuffer"),
    Filter(isophotes, "gbuffer"),
)
