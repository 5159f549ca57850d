"""A bird's-eye G-buffer of real terrain
=====================================

A bird's-eye G-buffer of real terrain: the Jacksboro fault DEM seen from the south-east.

The DEM (Matplotlib's sample data) becomes a surface in metres with north at +y
(:func:`sciviz_gbuf.datasets.load_jacksboro_terrain`, vertical exaggeration 2), a perspective
camera is placed to frame it from the south-east, and the capture carries the ``elevation``
point array along with the geometric channels. The G-buffer is saved as ``.npz`` so
enhancements can be run later without rendering again.

Usage: ``python examples/terrain_birdseye_gbuffer.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.apps.demo import terrain_birdseye_camera
from sciviz_gbuf.compose import colorize, montage, normals_to_rgb, write_png
from sciviz_gbuf.datasets import load_jacksboro_terrain

WINDOW = (1024, 768)


def main(outdir: Path) -> list[Path]:
    """Capture the terrain and write channel images, a montage and the G-buffer to ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    terrain = load_jacksboro_terrain(vert_exag=2.0)
    camera = terrain_birdseye_camera(terrain.bounds, aspect=WINDOW[0] / WINDOW[1])
    g = sg.capture(terrain, window_size=WINDOW, camera=camera, scalars=["elevation"])
    print(g)
    images = {
        "depth": colorize(g.depth),
        "normal": normals_to_rgb(g.normal),
        "elevation": colorize(g.scalars["elevation"], cmap="terrain"),
        # northing shows which way is north: it grows away from the viewer
        "northing": colorize(g.world[..., 1], cmap="plasma"),
    }
    written = [write_png(outdir / f"terrain_{k}.png", v) for k, v in images.items()]
    written.append(
        write_png(outdir / "terrain_montage.png", montage(list(images.items()), columns=2))
    )
    written.append(g.save(outdir / "terrain_gbuffer.npz"))
    return written


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
