"""Numba kernel of :mod:`.hatch`: the screen-space strokes of every family, pixel by pixel."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["hatch_compose", "screen_strokes"]


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
    # the families' sines and cosines (float64 theta: libm's sin and cos, as numba's math.*)
    sin_a = np.array([math.sin(float(a)) for a in theta], dtype=np.float64)
    cos_a = np.array([math.cos(float(a)) for a in theta], dtype=np.float64)
    run_bands(
        _strokes_rows, mask.shape[0], normal, mask, light, sin_a, cos_a, sp, cap_w, tau, left,
        max_ink, out,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _strokes_rows(r0, r1, normal, mask, light, sin_a, cos_a, sp, cap_w, tau, left, max_ink, out):
    """Rows ``r0 .. r1`` of :func:`screen_strokes` (one band of :func:`.run_bands`)."""
    h, w = mask.shape
    n = sin_a.size
    lx, ly, lz = light[0], light[1], light[2]
    one = np.float32(1.0)
    zero = np.float32(0.0)
    half = np.float32(0.5)
    period = np.float32(sp)
    m_ink = np.float32(max_ink)
    for r in range(r0, r1):
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


def hatch_compose(strokes, k, mask, prof, edges, halo_core, ink_c, paper_c, out):
    """``out`` (h, w, 3): the hatch picture of ``hatch.hatch`` from its buffer-size stroke ink.

    The stroke amount is the ``k x k`` block mean of ``strokes`` (NaN left out) clipped to
    [0, 1]; with ``edges``, it gives way next to the profiles (``prof``, output size) by their
    3 x 3 maximum with edges repeated (``hatch.profile_halo``: 0 on the lines' own pixels, ink
    >= ``halo_core``, and where the block is not fully covered), and the profiles are drawn
    over it (``* (1 - prof)``); then ``amount (ink - paper) + paper``, clipped, in float32.
    """
    run_bands(
        _compose_rows, out.shape[0], strokes, k, mask, prof, edges, halo_core, ink_c, paper_c, out
    )


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _compose_rows(r0, r1, strokes, k, mask, prof, edges, halo_core, ink_c, paper_c, out):
    """Output rows ``r0 .. r1`` of :func:`hatch_compose` (the 3 x 3 maximum reads ``prof``
    rows beyond the band: an input, not written here)."""
    oh, ow = out.shape[0], out.shape[1]
    one = np.float32(1.0)
    zero = np.float32(0.0)
    for r in range(r0, r1):
        r = np.int64(r)
        for c in range(ow):
            if k == 1:
                a = strokes[r, c]
            else:
                tot = 0.0
                n = 0
                for i in range(r * k, r * k + k):
                    for j in range(c * k, c * k + k):
                        v = strokes[i, j]
                        if not np.isnan(v):
                            tot += v
                            n += 1
                a = np.float32(tot / n) if n > 0 else np.float32(np.nan)
            a = min(max(a, zero), one) if a == a else a
            keep = one
            if edges:
                p = prof[r, c]
                halo = zero
                if not p >= halo_core:
                    halo = np.float32(-np.inf)
                    for dr in range(-1, 2):
                        rr = min(max(r + dr, 0), oh - 1)
                        for dc in range(-1, 2):
                            cc = min(max(c + dc, 0), ow - 1)
                            halo = max(halo, prof[rr, cc])
                    cover = 0.0
                    for i in range(r * k, r * k + k):
                        for j in range(c * k, c * k + k):
                            cover += 1.0 if mask[i, j] else 0.0
                    if np.float32(cover / (k * k)) < one:
                        halo = zero
                a = a * (one - halo)
                keep = one - p
            for ch in range(3):
                v = a * (ink_c[ch] - paper_c[ch])
                v += paper_c[ch]
                if edges:
                    v *= keep
                out[r, c, ch] = min(max(v, zero), one) if v == v else v
