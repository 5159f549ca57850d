"""Per-pixel kernels of colour bands and of the map composite (bands x relief, then ink).

One function, :func:`_band_rgb`, picks a pixel's band colour for both
:func:`~sciviz_gbuf.filters.color_bands` (float32 RGBA) and the topographic map's fused
composite (uint8 RGBA), which never builds a float image of the whole map: at 8192² that
would be 1 GB, and the numpy passes cost more than the hillshade and contours together.
All arithmetic is float32, as numpy does it on float32 heights.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands

# Band modes: a continuous ramp, regular bands of an interval, bands between levels.
CONTINUOUS, INTERVAL, LEVELS = 0, 1, 2


@njit(cache=True, inline="always")
def _lut_index(rep, lo, scale, n):
    """Entry of a ``n``-colour table for ``rep``; ``scale = (n-1)/(hi-lo)``, 0 for the middle."""
    if scale == 0:
        t = np.float32((n - 1) / 2)
    else:
        t = (rep - lo) * scale
    if np.isnan(t):
        return 0
    t = np.rint(t)
    if t < 0:
        return 0
    if t > n - 1:
        return n - 1
    return int(t)


@njit(cache=True, inline="always")
def _band_rgb(v, mode, base, q, levels, mids, land, sea, tab):
    """The band colour of height ``v`` (float32); ``tab`` = (land_lo, land_scale, sea_lo,
    sea_scale, sea_level) as float32, sea_level NaN without a sea."""
    if mode == INTERVAL:
        rep = (np.floor((v - base) / q) + np.float32(0.5)) * q + base
    elif mode == LEVELS:
        rep = np.float32(mids[np.searchsorted(levels, v, side="right")])
    else:
        rep = v
    if not np.isnan(tab[4]) and v < tab[4]:
        i = _lut_index(rep, tab[2], tab[3], sea.shape[0])
        return sea[i, 0], sea[i, 1], sea[i, 2]
    i = _lut_index(rep, tab[0], tab[1], land.shape[0])
    return land[i, 0], land[i, 1], land[i, 2]


def band_image(z, valid, mode, base, q, levels, mids, land, sea, tab, out):
    """``out[..., :3]`` band colours and ``out[..., 3]`` 1 where ``valid``; zeros elsewhere."""
    run_bands(_band_rows, z.shape[0], z, valid, mode, base, q, levels, mids, land, sea, tab, out)


# error_model="numpy" in the band kernels, as numba compiled the prange loop bodies they
# replace: a division by zero gives inf / NaN, it does not raise.
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _band_rows(i0, i1, z, valid, mode, base, q, levels, mids, land, sea, tab, out):
    """Rows ``i0 .. i1`` of :func:`band_image` (one band of :func:`.run_bands`)."""
    w = z.shape[1]
    for i in range(i0, i1):
        for j in range(w):
            if valid[i, j]:
                r, g, b = _band_rgb(z[i, j], mode, base, q, levels, mids, land, sea, tab)
                out[i, j, 0] = r
                out[i, j, 1] = g
                out[i, j, 2] = b
                out[i, j, 3] = np.float32(1.0)
            else:
                for c in range(4):
                    out[i, j, c] = np.float32(0.0)


@njit(cache=True, inline="always")
def _to_byte(x):
    x = min(max(x, np.float32(0.0)), np.float32(1.0))
    return np.uint8(np.rint(x * np.float32(255.0)))


def map_image(
    z,
    bands,
    mode,
    base,
    q,
    levels,
    mids,
    land,
    sea,
    tab,
    relief,
    sh,
    flat,
    lit,
    sky,
    ink,
    ink_rgb,
    out,
):
    """The topographic map's pixels as uint8 RGBA ``out``.

    Colour: the band colour (``bands``) or white. Relief (``relief``): ``light = 1/3 sky +
    2/3 sh lit / flat`` (``lit``, ``sky`` are ignored when empty), 1 on open flat ground;
    below 1 it multiplies the colour, above 1 it lifts it up to halfway to white. Then the
    contour ``ink`` (if not empty) blends towards ``ink_rgb``. NaN heights: transparent black.
    """
    run_bands(
        _map_rows, z.shape[0], z, bands, mode, base, q, levels, mids, land, sea, tab, relief,
        sh, flat, lit, sky, ink, ink_rgb, out,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _map_rows(
    i0,
    i1,
    z,
    bands,
    mode,
    base,
    q,
    levels,
    mids,
    land,
    sea,
    tab,
    relief,
    sh,
    flat,
    lit,
    sky,
    ink,
    ink_rgb,
    out,
):
    """Rows ``i0 .. i1`` of :func:`map_image` (one band of :func:`.run_bands`)."""
    w = z.shape[1]
    use_lit = lit.shape[0] > 0
    use_sky = sky.shape[0] > 0
    use_ink = ink.shape[0] > 0
    third = np.float32(1.0 / 3.0)
    for i in range(i0, i1):
        for j in range(w):
            v = z[i, j]
            if np.isnan(v):
                for c in range(4):
                    out[i, j, c] = 0
                continue
            if bands:
                r, g, b = _band_rgb(v, mode, base, q, levels, mids, land, sea, tab)
            else:
                r = g = b = np.float32(1.0)
            if relief:
                d = sh[i, j] / flat
                if use_lit:
                    d *= lit[i, j]
                a = sky[i, j] if use_sky else np.float32(1.0)
                light = third * a + (np.float32(1.0) - third) * d
                if np.isnan(light):
                    light = np.float32(1.0)
                m = min(light, np.float32(1.0))
                up = np.float32(0.5) * min(
                    max(light - np.float32(1.0), np.float32(0.0)), np.float32(1.0)
                )
                r = r * m + (np.float32(1.0) - r) * up
                g = g * m + (np.float32(1.0) - g) * up
                b = b * m + (np.float32(1.0) - b) * up
            if use_ink:
                k = ink[i, j]
                r = r * (np.float32(1.0) - k) + ink_rgb[0] * k
                g = g * (np.float32(1.0) - k) + ink_rgb[1] * k
                b = b * (np.float32(1.0) - k) + ink_rgb[2] * k
            out[i, j, 0] = _to_byte(r)
            out[i, j, 1] = _to_byte(g)
            out[i, j, 2] = _to_byte(b)
            out[i, j, 3] = 255
