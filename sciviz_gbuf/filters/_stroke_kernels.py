"""Antialiased rasterisation of stroke segments (for :func:`.strokes.draw_strokes`)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["draw_segments"]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def draw_segments(seg, width, caps, out):
    """Max-combine the ink of straight segments into ``out`` (H, W) float32.

    ``seg`` (n, 4) float64 ``x0, y0, x1, y1`` in pixels (pixel centres at integers), ``width``
    (n,) float64, ``caps`` (n, 2) bool: a round cap (a joint of a polyline) at the start / end,
    else butt (a stroke's or a dash's end). The ink of a pixel is its coverage by the segment's
    band, box-filtered by one pixel: ``clip(w / 2 + 0.5 - distance, 0, 1)`` across, and the
    same ramp along the segment at butt ends.
    """
    h, w = out.shape
    for i in range(seg.shape[0]):
        x0, y0, x1, y1 = seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3]
        half = 0.5 * width[i]
        dx, dy = x1 - x0, y1 - y0
        length = np.sqrt(dx * dx + dy * dy)
        if length > 0.0:
            ux, uy = dx / length, dy / length
        else:
            ux, uy = 1.0, 0.0
        reach = half + 1.0
        ca = max(0, int(np.floor(min(x0, x1) - reach)))
        cb = min(w - 1, int(np.ceil(max(x0, x1) + reach)))
        ra = max(0, int(np.floor(min(y0, y1) - reach)))
        rb = min(h - 1, int(np.ceil(max(y0, y1) + reach)))
        for r in range(ra, rb + 1):
            for c in range(ca, cb + 1):
                px, py = c - x0, r - y0
                t = px * ux + py * uy
                across = abs(px * uy - py * ux)
                if t < 0.0:
                    if caps[i, 0]:
                        d = np.sqrt(px * px + py * py)
                        along = 1.0
                    else:
                        d = across
                        along = min(max(0.5 + t, 0.0), 1.0)
                elif t > length:
                    if caps[i, 1]:
                        qx, qy = c - x1, r - y1
                        d = np.sqrt(qx * qx + qy * qy)
                        along = 1.0
                    else:
                        d = across
                        along = min(max(0.5 - (t - length), 0.0), 1.0)
                else:
                    d = across
                    along = min(max(0.5 + t, 0.0), 1.0) if not caps[i, 0] else 1.0
                    if not caps[i, 1]:
                        along = min(along, min(max(0.5 + (length - t), 0.0), 1.0))
                ink = min(max(half + 0.5 - d, 0.0), 1.0) * along
                if ink > out[r, c]:
                    out[r, c] = np.float32(ink)
