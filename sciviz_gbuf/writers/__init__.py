"""Writers: PNG, GeoTIFF and Cloud-Optimized GeoTIFF files of composed images."""

from .cog import check_cog, local_client, write_cog

__all__ = ["check_cog", "local_client", "write_cog"]
