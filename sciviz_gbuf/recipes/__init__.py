"""Recipes: the data flow capture -> filters -> compose, packaged for one kind of picture each.

- :mod:`.saito1990`: the panels of Saito & Takahashi's Fig. 3 and Fig. 7 (and the 2003 edge map).
- :mod:`.terrain`: plan-view topographic maps of DEMs (bands, relief, contours; Fig. 11).
- :mod:`.labels`: contour labels of those maps (uphill reading, knocked-out lines, GeoJSON).
- :mod:`.birdseye`: bird's-eye maps and the sumi-e of DEMs (Figs. 12, 13).
- :mod:`.medical`: enhanced CT surfaces (Fig. 14): profiles, shading, contours, colour bands.
- :mod:`.surface`: surface analysis of Bezier patches (Fig. 15): reflection lines, zebra,
  isophotes, curvature maps, contours; :func:`seam_patches` builds the paper's C1 surface.
- :mod:`.contour_figures`: the panels of their Fig. 5 (contour lines), Fig. 6 (curved hatching)
  and Fig. 11 (a plan-view topographic map of the bundled DEM).
- :mod:`.npr`: one NPR picture of any scene by style name (the ``mesh`` command).
- :mod:`.vector`: the same pictures' lines as vector strokes for SVG and PDF.

Shared layers live in the private :mod:`._map` and :mod:`._intervals`. The cameras
(:mod:`sciviz_gbuf.core.framing`) and the illustrations (:mod:`sciviz_gbuf.styles.illustration`)
that used to live here are re-exported under their old names.
"""

from typing import TYPE_CHECKING

from .._atomic import lazy_exports

#: Public name -> module (relative to this package) that defines it: imported on first
#: use (``_atomic.lazy_exports``), so importing one module of the package does
#: not import them all.
_EXPORTS = {
    "framed_camera": "..core.framing",
    "named_view_camera": "..core.framing",
    "oblique_camera": "..core.framing",
    "terrain_birdseye_camera": "..core.framing",
    "STYLES": "..styles.illustration",
    "fig7_edge_map": "..styles.illustration",
    "illustrate": "..styles.illustration",
    "shade_image": "..styles.illustration",
    "signed_to_grey": "..styles.illustration",
    "birdseye_gbuffer": "birdseye",
    "birdseye_layers": "birdseye",
    "birdseye_map": "birdseye",
    "birdseye_panels": "birdseye",
    "sumi_e": "birdseye",
    "CONTOUR_CAPTIONS": "contour_figures",
    "fig5_panels": "contour_figures",
    "fig6_panels": "contour_figures",
    "fig11_panels": "contour_figures",
    "write_panels": "contour_figures",
    "ContourLabel": "labels",
    "contour_labels": "labels",
    "labels_to_geojson": "labels",
    "ct_enhance": "medical",
    "ct_gbuffer": "medical",
    "ct_layers": "medical",
    "ct_panels": "medical",
    "ct_surface": "medical",
    "ct_translucent": "medical",
    "view_camera": "medical",
    "CAPTIONS": "saito1990",
    "fig3_panels": "saito1990",
    "fig7_panels": "saito1990",
    "nut_camera": "saito1990",
    "seam_patches": "surface",
    "surface_analysis": "surface",
    "surface_gbuffer": "surface",
    "surface_layers": "surface",
    "map_grid": "terrain",
    "nice_intervals": "terrain",
    "topographic_map": "terrain",
    "write_topographic_cog": "terrain",
    "write_topographic_png": "terrain",
    "TilePyramid": "tiles",
    "mercator_dem": "tiles",
    "native_zoom": "tiles",
    "tile_bounds": "tiles",
    "write_map_tiles": "tiles",
    "VectorPicture": "vector",
    "drawing_picture": "vector",
    "edge_picture": "vector",
    "surface_picture": "vector",
    "technical_drawing": "vector",
    "technical_drawing_image": "vector",
    "topographic_picture": "vector",
    "write_vector": "vector",
}

__all__ = [
    "CAPTIONS",
    "CONTOUR_CAPTIONS",
    "STYLES",
    "ContourLabel",
    "TilePyramid",
    "VectorPicture",
    "birdseye_gbuffer",
    "birdseye_layers",
    "birdseye_map",
    "birdseye_panels",
    "contour_labels",
    "ct_enhance",
    "ct_gbuffer",
    "ct_layers",
    "ct_panels",
    "ct_surface",
    "ct_translucent",
    "drawing_picture",
    "edge_picture",
    "fig3_panels",
    "fig5_panels",
    "fig6_panels",
    "fig7_edge_map",
    "fig7_panels",
    "fig11_panels",
    "framed_camera",
    "illustrate",
    "labels_to_geojson",
    "map_grid",
    "mercator_dem",
    "named_view_camera",
    "native_zoom",
    "nice_intervals",
    "nut_camera",
    "oblique_camera",
    "seam_patches",
    "shade_image",
    "signed_to_grey",
    "sumi_e",
    "surface_analysis",
    "surface_gbuffer",
    "surface_layers",
    "surface_picture",
    "technical_drawing",
    "technical_drawing_image",
    "terrain_birdseye_camera",
    "tile_bounds",
    "topographic_map",
    "topographic_picture",
    "view_camera",
    "write_map_tiles",
    "write_panels",
    "write_topographic_cog",
    "write_topographic_png",
    "write_vector",
]

# the recipe modules themselves, so ``sg.recipes.medical.ct_gbuffer`` works in a fresh interpreter
_SUBMODULES = (
    "birdseye",
    "contour_figures",
    "furniture",
    "labels",
    "layout",
    "map_options",
    "medical",
    "npr",
    "saito1990",
    "surface",
    "terrain",
    "terrain_chunked",
    "tiles",
    "vector",
)

lazy_exports(__name__, _EXPORTS, _SUBMODULES)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from ..core.framing import (
        framed_camera,
        named_view_camera,
        oblique_camera,
        terrain_birdseye_camera,
    )
    from ..styles.illustration import STYLES, fig7_edge_map, illustrate, shade_image, signed_to_grey
    from .birdseye import birdseye_gbuffer, birdseye_layers, birdseye_map, birdseye_panels, sumi_e
    from .contour_figures import (
        CONTOUR_CAPTIONS,
        fig5_panels,
        fig6_panels,
        fig11_panels,
        write_panels,
    )
    from .labels import ContourLabel, contour_labels, labels_to_geojson
    from .medical import (
        ct_enhance,
        ct_gbuffer,
        ct_layers,
        ct_panels,
        ct_surface,
        ct_translucent,
        view_camera,
    )
    from .saito1990 import CAPTIONS, fig3_panels, fig7_panels, nut_camera
    from .surface import seam_patches, surface_analysis, surface_gbuffer, surface_layers
    from .terrain import (
        map_grid,
        nice_intervals,
        topographic_map,
        write_topographic_cog,
        write_topographic_png,
    )
    from .tiles import TilePyramid, mercator_dem, native_zoom, tile_bounds, write_map_tiles
    from .vector import (
        VectorPicture,
        drawing_picture,
        edge_picture,
        surface_picture,
        technical_drawing,
        technical_drawing_image,
        topographic_picture,
        write_vector,
    )
