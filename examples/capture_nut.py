"""Capture the G-buffers of a mesh
===============================

Capture the G-buffers of PyVista's nut and write each channel as a PNG.

Shows the basic workflow: one offscreen capture (:func:`sciviz_gbuf.capture`, default iso
view) gives depth, Saito's ``sz``, normals, world coordinates and ids, which
:mod:`sciviz_gbuf.compose` turns into images.

Usage: ``python examples/capture_nut.py [outdir]`` (default ``examples/output``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import sciviz_gbuf as sg
from sciviz_gbuf.compose import colorize, ids_to_rgb, montage, normals_to_rgb, write_png
from sciviz_gbuf.datasets import load_nut


def main(outdir: Path) -> list[Path]:
    """Capture the nut and write its channel images and a montage into ``outdir``."""
    outdir.mkdir(parents=True, exist_ok=True)
    g = sg.capture(load_nut(), window_size=(800, 600))
    print(g)
    images = {
        "depth": colorize(g.depth),
        "sz": colorize(g.sz),
        "normal": normals_to_rgb(g.normal),
        "world_z": colorize(g.world[..., 2], cmap="plasma"),
        "cell_id": ids_to_rgb(g.cell_id),
        "mask": g.mask,
    }
    written = [write_png(outdir / f"nut_{k}.png", v) for k, v in images.items()]
    written.append(write_png(outdir / "nut_montage.png", montage(list(images.items()), columns=3)))
    return written


if __name__ == "__main__":
    default = Path(sys.argv[0]).resolve().parent / "output"
    for path in main(Path(sys.argv[1]) if len(sys.argv) > 1 else default):
        print(path)
