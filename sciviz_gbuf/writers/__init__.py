"""Writers: PNG, GeoTIFF and Cloud-Optimized GeoTIFF files of composed images; GeoJSON of
vector features; SVG and PDF line art."""

from .cog import check_cog, local_client, write_cog
from .geojson import write_geojson
from .vector import SvgText, write_pdf, write_strokes, write_svg

__all__ = [
    "SvgText",
    "check_cog",
    "local_client",
    "write_cog",
    "write_geojson",
    "write_pdf",
    "write_strokes",
    "write_svg",
]
