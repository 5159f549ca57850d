"""Numba kernels of :mod:`.tone`: the shade of ``N.L`` per buffer pixel, box-filtered to the
output size in the same pass (no buffer-size colour image in between)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["gooch_shade", "lambert_shade", "modulation_image", "toon_shade"]


@njit(inline="always", cache=True)
def _finite(v):
    """``np.nan_to_num(v, nan=0.0)`` of a float32."""
    big = np.float32(3.4028235e38)
    if np.isnan(v):
        return np.float32(0.0)
    return min(max(v, -big), big)


@njit(inline="always", cache=True)
def _n_dot_l(normal, mask, r, c, lx, ly, lz):
    """``N.L`` in float32 clipped to [-1, 1]; 0 off the surface, non-finite components as
    ``np.nan_to_num`` makes them on it (as ``tone._n_dot_l``)."""
    nx, ny, nz = normal[r, c, 0], normal[r, c, 1], normal[r, c, 2]
    d = nx * lx + ny * ly + nz * lz
    if np.isnan(d):
        if not mask[r, c]:
            return np.float32(0.0)
        nx, ny, nz = _finite(nx), _finite(ny), _finite(nz)
        d = nx * lx + ny * ly + nz * lz
    return min(max(d, np.float32(-1.0)), np.float32(1.0))


def gooch_shade(normal, mask, light, k_warm, k_cool, bg, clip, k, out):
    """``out`` (h, w, 3): the ``k x k`` block means of ``clip(t k_warm + (1 - t) k_cool)``,
    ``t = (1 + N.L) / 2``, paper ``bg`` off the mask, clipped to [0, 1] (``tone.gooch``)."""
    run_bands(_gooch_rows, out.shape[0], normal, mask, light, k_warm, k_cool, bg, clip, k, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _gooch_rows(r0, r1, normal, mask, light, k_warm, k_cool, bg, clip, k, out):
    """Output rows ``r0 .. r1`` of :func:`gooch_shade` (one band of :func:`.run_bands`)."""
    ow = out.shape[1]
    lx, ly, lz = light[0], light[1], light[2]
    half = np.float32(0.5)
    one = np.float32(1.0)
    for r in range(r0, r1):
        r = np.int64(r)
        for col in range(ow):
            t0 = 0.0
            t1 = 0.0
            t2 = 0.0
            for i in range(r * k, r * k + k):
                for j in range(col * k, col * k + k):
                    if not mask[i, j]:
                        t0 += bg[0]
                        t1 += bg[1]
                        t2 += bg[2]
                        continue
                    t = (_n_dot_l(normal, mask, i, j, lx, ly, lz) + one) * half
                    u = one - t
                    for ch in range(3):
                        v = t * k_warm[ch] + u * k_cool[ch]
                        if clip:
                            v = min(max(v, np.float32(0.0)), one)
                        if ch == 0:
                            t0 += v
                        elif ch == 1:
                            t1 += v
                        else:
                            t2 += v
            n = k * k
            for ch in range(3):
                tot = t0 if ch == 0 else (t1 if ch == 1 else t2)
                v = np.float32(tot / n)
                out[r, col, ch] = min(max(v, np.float32(0.0)), one)


def toon_shade(normal, mask, light, table, bg, k, out):
    """``out`` (h, w, 3): the ``k x k`` block means of the toon texel of ``max(N.L, 0)`` (the
    ``n`` texels of ``table``, paper ``bg`` off the mask), clipped to [0, 1] (``tone.toon``
    without smoothing)."""
    run_bands(_toon_rows, out.shape[0], normal, mask, light, table, bg, k, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _toon_rows(r0, r1, normal, mask, light, table, bg, k, out):
    """Output rows ``r0 .. r1`` of :func:`toon_shade`."""
    ow = out.shape[1]
    lx, ly, lz = light[0], light[1], light[2]
    n_tex = table.shape[0]
    fn = np.float32(n_tex)
    one = np.float32(1.0)
    for r in range(r0, r1):
        r = np.int64(r)
        for col in range(ow):
            t0 = 0.0
            t1 = 0.0
            t2 = 0.0
            for i in range(r * k, r * k + k):
                for j in range(col * k, col * k + k):
                    if not mask[i, j]:
                        t0 += bg[0]
                        t1 += bg[1]
                        t2 += bg[2]
                        continue
                    s = max(_n_dot_l(normal, mask, i, j, lx, ly, lz), np.float32(0.0))
                    idx = min(np.int64(s * fn), n_tex - 1)
                    t0 += table[idx, 0]
                    t1 += table[idx, 1]
                    t2 += table[idx, 2]
            n = k * k
            for ch in range(3):
                tot = t0 if ch == 0 else (t1 if ch == 1 else t2)
                v = np.float32(tot / n)
                out[r, col, ch] = min(max(v, np.float32(0.0)), one)


def lambert_shade(normal, mask, light, ambient, highlight, k, out):
    """``out`` (h, w): the ``k x k`` block means of ``highlight * clip(ambient + (1 - ambient)
    max(N.L, 0))`` on the surface and 1 (paper) off it, NaN normals left out, clipped to
    [0, 1] (``illustration.shade_image``, with ``filters.lambert``'s arithmetic)."""
    run_bands(_lambert_rows, out.shape[0], normal, mask, light, ambient, highlight, k, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _lambert_rows(r0, r1, normal, mask, light, ambient, highlight, k, out):
    """Output rows ``r0 .. r1`` of :func:`lambert_shade`."""
    ow = out.shape[1]
    lx, ly, lz = light[0], light[1], light[2]
    one = np.float32(1.0)
    zero = np.float32(0.0)
    rest = np.float32(1.0 - ambient)
    amb = np.float32(ambient)
    hi = np.float32(highlight)
    for r in range(r0, r1):
        r = np.int64(r)
        for col in range(ow):
            tot = 0.0
            n = 0
            for i in range(r * k, r * k + k):
                for j in range(col * k, col * k + k):
                    if not mask[i, j]:
                        tot += 1.0
                        n += 1
                        continue
                    d = normal[i, j, 0] * lx + normal[i, j, 1] * ly + normal[i, j, 2] * lz
                    if np.isnan(d):
                        continue
                    s = amb + rest * max(d, zero)
                    s = min(max(s, zero), one)
                    tot += hi * s
                    n += 1
            if n == 0:
                out[r, col] = np.float32(np.nan)
            else:
                v = np.float32(tot / n)
                out[r, col] = min(max(v, zero), one)


def modulation_image(normal, mask, light, none, full, out):
    """``out`` (h, w): ``lines.modulation(filters.lambert(normal, light=light, mask=mask))``
    value for value at the buffer resolution, without the shade image in between: the
    smoothstep of the tone ``1 - max(N.L, 0)`` from ``none`` to ``full`` (float32, N.L summed
    component by component as ``lambert`` does); 0 off the mask and where N.L is NaN."""
    run_bands(_modulation_rows, mask.shape[0], normal, mask, light, none, full, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _modulation_rows(r0, r1, normal, mask, light, none, full, out):
    """Rows ``r0 .. r1`` of :func:`modulation_image`."""
    w = mask.shape[1]
    lx, ly, lz = light[0], light[1], light[2]
    one = np.float32(1.0)
    zero = np.float32(0.0)
    lo = np.float32(none)
    span = np.float32(full - none)
    three = np.float32(3.0)
    two = np.float32(2.0)
    for r in range(r0, r1):
        r = np.int64(r)
        for c in range(w):
            d = normal[r, c, 0] * lx
            d += normal[r, c, 1] * ly
            d += normal[r, c, 2] * lz
            # NaN shade (off the mask, NaN normal) is read as 1 (lit): tone 0, no ink
            s = min(max(d, zero), one) if (mask[r, c] and d == d) else one
            x = min(max(((one - s) - lo) / span, zero), one)
            out[r, c] = x * x * (three - two * x)
