"""Fig. 15: surface analysis of Bezier patches
===========================================

Saito & Takahashi 1990 Fig. 15: surface analysis of Bezier patches.

Without a patch file this builds the paper's surface in code: two bicubic patches joined with
C1 (not C2) continuity, and the same with a C2 join; each is rendered once and shown as contour
lines, reflection lines, zebra stripes and a mean-curvature map, so the C1 seam is seen where
the lines turn. With a ``.bpt`` file (e.g. the Utah teapot) every mode is drawn for that file.

Usage: ``python examples/fig15_surface_analysis.py [outdir] [FILE.bpt]``
(default outdir ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.compose import montage, write_png
from sciviz_gbuf.readers import read_patches
from sciviz_gbuf.recipes.surface import MODES, seam_patches, surface_gbuffer

VIEW = ((1.0, -1.2, 4.0), (1.0, 0.75, 0.6), (0.0, 1.0, 0.0))
OPTIONS = {"axis": (1.0, 0.4, 0.0), "stripes": 24, "background": (1.0, 1.0, 1.0)}


def main(outdir: Path, bpt: str | None = None) -> list[Path]:
    """Write the Fig. 15 montage (or one for ``bpt``) to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    panels = []
    if bpt is None:
        for continuity in ("C1", "C2"):
            gb = surface_gbuffer(seam_patches(continuity), view=VIEW, window_size=(480, 360))
            for mode in ("contours", "reflection", "stripes", "curvature"):
                image = sg.surface_analysis(gb, mode=mode, curvature="mean", **OPTIONS)
                panels.append((f"{continuity} join: {mode}", image))
        name = "fig15_seams.png"
    else:
        patches = read_patches(bpt)
        gb = surface_gbuffer(patches, window_size=(480, 360), resolution=24)
        for mode in MODES:
            image = sg.surface_analysis(gb, mode=mode, background=(1.0, 1.0, 1.0))
            panels.append((f"{Path(bpt).stem}: {mode}", image))
        name = f"fig15_{Path(bpt).stem}.png"
    return [write_png(outdir / name, montage(panels, columns=4))]


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(sys.argv[0]).resolve().parent / "output"
    for path in main(out, sys.argv[2] if len(sys.argv) > 2 else None):
        print(path)
