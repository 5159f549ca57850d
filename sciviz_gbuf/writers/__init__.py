"""Writers: PNG, GeoTIFF and Cloud-Optimized GeoTIFF files of composed images; GeoJSON of
vector features; SVG and PDF line art; web-map tiles and their viewer."""

from .cog import check_cog, local_client, write_cog
from .geojson import write_geojson
from .tiles import encode_tile, write_tile_viewer, write_tilejson
from .vector import SvgText, write_pdf, write_strokes, write_svg

__all__ = [
    "SvgText",
    "check_cog",
    "encode_tile",
    "local_client",
    "write_cog",
    "write_geojson",
    "write_pdf",
    "write_strokes",
    "write_svg",
    "write_tile_viewer",
    "write_tilejson",
]
