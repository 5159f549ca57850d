"""Rasterise vector strokes back to pixels, independently of the package (test helper).

Each segment is sampled every 0.1 px and each sample marks the pixel whose centre is nearest
(pixel centres at integers, x the column, y the row): a one-pixel-wide digital line along the
stroke's centre, what an image-space line detector would report for it.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable

import numpy as np


def rasterize(strokes: Iterable, shape: tuple[int, int], step: float = 0.1) -> np.ndarray:
    """Bool image of ``shape`` with the pixels the strokes' centre lines pass through."""
    out = np.zeros(shape, bool)
    h, w = shape
    for s in strokes:
        pts = np.asarray(s.points, np.float64)
        if s.closed and len(pts) > 2:
            pts = np.vstack([pts, pts[:1]])
        if len(pts) == 1:
            pts = np.vstack([pts, pts])
        for a, b in itertools.pairwise(pts):
            n = max(2, int(np.ceil(np.hypot(*(b - a)) / step)) + 1)
            t = np.linspace(0.0, 1.0, n)[:, None]
            xy = np.rint(a + t * (b - a)).astype(np.int64)
            ok = (xy[:, 0] >= 0) & (xy[:, 0] < w) & (xy[:, 1] >= 0) & (xy[:, 1] < h)
            out[xy[ok, 1], xy[ok, 0]] = True
    return out
