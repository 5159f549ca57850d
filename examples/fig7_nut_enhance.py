"""Fig. 7: edge enhancement of a shaded image
==========================================

Saito & Takahashi (1990) Fig. 7 on PyVista's machine nut: edge enhancement of a shaded image.

(a) a Lambert shade from the G-buffer's normals, light from the upper left; (b) the depth
(``sz``) image; (c) the edge image: convex internal edges white, concave edges and profiles
black, on mid grey; (d) the shade enhanced with (c), white lines giving the "edge highlight"
of industrial-design illustrations; (c'), (d') the same with all edges black (absolute values
of the internal edges). Then the 2003 variant (Nienhaus & Döllner): the shade enhanced with
the RGBA edge map of the ``diagonal`` and ``c1`` operators (white inner edges, black
profiles).

The capture is 3x supersampled, so lines (1.5 output pixels wide) and silhouettes are
antialiased.

Usage: ``python examples/fig7_nut_enhance.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.compose import montage, write_png
from sciviz_gbuf.datasets import load_nut
from sciviz_gbuf.recipes import fig7_panels, nut_camera

WINDOW = (640, 480)


def main(outdir: Path) -> list[Path]:
    """Capture the nut, write one PNG per Fig. 7 panel and a montage into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    nut = load_nut()
    camera = nut_camera(nut.bounds, aspect=WINDOW[0] / WINDOW[1])
    g = sg.capture(nut, window_size=WINDOW, camera=camera, supersample=3)
    print(g)
    panels = fig7_panels(g, width=1.5)
    written = [write_png(outdir / f"fig7_{key}.png", img) for key, _, img in panels]
    tiles = [(title, img) for _, title, img in panels]
    written.append(write_png(outdir / "fig7_montage.png", montage(tiles, columns=4)))
    return written


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
