"""2003 Fig. 8: edges in a mirror
==============================

Nienhaus & Döllner (2003) §5, Fig. 8: an edge-enhanced scene with a planar mirror.

PyVista's machine nut and a ball stand in front of an upright rectangular mirror. The scene is
captured twice, from the camera and from the camera reflected about the mirror plane (without
the mirror, clipped to its front), both G-buffers are edge-enhanced separately (shade plus the
2003 edge map: white inner edges, black profiles), and the reflected image is composited into
the mirror, slightly tinted. The reflected nut therefore has its own profiles and inner edges,
detected from its own viewpoint, which edge detection on the main view alone (where the mirror
is a flat plane) cannot give.

Usage: ``python examples/mirror_edges.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from sciviz_gbuf.compose import write_png
from sciviz_gbuf.recipes.npr import MIRROR_CAMERA, mirror_scene
from sciviz_gbuf.styles.mirror import mirror_enhance

WINDOW = (800, 600)


def main(outdir: Path) -> Path:
    """Render the enhanced mirrored scene and write ``mirror_edges.png`` into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    image = mirror_enhance(mirror_scene(), 0, camera=MIRROR_CAMERA, window_size=WINDOW)
    return write_png(outdir / "mirror_edges.png", image)


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else default))
