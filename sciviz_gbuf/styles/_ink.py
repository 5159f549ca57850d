"""Line ink that never fills an area: solid clumps thinned to their centre lines.

Where line families converge (a torus's inner rim meeting its silhouette, profile detections
crowding on a surface seen at a grazing angle, a hole smaller than its outline) the antialiased
lines of a drawing add up to a solid black patch. A drawing has lines only, so such a patch
is replaced by its skeleton: the lines that run into it continue through it, one pixel wide.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ._ink_kernels import clump_mask

__all__ = ["clump_cut", "clump_radius", "declump", "disc", "solid_clump_cut"]

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
    return solid_clump_cut(np.asarray(ink) > 0.5, width)  # NaN compares False: no ink


def solid_clump_cut(solid: np.ndarray, width: float) -> np.ndarray | None:
    """:func:`clump_cut` of the half-ink pixels ``solid`` (a boolean image)."""
    solid = np.ascontiguousarray(solid, dtype=np.bool_)
    se = disc(clump_radius(width))
    dr, dc = (np.ascontiguousarray(v - se.shape[0] // 2, dtype=np.int64) for v in np.nonzero(se))
    core = np.empty(solid.shape, dtype=np.bool_)
    clump = np.empty(solid.shape, dtype=np.bool_)
    if not clump_mask(solid, dr, dc, core, clump):
        return None
    # scikit-image is heavy to import and only needed where there is a clump
    from skimage.morphology import skeletonize

    # Labelled within the clumps' bounding box (a few per cent of the picture, usually).
    rows, cols = np.nonzero(clump.any(axis=1))[0], np.nonzero(clump.any(axis=0))[0]
    r0, c0 = int(rows[0]), int(cols[0])
    labels, _ = ndimage.label(clump[r0 : rows[-1] + 1, c0 : cols[-1] + 1], structure=_SQUARE)
    cut = np.zeros(solid.shape, dtype=bool)
    pad = se.shape[0] + 2
    for i, box in enumerate(ndimage.find_objects(labels), start=1):
        rs, cs = box
        rs, cs = slice(rs.start + r0, rs.stop + r0), slice(cs.start + c0, cs.stop + c0)
        win = tuple(slice(max(b.start - pad, 0), b.stop + pad) for b in (rs, cs))
        region = ndimage.binary_dilation(_own(labels, i, r0, c0, win, solid.shape), _SQUARE)
        # the skeleton of all the solid ink around, so lines entering the clump join it
        skel = skeletonize(solid[win])
        cut[win] |= region & ~skel
    return cut


def _own(labels: np.ndarray, i: int, r0: int, c0: int, win: tuple, shape: tuple) -> np.ndarray:
    """``labels == i`` of the clump-box labelling over the window ``win`` of the image."""
    ra, rb = max(win[0].start, 0), min(win[0].stop, shape[0])
    ca, cb = max(win[1].start, 0), min(win[1].stop, shape[1])
    out = np.zeros((rb - ra, cb - ca), dtype=bool)
    # the part of the window the clump box covers
    la, lb = max(ra - r0, 0), min(rb - r0, labels.shape[0])
    ka, kb = max(ca - c0, 0), min(cb - c0, labels.shape[1])
    if la < lb and ka < kb:
        out[la + r0 - ra : lb + r0 - ra, ka + c0 - ca : kb + c0 - ca] = labels[la:lb, ka:kb] == i
    return out


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
