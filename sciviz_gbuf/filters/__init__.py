"""Image-space operators on G-buffer channels: pure functions on numpy arrays (and a mask),
returning new float32 arrays; inputs are never modified. Shades are in [0, 1] with 1 = lit;
line images are ink in [0, 1] with 1 = full ink (signed images are documented as such)."""

from typing import TYPE_CHECKING

from .._atomic import lazy_exports

#: Public name -> module (relative to this package) that defines it: imported on first use
#: (``_atomic.lazy_exports``), so a command that needs the hillshade and the contours does
#: not wait for the edge, stroke and texture modules (and scipy's, matplotlib's imports).
_EXPORTS = {
    "BATHYMETRIC": "bands",
    "HYPSOMETRIC": "bands",
    "color_bands": "bands",
    "composite_map": "bands",
    "ContourPolyline": "contour_vectors",
    "contour_polylines": "contour_vectors",
    "polylines_to_geojson": "contour_vectors",
    "band_heights": "contours",
    "contour_line_parameters": "contours",
    "contour_lines": "contours",
    "hatching": "contours",
    "modulated_hatching": "contours",
    "crease_edges": "edges",
    "edge_map": "edges",
    "enhance": "edges",
    "hidden_edges": "edges",
    "id_edges": "edges",
    "internal_edges": "edges",
    "profile_and_crease_edges": "edges",
    "profile_edges": "edges",
    "fill_nodata_ring": "hillshade",
    "hillshade": "hillshade",
    "c1_discontinuity": "operators",
    "diagonal_depth_discontinuity": "operators",
    "diagonal_normal_discontinuity": "operators",
    "normalize_gradient": "operators",
    "second_order": "operators",
    "sobel_gradient": "operators",
    "suppress_zeroth_order": "operators",
    "highlight_lines": "reflection",
    "isophotes": "reflection",
    "reflection_angle": "reflection",
    "reflection_lines": "reflection",
    "local_relief": "relief",
    "texture_shade": "relief",
    "lambert": "shading",
    "Stroke": "strokes",
    "bridge": "strokes",
    "dash_pieces": "strokes",
    "draw_strokes": "strokes",
    "edge_strokes": "strokes",
    "paint_strokes": "strokes",
    "simplify": "strokes",
    "vectorize": "strokes",
    "cast_shadows": "terrain_light",
    "openness": "terrain_light",
    "sky_view": "terrain_light",
}

__all__ = [
    "BATHYMETRIC",
    "HYPSOMETRIC",
    "ContourPolyline",
    "Stroke",
    "band_heights",
    "bridge",
    "c1_discontinuity",
    "cast_shadows",
    "color_bands",
    "composite_map",
    "contour_line_parameters",
    "contour_lines",
    "contour_polylines",
    "crease_edges",
    "dash_pieces",
    "diagonal_depth_discontinuity",
    "diagonal_normal_discontinuity",
    "draw_strokes",
    "edge_map",
    "edge_strokes",
    "enhance",
    "fill_nodata_ring",
    "hatching",
    "hidden_edges",
    "highlight_lines",
    "hillshade",
    "id_edges",
    "internal_edges",
    "isophotes",
    "lambert",
    "local_relief",
    "modulated_hatching",
    "normalize_gradient",
    "openness",
    "paint_strokes",
    "polylines_to_geojson",
    "profile_and_crease_edges",
    "profile_edges",
    "reflection_angle",
    "reflection_lines",
    "second_order",
    "simplify",
    "sky_view",
    "sobel_gradient",
    "suppress_zeroth_order",
    "texture_shade",
    "vectorize",
]

lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .bands import BATHYMETRIC, HYPSOMETRIC, color_bands, composite_map
    from .contour_vectors import ContourPolyline, contour_polylines, polylines_to_geojson
    from .contours import (
        band_heights,
        contour_line_parameters,
        contour_lines,
        hatching,
        modulated_hatching,
    )
    from .edges import (
        crease_edges,
        edge_map,
        enhance,
        hidden_edges,
        id_edges,
        internal_edges,
        profile_and_crease_edges,
        profile_edges,
    )
    from .hillshade import fill_nodata_ring, hillshade
    from .operators import (
        c1_discontinuity,
        diagonal_depth_discontinuity,
        diagonal_normal_discontinuity,
        normalize_gradient,
        second_order,
        sobel_gradient,
        suppress_zeroth_order,
    )
    from .reflection import highlight_lines, isophotes, reflection_angle, reflection_lines
    from .relief import local_relief, texture_shade
    from .shading import lambert
    from .strokes import (
        Stroke,
        bridge,
        dash_pieces,
        draw_strokes,
        edge_strokes,
        paint_strokes,
        simplify,
        vectorize,
    )
    from .terrain_light import cast_shadows, openness, sky_view
