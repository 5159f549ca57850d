"""Relief styles: hillshade, VAT, openness, texture shading, local relief
======================================================================

The same map of the bundled Jacksboro fault DEM lit five ways
(``topographic_map(relief=...)``, ``sciviz-gbuf topo --relief ...``): GDAL's hillshade (the
default), RVT's VAT blend (hillshade, slope, positive openness and sky view), positive
openness, Brown's texture shading and the simple local relief model, each over the hillshade
with RVT's blend modes and normalised to 1 on flat ground, so the colour bands keep their
colours where the ground is flat. The panels are drawn without colour bands, so the relief
itself shows; a sixth panel is the VAT style with the bands.

Usage: ``python examples/terrain_relief_styles.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import sciviz_gbuf as sg
from sciviz_gbuf.compose import write_png
from sciviz_gbuf.datasets import load_jacksboro_dem

STYLES = ("hillshade", "vat", "openness", "texture", "local_relief")


def main(outdir: Path) -> list[Path]:
    """Write one sheet of the six panels to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    dem = load_jacksboro_dem()
    panels = [sg.topographic_map(dem, relief=s, bands=False, contours=False) for s in STYLES]
    panels.append(sg.topographic_map(dem, relief="vat"))
    h, w = panels[0].shape[:2]
    sheet = np.full((2 * h + 8, 3 * w + 16, 4), 255, np.uint8)
    for k, img in enumerate(panels):
        r, c = divmod(k, 3)
        sheet[r * (h + 8) : r * (h + 8) + h, c * (w + 8) : c * (w + 8) + w] = img
    path = outdir / "relief_styles.png"
    write_png(path, sheet)
    return [path]


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
