"""Numba kernels of :mod:`sciviz_gbuf.styles.fused`: every style, edges, bands and contours in
one pass per pixel."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands


def compose_kernel(
    mode,
    normal,
    mask,
    light,
    consts_gooch,
    toon_table,
    toon_bg,
    hatch_sc,
    hatch_spacing,
    hatch_tau,
    hatch_left,
    hatch_ink,
    halo_core,
    shade_c,
    layer,
    emap,
    inner_c,
    prof_c,
    tint,
    ink,
    ink_c,
    out,
):
    """One pass per pixel: the style's base colour from ``N.L`` (``mode``, see ``FUSED_MODES``),
    then the edge map (``emap``, empty: none), the band ``tint`` and contour ``ink`` (empty:
    none), to uint8 ``out``. ``layer``: the lines style's ink or hatch's profile ink (hatch:
    strokes give way to paper within one pixel of it, as ``profile_halo``)."""
    run_bands(
        _compose_rows, mask.shape[0], mode, normal, mask, light, consts_gooch, toon_table,
        toon_bg, hatch_sc, hatch_spacing, hatch_tau, hatch_left, hatch_ink, halo_core, shade_c,
        layer, emap, inner_c, prof_c, tint, ink, ink_c, out,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _compose_rows(
    i0,
    i1,
    mode,
    normal,
    mask,
    light,
    consts_gooch,
    toon_table,
    toon_bg,
    hatch_sc,
    hatch_spacing,
    hatch_tau,
    hatch_left,
    hatch_ink,
    halo_core,
    shade_c,
    layer,
    emap,
    inner_c,
    prof_c,
    tint,
    ink,
    ink_c,
    out,
):
    """Rows ``i0 .. i1`` of :func:`compose_kernel` (one band of :func:`.run_bands`; the
    profile halo reads ``layer`` rows beyond the band: an input, not written here)."""
    h, w = mask.shape
    lx, ly, lz = light[0], light[1], light[2]
    use_emap = emap.shape[0] > 0
    use_tint = tint.shape[0] > 0
    use_ink = ink.shape[0] > 0
    one = np.float32(1.0)
    zero = np.float32(0.0)
    n_tex = toon_table.shape[0]
    n_fam = hatch_sc.shape[1]
    for i in range(i0, i1):
        for j in range(w):
            r = g = b = one
            if mode == 4:  # lines: ink on paper
                r = g = b = one - layer[i, j]
            elif mask[i, j]:
                nx, ny, nz = normal[i, j, 0], normal[i, j, 1], normal[i, j, 2]
                d = nx * lx + ny * ly + nz * lz
                if mode == 0:  # Lambert shade below white (shade_image); NaN normal: paper
                    if d == d:
                        s = max(d, zero)
                        v = shade_c[1] * (shade_c[0] + (one - shade_c[0]) * s)
                        r = g = b = min(max(v, zero), one)
                elif mode == 1:  # gooch: cool to warm over t = (1 + N.L) / 2
                    if d != d:
                        d = zero
                    t = (one + min(max(d, -one), one)) * np.float32(0.5)
                    r = min(max(t * consts_gooch[1, 0] + (one - t) * consts_gooch[0, 0], zero), one)
                    g = min(max(t * consts_gooch[1, 1] + (one - t) * consts_gooch[0, 1], zero), one)
                    b = min(max(t * consts_gooch[1, 2] + (one - t) * consts_gooch[0, 2], zero), one)
                elif mode == 2:  # toon: nearest texel of max(N.L, 0)
                    if d != d:
                        d = zero
                    s = max(min(d, one), zero)
                    k = min(int(s * np.float32(n_tex)), n_tex - 1)
                    r, g, b = toon_table[k, 0], toon_table[k, 1], toon_table[k, 2]
                else:  # hatch: prioritised stroke families covering the tone 1 - shade
                    tone = zero
                    if d == d:
                        tone = one - min(max(d, zero), one)
                    left = one
                    y = np.float64(h - 1 - i)
                    x = np.float64(j)
                    for f in range(n_fam):
                        top = min(tone, hatch_tau[f + 1])
                        cov = one - (one - hatch_ink * top) / hatch_left[f]
                        cov = min(max(cov, zero), one)
                        c = (-x * hatch_sc[0, f] + y * hatch_sc[1, f]) / hatch_spacing
                        dist = np.float32(abs((c - np.rint(c)) * hatch_spacing))
                        wd = max(cov * np.float32(hatch_spacing), zero)
                        a = max((wd + one) * np.float32(0.5), one)
                        left *= one - min(wd, one) * min(max(a - dist, zero), one)
                    # the profile halo: no strokes within one pixel of a profile
                    halo = zero
                    if layer[i, j] < halo_core:
                        for di in range(max(i - 1, 0), min(i + 2, h)):
                            for dj in range(max(j - 1, 0), min(j + 2, w)):
                                halo = max(halo, layer[di, dj])
                    r = g = b = one - (one - left) * (one - halo)
            elif mode == 1:
                r, g, b = consts_gooch[2, 0], consts_gooch[2, 1], consts_gooch[2, 2]
            elif mode == 2:
                r, g, b = toon_bg[0], toon_bg[1], toon_bg[2]
            if mode == 3:
                p = one - layer[i, j]
                r, g, b = r * p, g * p, b * p
            if use_emap:
                e = emap[i, j, 0]
                if e == e:
                    e = min(max(e, zero), one)
                    r += (inner_c[0] - r) * e
                    g += (inner_c[1] - g) * e
                    b += (inner_c[2] - b) * e
                e = emap[i, j, 3]
                if e == e:
                    e = min(max(e, zero), one)
                    r += (prof_c[0] - r) * e
                    g += (prof_c[1] - g) * e
                    b += (prof_c[2] - b) * e
            if use_tint and mask[i, j]:
                r, g, b = r * tint[i, j, 0], g * tint[i, j, 1], b * tint[i, j, 2]
            if use_ink:
                q = ink[i, j]
                r = r * (one - q) + ink_c[0] * q
                g = g * (one - q) + ink_c[1] * q
                b = b * (one - q) + ink_c[2] * q
            out[i, j, 0] = np.uint8(np.rint(min(max(r, zero), one) * np.float32(255.0)))
            out[i, j, 1] = np.uint8(np.rint(min(max(g, zero), one) * np.float32(255.0)))
            out[i, j, 2] = np.uint8(np.rint(min(max(b, zero), one) * np.float32(255.0)))


def rgb_on_paper(rgba, out):
    """``out``: the RGB of ``rgba``, white where it is fully transparent."""
    run_bands(_paper_rows, out.shape[0], rgba, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _paper_rows(i0, i1, rgba, out):
    """Rows ``i0 .. i1`` of :func:`rgb_on_paper`."""
    w = out.shape[1]
    for i in range(i0, i1):
        for j in range(w):
            clear = rgba[i, j, 3] == 0
            for c in range(3):
                out[i, j, c] = 255 if clear else rgba[i, j, c]
