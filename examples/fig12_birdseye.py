"""Figs. 12 and 13: bird's-eye maps and a sumi-e
=============================================

The 1990 Fig. 12 (bird's-eye maps) and Fig. 13 (a sumi-e) on the bundled Jacksboro DEM.

The terrain is rendered once; the contour image ``cn`` (of the true height), the profile image
``pr`` (from ``sz``), ``mx2`` (profiles + relief) and ``mx4`` (profiles + contours + relief +
colour bands) are image processing on the kept G-buffer, and so is a second set with other
contour intervals: nothing is rendered again. The sumi-e uses a lower view.

Usage: ``python examples/fig12_birdseye.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.compose import montage, write_png
from sciviz_gbuf.datasets import load_jacksboro_dem
from sciviz_gbuf.recipes import birdseye_gbuffer, birdseye_panels

SIZE = (960, 640)


def main(outdir: Path) -> list[Path]:
    """Write the Fig. 12 panels, their montage and the sumi-e to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    dem = load_jacksboro_dem()
    t0 = time.perf_counter()
    gb = birdseye_gbuffer(dem, window_size=SIZE, vert_exag=2.0)
    t1 = time.perf_counter()
    panels = birdseye_panels(gb, background=(1, 1, 1))
    t2 = time.perf_counter()
    fine = birdseye_panels(gb, interval=10, major_interval=50, background=(1, 1, 1))
    t3 = time.perf_counter()
    print(f"capture {t1 - t0:.2f} s; enhancement {t2 - t1:.2f} s, again {t3 - t2:.2f} s")
    written = [write_png(outdir / f"fig12_{k}.png", v) for k, v in panels.items()]
    tiles = [(f"({k})", panels[k]) for k in ("cn", "pr", "mx2", "mx4")]
    tiles.append(("(mx4) 10 m / 50 m contours, same G-buffer", fine["mx4"]))
    written.append(write_png(outdir / "fig12_montage.png", montage(tiles, columns=2)))
    ink = sg.sumi_e(dem, window_size=SIZE, elevation_angle=15.0, vert_exag=2.5)
    written.append(write_png(outdir / "fig13_sumi_e.png", ink))
    return written


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
