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


def map_image_fast(
    z, bands, mode, base, q, levels, mids, land, sea, tab, relief, sh, flat, lit, sky, ink,
    ink_rgb, out,
):  # fmt: skip
    """:func:`map_image` as loops LLVM vectorises, the same bytes (tested): per row, one
    loop finds each pixel's row of the stacked colour table ``[land; sea]`` (a binary search
    per pixel with explicit ``levels``), a second gathers the colours, lights them and
    writes each pixel as one 32-bit word. The optional layers come as rows of ones
    (``lit``, ``sky``) or zeros (``ink``) when absent: multiplying by 1 and adding 0 leave
    float32 values as they are, so the loops have no per-pixel branches."""
    h, w = z.shape
    table = np.concatenate([land[:, :3], sea[:, :3]]).astype(np.float32)
    rgb = np.ascontiguousarray(table.T)  # (3, n): one gather table per channel
    if not bands:
        rgb[:] = np.float32(1.0)
    out32 = out.reshape(h, w * 4).view(np.uint32)
    ones = np.ones(w, np.float32)
    zeros = np.zeros(w, np.float32)
    run_bands(
        _map_rows_fast, h, z, bands, mode, base, q, levels, mids, land.shape[0],
        sea.shape[0], tab, rgb, relief, sh, flat, lit, sky, ink, ink_rgb, ones, zeros, out32,
        scratch=lambda: (np.empty(w, np.int32), *(np.empty(w, np.float32) for _ in range(3))),
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _index_row(zi, mode, base, q, levels, mids, n_land, n_sea, tab, rep, idx):
    """``idx[j]``: the row of the stacked table ``[land; sea]`` of ``zi[j]``'s colour, as
    :func:`_band_rgb` picks it (``_lut_index``'s arithmetic, its branches as selects);
    ``rep`` is scratch. One loop per step and mode, so that each vectorises."""
    n = zi.shape[0]
    if mode == INTERVAL:
        _interval_rep(zi, base, q, rep)
    elif mode == LEVELS:
        for j in range(n):
            rep[j] = np.float32(mids[np.searchsorted(levels, zi[j], side="right")])
    else:
        for j in range(n):
            rep[j] = zi[j]
    _table_index(zi, rep, n_land, n_sea, tab[0], tab[1], tab[2], tab[3], tab[4], idx)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _interval_rep(zi, base, q, rep):
    half = np.float32(0.5)
    for j in range(zi.shape[0]):
        rep[j] = (np.floor((zi[j] - base) / q) + half) * q + base


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _table_index(zi, rep, n_land, n_sea, lo_l, sc_l, lo_s, sc_s, sea_level, idx):
    mid_l = np.float32((n_land - 1) / 2)
    mid_s = np.float32((n_sea - 1) / 2)
    top_l = np.float32(n_land - 1)
    top_s = np.float32(n_sea - 1)
    off_s = np.int32(n_land)
    zero = np.float32(0.0)
    for j in range(zi.shape[0]):
        v = zi[j]
        sea = v < sea_level  # False without a sea (NaN)
        lo = lo_s if sea else lo_l
        sc = sc_s if sea else sc_l
        t = (rep[j] - lo) * sc
        t = (mid_s if sea else mid_l) if sc == zero else t
        t = np.rint(t)
        t = zero if t != t else t
        t = max(t, zero)
        t = min(t, top_s if sea else top_l)
        idx[j] = np.int32(t) + (off_s if sea else np.int32(0))


@njit(cache=True, inline="always")
def _byte32(x):
    """:func:`_to_byte` as a 32-bit word: the same value, but converted through int32, which
    vectorises (a float-to-uint8 conversion does not: 4x slower)."""
    x = min(max(x, np.float32(0.0)), np.float32(1.0))
    return np.uint32(np.int32(np.rint(x * np.float32(255.0))))


@njit(cache=True, nogil=True, _nrt=False)
def _gather_row(idx, rgb, cr, cg, cb):
    """The colours of table rows ``idx`` (a loop of its own: a gather keeps the loop it is
    in from vectorising, about 7x slower)."""
    red, green, blue = rgb[0], rgb[1], rgb[2]
    for j in range(idx.shape[0]):
        k = idx[j]
        cr[j] = red[k]
        cg[j] = green[k]
        cb[j] = blue[k]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _light_row(zi, cr, cg, cb, relief, sh, flat, lit, sky, ink, ink_rgb, o):
    """The pixels of one row of colours as words ``r | g << 8 | b << 16 | 255 << 24`` (0 at
    NaN heights)."""
    third = np.float32(1.0 / 3.0)
    one = np.float32(1.0)
    zero = np.float32(0.0)
    half = np.float32(0.5)
    r_ink, g_ink, b_ink = ink_rgb[0], ink_rgb[1], ink_rgb[2]
    for j in range(zi.shape[0]):
        r = cr[j]
        g = cg[j]
        b = cb[j]
        if relief:
            d = sh[j] / flat
            d *= lit[j]
            light = third * sky[j] + (one - third) * d
            light = one if light != light else light
            m = min(light, one)
            up = half * min(max(light - one, zero), one)
            r = r * m + (one - r) * up
            g = g * m + (one - g) * up
            b = b * m + (one - b) * up
        c = ink[j]
        r = r * (one - c) + r_ink * c
        g = g * (one - c) + g_ink * c
        b = b * (one - c) + b_ink * c
        word = (
            _byte32(r)
            | (_byte32(g) << np.uint32(8))
            | (_byte32(b) << np.uint32(16))
            | np.uint32(0xFF000000)
        )
        v = zi[j]
        o[j] = word if v == v else np.uint32(0)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _map_rows_fast(
    i0, i1, z, bands, mode, base, q, levels, mids, n_land, n_sea, tab, rgb, relief, sh, flat,
    lit, sky, ink, ink_rgb, ones, zeros, out32, idx, cr, cg, cb,
):  # fmt: skip
    """Rows ``i0 .. i1`` of :func:`map_image_fast` (one band of :func:`.run_bands`)."""
    use_lit = lit.shape[0] > 0
    use_sky = sky.shape[0] > 0
    use_ink = ink.shape[0] > 0
    for i in range(i0, i1):
        zi = z[i]
        if bands:
            _index_row(zi, mode, base, q, levels, mids, n_land, n_sea, tab, cr, idx)
        else:
            for j in range(zi.shape[0]):
                idx[j] = 0
        _gather_row(idx, rgb, cr, cg, cb)
        _light_row(
            zi, cr, cg, cb, relief, sh[i] if relief else ones, flat, lit[i] if use_lit else ones,
            sky[i] if use_sky else ones, ink[i] if use_ink else zeros, ink_rgb, out32[i],
        )  # fmt: skip
