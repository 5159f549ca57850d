"""A topographic map as PNG and GeoTIFF
====================================

A plan-view topographic map of the bundled Jacksboro DEM, as PNG and georeferenced GeoTIFF.

Colour bands per major interval, a GDAL-compatible relief with cast shadows and a sky-view term,
and major/minor contour lines (automatic intervals: 200 m / 40 m here, majors at least 6 px
apart on the median slope) whose minors thin out on steep slopes (Saito & Takahashi 1990,
Fig. 11 ``mx3``). The GeoTIFF carries the DEM's CRS and geotransform, so GIS software places it.

Usage: ``python examples/terrain_topographic_map.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.compose import montage, write_geotiff, write_png
from sciviz_gbuf.datasets import load_jacksboro_dem


def main(outdir: Path) -> list[Path]:
    """Write the map (PNG + GeoTIFF) and a montage of its variants to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    dem = load_jacksboro_dem()  # 3" WGS84 grid: pixel sizes in metres from the latitude
    full = sg.topographic_map(dem, shadows=True, sky_view=True)  # automatic intervals
    written = [write_png(outdir / "topo_map.png", full)]
    if _has_rasterio():
        written.append(write_geotiff(outdir / "topo_map.tif", full, dem=dem))
    variants = [
        ("bands + relief + contours, shadows, sky view", full),
        ("GDAL-style: bands + relief", sg.topographic_map(dem, contours=False)),
        ("contours only", sg.topographic_map(dem, bands=False, relief=False)),
        ("continuous tints, multidirectional", sg.topographic_map(
            dem, bands="continuous", variant="multidirectional"
        )),
    ]  # fmt: skip
    written.append(write_png(outdir / "topo_montage.png", montage(variants, columns=2)))
    return written


def _has_rasterio() -> bool:
    try:
        import rasterio  # noqa: F401
    except ImportError:
        return False
    return True


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
