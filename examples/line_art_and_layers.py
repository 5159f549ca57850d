"""Vector line art, hidden lines and a translucent skin
=====================================================

Line drawings that stay sharp at any zoom, and what lies behind the visible surface.

The nut's profile and crease lines are traced into vector strokes
(:func:`sciviz_gbuf.edge_strokes`) and written as SVG and PDF; a capture that keeps the
surfaces behind the visible one (``capture(layers=4)``, the extended G-buffer of Saito &
Takahashi 1990 §5.1) gives the hidden lines of a technical drawing, dashed; and PyVista's
bundled frog is drawn with a translucent body envelope over its skeleton
(:func:`sciviz_gbuf.recipes.ct_translucent`).

Usage: ``python examples/line_art_and_layers.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.compose import write_png
from sciviz_gbuf.datasets import load_frog_body, load_frog_skeleton, load_nut
from sciviz_gbuf.recipes import (
    ct_surface,
    ct_translucent,
    technical_drawing,
    technical_drawing_image,
    write_vector,
)


def main(outdir: Path) -> list[Path]:
    """Write the nut's edges as SVG/PDF, its technical drawing (SVG and PNG) and the
    translucent frog into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    nut = load_nut()
    gb = sg.capture(nut, window_size=(640, 480), supersample=2, layers=4)
    strokes = sg.edge_strokes(gb, width=1.5)
    print(f"{len(strokes)} strokes, {sum(len(s.points) for s in strokes)} vertices")
    size = gb.output_shape[::-1]
    written = [sg.write_svg(outdir / "nut_edges.svg", strokes, size=size),
               sg.write_pdf(outdir / "nut_edges.pdf", strokes, size=size)]  # fmt: skip
    # visible lines solid, the edges of the surfaces behind dashed (the SVG and the PNG
    # draw the same strokes and dashes)
    written.append(write_vector(outdir / "nut_hidden.svg", technical_drawing(gb)))
    written.append(write_png(outdir / "nut_hidden.png", technical_drawing_image(gb)))
    skin = ct_surface(load_frog_body(), iso=0.5, scalars="body")
    bone = ct_surface(load_frog_skeleton(), iso=0.5)
    frog = ct_translucent(None, translucent=skin, inner=bone, view=(0.0, -0.7, 1.0),
                          window_size=(640, 480), background=(1.0, 1.0, 1.0))  # fmt: skip
    written.append(write_png(outdir / "frog_translucent.png", frog))
    return written


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
