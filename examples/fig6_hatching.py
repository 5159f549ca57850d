"""Fig. 6: curved hatching
=======================

Saito & Takahashi (1990) Fig. 6: curved hatching of ``s = x y``.

Contour lines at a regular interval are too sparse where the gradient is small and too dense
where it is large: unusable as hatching. Curved hatching (Eq. 17-21, "binary thinning out")
picks the interval per pixel, doubling or halving it, so that the lines stay about ``d_i``
pixels apart everywhere; the lines half way between appear gradually as the spacing grows.
Shown: the regular contours (lines 6 pixels apart half way from the centre to an edge), the
hatching with ``spacing=6`` and the filter's quick fade-in of the in-between lines
(``transition=0.2``, every visible spacing within +-33 % of 6 pixels), and the hatching with
Eq. 18 exactly (``transition=1``: an exactly constant mean ink, but faint in-between lines
over wider bands).

Usage: ``python examples/fig6_hatching.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from sciviz_gbuf.recipes import fig6_panels, write_panels

SIZE = 384


def main(outdir: Path) -> list[Path]:
    """Write one PNG per Fig. 6 panel and a montage into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    panels = fig6_panels(SIZE, spacing=6.0, width=1.0)
    return write_panels(outdir, "fig6", panels, columns=3)


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
