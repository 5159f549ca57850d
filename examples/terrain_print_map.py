"""A labelled topographic map on an A4 page (PDF and PNG)
=======================================================

The bundled Jacksboro fault DEM as a printed map: colour bands, relief and contour lines
(Saito & Takahashi 1990, Fig. 11) at a round map scale (the smallest 1, 2, 2.5 or 5 times a
power of ten at which the DEM fits the page's frame: 1:200 000 here), with the index contours'
heights written into the lines (reading uphill, the line broken under the number), a
hypsometric legend whose classes are the map's colour bands, a scale bar, a north arrow, a
title, a credit line and the coordinates on the frame. The relief is RVT's VAT blend
(hillshade, slope, openness, sky view). The same page is written as PDF, whose contour lines
and labels are vector lines and text over the raster relief, and as PNG; the command line does
the same with ``sciviz-gbuf topo --page A4 --labels --relief vat --graticule ticks -o map.pdf``.

The labels' positions are also written as GeoJSON points (with their rotation), which a GIS
can draw over the map.

Usage: ``python examples/terrain_print_map.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.datasets import load_jacksboro_dem
from sciviz_gbuf.recipes.layout import page_scale, write_map_page
from sciviz_gbuf.writers import write_geojson

CREDIT = "Heights: USGS 3 arc-second DEM (matplotlib sample data). Map: sciviz-gbuf"


def main(outdir: Path) -> list[Path]:
    """Write the page (PDF, PNG) and the labels (GeoJSON) to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    dem = load_jacksboro_dem()
    page = {"page": "A4", "dpi": 200, "title": "Jacksboro fault, Tennessee", "credit": CREDIT,
            "relief": "vat", "graticule": "ticks"}  # fmt: skip
    written = []
    for name in ("topo_page.pdf", "topo_page.png"):
        write_map_page(outdir / name, dem, **page)
        written.append(outdir / name)
    # the labels of the page's map: its scale and resolution
    n = page_scale(dem, "A4", title=True)
    labels = sg.contour_labels(dem, scale=f"1:{n}", dpi=page["dpi"])
    path = outdir / "topo_labels.geojson"
    write_geojson(path, sg.labels_to_geojson(labels, crs=dem.crs))
    written.append(path)
    return written


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
