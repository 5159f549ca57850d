"""Numba kernel of :mod:`.hatch`: the screen-space strokes of every family, pixel by pixel."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = ["screen_strokes"]


@njit(parallel=True, cache=True)
def screen_strokes(normal, mask, light, theta, sp, cap_w, tau, left, max_ink, out):
    """``out`` (H, W): the stroke ink ``1 - prod_f (1 - ink_f)`` of the families that ink each
    pixel with ``tone > 0`` (family ``f >= 1`` where ``tone > tau[f]``), 0 elsewhere; the tone
    is ``1 - max(N.L, 0)`` on the surface (``hatch._tone``: ``filters.lambert``'s arithmetic,
    0 off the surface and where the normal is NaN).

    The arithmetic of ``hatch.hatch`` in screen space, value for value: the stroke coordinate
    ``(-x sin a + y cos a) / sp`` in float64 (x right, y up, in pixels), the family coverage
    (``_family_coverage``), the width ``cover sp`` (capped at ``cap_w`` if ``cap_w >= 0``) and
    the antialiased ink (``stroke_ink``) in float32.
    """
    h, w = mask.shape
    n = theta.size
    lx, ly, lz = light[0], light[1], light[2]
    sin_a = np.empty(n, dtype=np.float64)
    cos_a = np.empty(n, dtype=np.float64)
    for f in range(n):
        sin_a[f] = math.sin(theta[f])
        cos_a[f] = math.cos(theta[f])
    one = np.float32(1.0)
    zero = np.float32(0.0)
    half = np.float32(0.5)
    period = np.float32(sp)
    m_ink = np.float32(max_ink)
    for r in prange(h):
        r = np.int64(r)
        y = np.float64(np.float32(h - 1 - r))
        for c in range(w):
            t = zero
            if mask[r, c]:
                d = normal[r, c, 0] * lx + normal[r, c, 1] * ly + normal[r, c, 2] * lz
                if d == d:
                    t = one - min(max(max(d, zero), zero), one)
            if not t > 0:
                out[r, c] = zero
                continue
            x = np.float64(np.float32(c))
            paper = one
            for f in range(n):
                if f > 0 and not t > tau[f]:
                    break
                top = min(t, tau[f + 1])
                cover = one - (one - m_ink * top) / left[f]
                cover = min(max(cover, zero), one)
                along = -x * sin_a[f] + y * cos_a[f]
                along /= sp
                d = np.float32((along - np.rint(along)) * np.float64(period))
                width = cover * period
                if cap_w >= 0.0:
                    width = min(width, np.float32(cap_w) * (period / period))
                wd = max(width, zero)
                dist = abs(d)
                reach = max((wd + one) * half, one)
                ink = min(wd, one) * min(max(reach - dist, zero), one)
                paper *= one - ink
            out[r, c] = one - paper
