"""Numba kernel of the COG writer (:mod:`._cog_layout`): an overview level from the level
below it.

:func:`halve_rows` computes what ``_cog_layout.halve_reference`` states with numpy (a 5-D
reshape, sums over two axes in uint32, integer divisions): each pixel the rounded mean of the
2 x 2 below it, the colour weighted by alpha. The same integer arithmetic, so the same bytes
(tested); one pass instead of a dozen temporaries: 0.44 s -> ~0.02 s for a 2048² block, which
a COG's writer halves twice for every block of the map.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["halve_rows"]


@njit(cache=True, nogil=True, _nrt=False)
def halve_rows(i0: int, i1: int, a: np.ndarray, out: np.ndarray) -> None:
    """Rows ``i0 .. i1`` of the next level ``out`` ((h2, w2, c) uint8) of ``a`` ((h, w, c)
    uint8, h2 = ceil(h / 2), w2 = ceil(w / 2)): the rounded mean ``(s + n // 2) // n`` of the
    ``n`` pixels under each (1 or 2 at an odd edge); with c == 4 the colour is
    ``(sum(c alpha) + A // 2) // max(A, 1)`` for the alpha sum ``A``, and alpha the rounded
    mean of the alphas."""
    h, w, c = a.shape
    w2 = out.shape[1]
    for i in range(i0, i1):
        r0 = 2 * i
        nr = 2 if r0 + 1 < h else 1
        for j in range(w2):
            c0 = 2 * j
            nc = 2 if c0 + 1 < w else 1
            n = np.uint32(nr * nc)
            if c == 4:
                sa = np.uint32(0)
                s0 = np.uint32(0)
                s1 = np.uint32(0)
                s2 = np.uint32(0)
                for r in range(r0, r0 + nr):
                    for q in range(c0, c0 + nc):
                        al = np.uint32(a[r, q, 3])
                        sa += al
                        s0 += np.uint32(a[r, q, 0]) * al
                        s1 += np.uint32(a[r, q, 1]) * al
                        s2 += np.uint32(a[r, q, 2]) * al
                d = sa if sa > np.uint32(0) else np.uint32(1)
                half = sa // np.uint32(2)
                out[i, j, 0] = np.uint8((s0 + half) // d)
                out[i, j, 1] = np.uint8((s1 + half) // d)
                out[i, j, 2] = np.uint8((s2 + half) // d)
                out[i, j, 3] = np.uint8((sa + n // np.uint32(2)) // n)
            else:
                for ch in range(c):
                    s = np.uint32(0)
                    for r in range(r0, r0 + nr):
                        for q in range(c0, c0 + nc):
                            s += np.uint32(a[r, q, ch])
                    out[i, j, ch] = np.uint8((s + n // np.uint32(2)) // n)
