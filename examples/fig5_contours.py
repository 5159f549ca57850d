"""Figs. 4 and 5: contour lines without tracking
=============================================

Saito & Takahashi (1990) Fig. 5 (and Fig. 4): contour lines of ``s = x y`` without tracking.

Every pixel gets ink from its own value ``s`` and the Eq. 9 gradient ``g`` of the field there:
``|s - p| / g`` is its distance in pixels to the level ``p``, and a line profile ``f1`` turns
that into ink (Eq. 7-14). The field of Eq. 16 has no gradient at the centre and a large one in
the corners, so the contour interval that gives readable lines half way out crowds them into
each other further out. Eq. 10 and 15 handle both ends: (a) the flat centre fades to white
(``c_sparse = 0``, ``g_eps`` = the gradient 0.3 from the centre) and the crowded corners fill
with black (``c_dense = 1``); (b) the same with a grey ``c_dense = 0.5``. Lines are 1.5 pixels
wide, one line width apart at distance 1 from the centre.

Then the three line profiles of Fig. 4, zoomed 8x with the pixels shown as squares: the
bilevel step of Eq. 8 (aliased), the linear ramp (exact pixel coverage, antialiased) and a
smooth higher-order profile.

Usage: ``python examples/fig5_contours.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from sciviz_gbuf.recipes import fig5_panels, write_panels

SIZE = 384


def main(outdir: Path) -> list[Path]:
    """Write one PNG per Fig. 5 panel (and the Fig. 4 crops) and a montage into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    panels = fig5_panels(SIZE, width=1.5)
    return write_panels(outdir, "fig5", panels, columns=5)


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
