"""Writers: PNG, GeoTIFF and Cloud-Optimized GeoTIFF files of composed images; GeoJSON of
vector features."""

from .cog import check_cog, local_client, write_cog
from .geojson import write_geojson

__all__ = ["check_cog", "local_client", "write_cog", "write_geojson"]
