"""Line ink that never fills an area: solid clumps thinned to their centre lines.

Where line families converge (a torus's inner rim meeting its silhouette, profile detections
crowding on a surface seen at a grazing angle, a hole smaller than its outline) the antialiased
lines of a drawing add up to a solid black patch. A drawing has lines only, so such a patch
is replaced by its skeleton: the lines that run into it continue through it, one pixel wide.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["clump_cut", "clump_radius", "declump", "disc"]

_SQUARE = np.ones((3, 3), dtype=bool)


def disc(radius: int) -> np.ndarray:
    """A structuring element: the 3 x 3 square for radius 1, a digital disc beyond."""
    if radius <= 1:
        return _SQUARE
    y, x = np.mgrid[-radius : radius + 1, -radius : radius + 1]
    return (x * x + y * y) <= radius * radius + radius  # rounder than the strict disc


def clump_radius(width: float) -> int:
    """Erosion radius that removes every line up to ``width`` output pixels wide (its
    half-ink core is at most ``width + 1`` pixels across) but not a solid clump."""
    return max(1, int(np.ceil(0.5 * float(width))))


def clump_cut(ink: np.ndarray, width: float) -> np.ndarray | None:
    """The pixels :func:`declump` clears in ``ink`` (a boolean image), None without a clump.

    A clump is what survives the morphological opening of the half-ink pixels by a disc that
    no line of ``width`` pixels survives (:func:`clump_radius`). Inside it, and within a pixel
    of it (the antialiased fringe), only the skeleton of the half-ink pixels keeps its ink, so
    lines crossing or entering the clump stay connected.
    """
    solid = np.asarray(ink) > 0.5  # NaN compares False: no ink
    se = disc(clump_radius(width))
    core = ndimage.binary_erosion(solid, se)
    if not core.any():
        return None
    # scikit-image is heavy to import and only needed where there is a clump
    from skimage.morphology import skeletonize

    clump = ndimage.binary_dilation(core, se) & solid
    labels, _ = ndimage.label(clump, structure=_SQUARE)
    cut = np.zeros(solid.shape, dtype=bool)
    pad = se.shape[0] + 2
    for i, box in enumerate(ndimage.find_objects(labels), start=1):
        win = tuple(slice(max(b.start - pad, 0), b.stop + pad) for b in box)
        region = ndimage.binary_dilation(labels[win] == i, _SQUARE)
        # the skeleton of all the solid ink around, so lines entering the clump join it
        skel = skeletonize(solid[win])
        cut[win] |= region & ~skel
    return cut


def declump(ink: np.ndarray, width: float) -> np.ndarray:
    """``ink`` (lines, 1 = full ink) with every clump thicker than a line thinned to a skeleton.

    See :func:`clump_cut` for what a clump is and what stays of it. Lines elsewhere are not
    touched; ink without clumps is returned as it is (the same array).
    """
    ink = np.asarray(ink, dtype=np.float32)
    cut = clump_cut(ink, width)
    if cut is None:
        return ink
    out = ink.copy()
    out[cut] = np.float32(0.0)
    return out
