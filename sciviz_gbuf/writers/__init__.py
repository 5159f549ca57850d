"""Writers: PNG, GeoTIFF and Cloud-Optimized GeoTIFF files of composed images; GeoJSON of
vector features; SVG and PDF line art; web-map tiles, their viewer, PMTiles archives."""

from typing import TYPE_CHECKING

from .._atomic import lazy_exports

#: Public name -> module (relative to this package) that defines it: imported on first
#: use (``_atomic.lazy_exports``), so importing one module of the package does
#: not import them all.
_EXPORTS = {
    "check_cog": "cog",
    "local_client": "cog",
    "write_cog": "cog",
    "write_geojson": "geojson",
    "pmtiles_tile_id": "pmtiles",
    "write_pmtiles": "pmtiles",
    "encode_tile": "tiles",
    "write_tile_viewer": "tiles",
    "write_tilejson": "tiles",
    "SvgText": "vector",
    "write_pdf": "vector",
    "write_strokes": "vector",
    "write_svg": "vector",
}

__all__ = [
    "SvgText",
    "check_cog",
    "encode_tile",
    "local_client",
    "pmtiles_tile_id",
    "write_cog",
    "write_geojson",
    "write_pdf",
    "write_pmtiles",
    "write_strokes",
    "write_svg",
    "write_tile_viewer",
    "write_tilejson",
]

lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .cog import check_cog, local_client, write_cog
    from .geojson import write_geojson
    from .pmtiles import pmtiles_tile_id, write_pmtiles
    from .tiles import encode_tile, write_tile_viewer, write_tilejson
    from .vector import SvgText, write_pdf, write_strokes, write_svg
