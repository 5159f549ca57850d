"""NPR styles and the Fig. 10 photocopy test
=========================================

NPR styles on PyVista's nut and a parametric torus, and the 1990 Fig. 10 photocopy test.

Nienhaus & Döllner 2003 §5: technical illustration (Gooch shading + edge map), cartoon shading
(hard and smoothed transitions) and halftone hatching; Saito & Takahashi 1990 Fig. 9: the line
drawing ``shuv`` of the torus's u and v; Fig. 10: the shaded image ``sh`` and the line drawing
``cv`` each copied five times by a model copy machine — the shade loses its gradation, the line
drawing survives. Each scene is captured once; every picture is a function of the G-buffer.

Usage: ``python examples/npr_styles.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf import styles
from sciviz_gbuf.compose import montage, write_png
from sciviz_gbuf.datasets import load_nut
from sciviz_gbuf.recipes import named_view_camera, seam_patches

SIZE = (480, 360)


def main(outdir: Path) -> list[Path]:
    """Write ``npr_styles.png`` and ``npr_photocopy.png`` into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    nut = load_nut()
    gb = sg.capture(
        nut, window_size=SIZE, camera=named_view_camera(nut.points, "iso"), supersample=2
    )
    torus = pv.ParametricTorus(texture_coordinates=True)
    tgb = sg.capture(
        torus, window_size=SIZE, camera=named_view_camera(torus.points, "iso"), supersample=2
    )
    # a surface parameterised without a seam (a closed torus's wrap shows in u/v strokes)
    patch = seam_patches("C2").to_mesh(resolution=48)
    view = ((1.0, -1.2, 4.0), (1.0, 0.75, 0.6), (0.0, 1.0, 0.0))
    pgb = sg.capture(patch, window_size=SIZE, camera=view, supersample=2)
    panels = [
        ("Gooch + edge map", styles.gooch(gb)),
        ("toon, 3 levels", styles.toon(gb, levels=3)),
        ("toon, smoothed", styles.toon(gb, levels=3, smooth=0.12)),
        ("hatching", styles.hatch(gb)),
        ("(shuv) line drawing", styles.line_drawing(tgb, combo="shuv")),
        ("uv hatching (two Bezier patches)", styles.hatch(pgb, space="uv")),
    ]
    written = [write_png(outdir / "npr_styles.png", montage(panels, columns=3))]
    sh = styles.line_drawing(tgb, combo="sh")
    cv = styles.line_drawing(tgb, combo="cv")
    copies = [
        ("(sh) original", sh),
        ("(sh) after 5 copies", styles.photocopy(sh, copies=5, seed=1)),
        ("(cv) original", cv),
        ("(cv) after 5 copies", styles.photocopy(cv, copies=5, seed=1)),
    ]
    written.append(write_png(outdir / "npr_photocopy.png", montage(copies, columns=2)))
    inside = tgb.downsample(tgb.mask.astype(np.float32)) == 1
    (_, sh0), (_, sh5), (_, cv0), (_, cv5) = copies
    mid = [np.mean((img[inside] > 0.1) & (img[inside] < 0.9)) for img in (sh0, sh5)]
    kept = np.mean(cv5[cv0 < 0.5] < 0.5)
    print(
        f"sh: mid-grey share of the torus {mid[0]:.0%} -> {mid[1]:.0%} after 5 copies; "
        f"cv: {kept:.0%} of the line pixels still dark"
    )
    return written


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(sys.argv[0]).resolve().parent / "output"
    for path in main(out):
        print(path)
