"""Fig. 11: a plan-view topographic map
====================================

Saito & Takahashi (1990) Fig. 11: a plan-view topographic map of the Jacksboro fault DEM.

A plan view needs no rendering: the DEM grid is the G-buffer. The bundled DEM (whole metres
on a 74.6 x 92.5 m grid) is lightly smoothed and resampled to square 20 m pixels, north up,
around the place where the fault's straight ridges meet a flat valley and a dissected plateau
(``wz``). Its contours (``cn``): 100 m majors, 2 pixels wide, which never thin out, and 20 m
minors, 1 pixel wide, which fade to white (``c_dense = 0``, Eq. 15) where they come closer
than 4 pixels: on slopes steeper than about 25 % only the majors remain, as in the paper,
where the 5 m contours give way to the 20 m ones. For comparison: the same contours without
thinning, and the majors alone. The relief (``sh``) is the Lambert shade of the grid's
normals with the sun in the north-west (azimuth 315°, altitude 45°); ``mx3`` combines the
contours, the relief and colour bands every 100 m.

The paper's 20 m / 5 m intervals suit a finer map of gentler hills; this terrain's median
slope is 24 %, which would bury 5 m contours at any scale the 75-92 m data supports.

Usage: ``python examples/fig11_topographic_contours.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from sciviz_gbuf.recipes import fig11_panels, write_panels

SIZE = 512


def main(outdir: Path) -> list[Path]:
    """Write one PNG per Fig. 11 panel and a montage into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    panels = fig11_panels(
        SIZE, pixel_size=20.0, interval=20.0, major_interval=100.0, dense_spacing=4.0
    )
    return write_panels(outdir, "fig11", panels, columns=4)


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
