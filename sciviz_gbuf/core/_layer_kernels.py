"""The triangles behind the visible one, per pixel: a k-buffer rasteriser for multi-layer
G-buffers (``capture(layers=k)``; 1990 §5.1's "extended" G-buffer).

The first layer is the GPU's visibility buffer. For the layers behind it every triangle is
rasterised again here, on the CPU, at the same pixel centres: a pixel centre is inside a
triangle by its three edge functions in float64, with the top-left rule on edges (a point on
an edge shared by two triangles belongs to exactly one of them, so a surface never shows up
twice at a pixel), and its eye depth is interpolated perspective-correctly (``1/d`` is affine
in screen space; ``d`` itself in a parallel projection). Each pixel keeps its nearest
fragments deeper than its first layer by more than a tolerance (the same surface, rasterised
by another triangle than the GPU chose, is not a layer behind it), as a sorted k-buffer.
The exact hit of each layer's triangle (world point, normal, ...) is then resolved by
:mod:`._capture_kernels`, as for the first layer.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .bands import run_bands

__all__ = ["peel_layers"]


def peel_layers(sx, sy, inv_d, tri, tid1, depth1, tol, parallel, out_tid, out_depth):
    """Fill ``out_tid`` / ``out_depth`` (L, H, W) with the triangles and eye depths of the
    ``L`` surfaces behind ``tid1`` / ``depth1`` at each pixel, nearest first (-1 / inf where
    there are fewer).

    Parameters
    ----------
    sx, sy : (n,) float64
        Vertices in pixel coordinates (column, row; pixel centres at integers, row 0 on top).
    inv_d : (n,) float64
        ``1 / d`` of each vertex (``d`` its eye depth along the view axis); ``d`` itself when
        ``parallel``. NaN for a vertex behind the eye: its triangles are skipped.
    tri : (m, 3) int64
    tid1 : (H, W) int64 and depth1 : (H, W) float32
        The first layer (triangle, depth; -1 / NaN on background).
    tol : (H, W) float64
        How much deeper than the layer before it a fragment must be to be a layer of its own
        (world units).
    parallel : bool
    """
    run_bands(_peel_rows, tid1.shape[0], sx, sy, inv_d, tri, tid1, depth1, tol, parallel,
              out_tid, out_depth)  # fmt: skip


@njit(inline="always", cache=True)
def _top_left(ax, ay, bx, by):
    """Whether edge a -> b of a positively oriented triangle owns the points on it."""
    dy = by - ay
    return dy > 0.0 or (dy == 0.0 and bx - ax < 0.0)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _peel_rows(
    r0, r1, sx, sy, inv_d, tri, tid1, depth1, tol, parallel, out_tid, out_depth
):  # fmt: skip
    """Rows ``r0 .. r1`` of :func:`peel_layers` (one band of :func:`.run_bands`): every
    triangle, clipped to the band."""
    n_layers, _h, w = out_tid.shape
    for r in range(r0, r1):
        for c in range(w):
            for k in range(n_layers):
                out_tid[k, r, c] = -1
                out_depth[k, r, c] = np.inf
    for t in range(tri.shape[0]):
        i0, i1, i2 = tri[t, 0], tri[t, 1], tri[t, 2]
        q0, q1, q2 = inv_d[i0], inv_d[i1], inv_d[i2]
        if not (np.isfinite(q0) and np.isfinite(q1) and np.isfinite(q2)):
            continue
        x0, y0 = sx[i0], sy[i0]
        x1, y1 = sx[i1], sy[i1]
        x2, y2 = sx[i2], sy[i2]
        area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
        if area == 0.0 or not np.isfinite(area):
            continue
        if area < 0.0:  # orient positively (swap 1 and 2)
            x1, y1, x2, y2 = x2, y2, x1, y1
            q1, q2 = q2, q1
            area = -area
        ra = max(r0, int(np.ceil(min(y0, y1, y2))))
        rb = min(r1 - 1, int(np.floor(max(y0, y1, y2))))
        ca = max(0, int(np.ceil(min(x0, x1, x2))))
        cb = min(w - 1, int(np.floor(max(x0, x1, x2))))
        if ra > rb or ca > cb:
            continue
        tl0 = _top_left(x1, y1, x2, y2)
        tl1 = _top_left(x2, y2, x0, y0)
        tl2 = _top_left(x0, y0, x1, y1)
        for r in range(ra, rb + 1):
            py = float(r)
            for c in range(ca, cb + 1):
                px = float(c)
                # edge functions: e0 opposite vertex 0, ...
                e0 = (x2 - x1) * (py - y1) - (y2 - y1) * (px - x1)
                e1 = (x0 - x2) * (py - y2) - (y0 - y2) * (px - x2)
                e2 = (x1 - x0) * (py - y0) - (y1 - y0) * (px - x0)
                if e0 < 0.0 or e1 < 0.0 or e2 < 0.0:
                    continue
                if (e0 == 0.0 and not tl0) or (e1 == 0.0 and not tl1) or (e2 == 0.0 and not tl2):
                    continue
                q = (e0 * q0 + e1 * q1 + e2 * q2) / area
                d = q if parallel else 1.0 / q
                first = tid1[r, c]
                if first < 0 or first == t:
                    continue
                if not d > depth1[r, c] + tol[r, c]:
                    continue
                # insert into the pixel's sorted k-buffer
                if not d < out_depth[n_layers - 1, r, c]:
                    continue
                k = n_layers - 1
                while k > 0 and out_depth[k - 1, r, c] > d:
                    out_depth[k, r, c] = out_depth[k - 1, r, c]
                    out_tid[k, r, c] = out_tid[k - 1, r, c]
                    k -= 1
                out_depth[k, r, c] = d
                out_tid[k, r, c] = t
