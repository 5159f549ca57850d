"""An out-of-core topographic map on dask
======================================

An out-of-core topographic map: a DEM mapped chunk by chunk on dask into a Cloud-Optimised
GeoTIFF with a PNG overview, never held whole (the pixels equal the in-memory map's).

The DEM is synthetic (generated chunk by chunk, 30 m cells); pass a GeoTIFF/VRT/.hgt to map
your own, read lazily by windows. ``--dask`` computes on a new 2-worker ``LocalCluster``
instead of this process's threads.

Usage: ``python examples/terrain_out_of_core.py [outdir] [DEM_FILE] [--dask]``
(default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.datasets import synthetic_dem
from sciviz_gbuf.readers import read_dem


def main(outdir: Path, dem_file: str | None = None, cluster: bool = False) -> list[Path]:
    """Write ``big_map.tif`` (COG) and its overview ``big_map.png`` to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    if dem_file is None:
        dem = synthetic_dem((1536, 2048), chunks=512)
    else:
        dem = read_dem(dem_file, chunks=1024)
    rgba = sg.topographic_map(dem)  # lazy: nothing is computed yet
    png = outdir / "big_map.png"
    cog = sg.write_cog(
        rgba,
        outdir / "big_map.tif",
        dem=dem,
        overview_png=png,
        overview_size=1024,
        client="local" if cluster else None,
    )
    return [cog, png]


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--dask"]
    out = Path(args[0]) if args else Path(sys.argv[0]).resolve().with_name("output")
    for path in main(out, args[1] if len(args) > 1 else None, "--dask" in sys.argv):
        print(path)
