"""Numba kernels of the 3x3 discontinuity operators (1990 Eq. 1-4, 9; 2003 §4.1.2).

Border rule, shared by every kernel here: a neighbour that is outside the image, masked, or not
finite takes the value of the centre pixel X. A coverage border therefore produces no response
from these operators by itself (it neither creates nor hides an edge); the profile of an object
against the background is drawn from the mask by :mod:`.edges`. Masked / non-finite centre
pixels get the operator's neutral value.

Rows run in parallel. Inside a row the interior columns take a branch-free path (selects only)
that LLVM vectorises; the two border columns take the same code with their flags set. Each
operator is compiled twice, with and without a mask, so the unmasked case reads no mask bytes.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["STENCILS", "diag_normal", "run"]


@njit(inline="always", cache=True)
def _sobel(x, a, b, c, d, e, f, g, h, k, aux):
    return (abs(a + 2 * b + c - f - 2 * g - h) + abs(c + 2 * e + h - a - 2 * d - f)) * np.float32(
        0.125
    )


@njit(inline="always", cache=True)
def _second(x, a, b, c, d, e, f, g, h, k, aux):
    return (8 * x - a - b - c - d - e - f - g - h) * np.float32(1.0 / 3.0)


@njit(inline="always", cache=True)
def _c1(x, a, b, c, d, e, f, g, h, k, aux):
    return (
        abs(a - x)
        + 2 * abs(b - x)
        + abs(c - x)
        + 2 * abs(d - x)
        + 2 * abs(e - x)
        + abs(f - x)
        + 2 * abs(g - x)
        + abs(h - x)
    ) * np.float32(0.125)


@njit(inline="always", cache=True)
def _diag_depth(x, a, b, c, d, e, f, g, h, k, aux):
    s = 1 - np.float32(0.5) * min(abs(a - h), np.float32(2))
    t = 1 - np.float32(0.5) * min(abs(c - f), np.float32(2))
    return s * s * t * t


@njit(inline="always", cache=True)
def _normalize(x, a, b, c, d, e, f, g, h, k, aux):
    # Eq. 3 on a gradient image: (g - g_min) / max(g_max - g_min, k_g).
    lo = min(x, a, b, c, d, e, f, g, h)
    hi = max(x, a, b, c, d, e, f, g, h)
    return (x - lo) / max(hi - lo, k)


@njit(inline="always", cache=True)
def _suppress(x, a, b, c, d, e, f, g, h, k, aux):
    # Eq. 4: x, a..h are the gradient g around the pixel, aux its second-order value l.
    t = max(x, a, b, c, d, e, f, g, h) / k
    return aux / max(np.float32(1), t * t)


def _make(op, neutral, masked: bool):
    neutral = np.float32(neutral)

    @njit(inline="always", cache=True)
    def pick(v, mv, inside, x):
        ok = (v - v == 0) & inside  # finite and in the image
        if masked:
            ok = ok & mv
        return v if ok else x

    @njit(inline="always", cache=True)
    def pixel(rows, masks, up, dn, c, cl, cr, lf, rt, k, aux, out):
        u, mid, lo = rows
        mu, mm, ml = masks
        x = mid[c]
        ax = aux[c]
        okx = (x - x == 0) & (ax - ax == 0)
        if masked:
            okx = okx & mm[c]
        a = pick(u[cl], mu[cl], up & lf, x)
        b = pick(u[c], mu[c], up, x)
        cc = pick(u[cr], mu[cr], up & rt, x)
        d = pick(mid[cl], mm[cl], lf, x)
        e = pick(mid[cr], mm[cr], rt, x)
        f = pick(lo[cl], ml[cl], dn & lf, x)
        g = pick(lo[c], ml[c], dn, x)
        hh = pick(lo[cr], ml[cr], dn & rt, x)
        v = op(x, a, b, cc, d, e, f, g, hh, k, ax)
        out[c] = v if okx else neutral

    @njit(parallel=True, cache=True)
    def kernel(img, m, k, aux, out):
        h, w = img.shape
        for r in prange(h):
            r = np.int64(r)
            up = r > 0
            dn = r < h - 1
            ru = r - 1 if up else r
            rd = r + 1 if dn else r
            rows = (img[ru], img[r], img[rd])
            masks = (m[ru], m[r], m[rd]) if masked else (m[0], m[0], m[0])
            xr = aux[r] if aux.shape[0] > 1 else aux[0]
            o = out[r]
            pixel(rows, masks, up, dn, 0, 0, min(1, w - 1), False, w > 1, k, xr, o)
            for c in range(1, w - 1):
                pixel(rows, masks, up, dn, c, c - 1, c + 1, True, True, k, xr, o)
            if w > 1:
                pixel(rows, masks, up, dn, w - 1, w - 2, w - 1, True, False, k, xr, o)

    return kernel


# name -> (op, value at masked / non-finite centre pixels)
_OPS = {
    "sobel": (_sobel, 0.0),
    "second": (_second, 0.0),
    "c1": (_c1, 0.0),
    "diag_depth": (_diag_depth, 1.0),
    "normalize": (_normalize, 0.0),
    "suppress": (_suppress, 0.0),
}
STENCILS = {
    (name, masked): _make(op, neutral, masked)
    for name, (op, neutral) in _OPS.items()
    for masked in (False, True)
}


def run(name: str, image: np.ndarray, mask: np.ndarray | None, k: float = 1.0, aux=None):
    """Apply stencil ``name`` to a C-contiguous float32 image; returns a new float32 image."""
    h, w = image.shape
    out = np.empty((h, w), dtype=np.float32)
    m = mask if mask is not None else np.ones((1, w), dtype=np.bool_)
    if aux is None:
        aux = np.zeros((1, w), dtype=np.float32)
    STENCILS[name, mask is not None](image, m, np.float32(k), aux, out)
    return out


@njit(inline="always", cache=True)
def _nvalid(n, m, masked, r, c):
    x, y, z = n[r, c, 0], n[r, c, 1], n[r, c, 2]
    ok = (x - x == 0) & (y - y == 0) & (z - z == 0)
    if masked:
        ok = ok & m[r, c]
    return ok


@njit(inline="always", cache=True)
def _ndot(n, m, masked, r1, c1, in1, r2, c2, in2, r, c):
    """Dot product of the normals at two pixels; an invalid one takes the centre's normal."""
    if not (in1 and _nvalid(n, m, masked, r1, c1)):
        r1, c1 = r, c
    if not (in2 and _nvalid(n, m, masked, r2, c2)):
        r2, c2 = r, c
    return n[r1, c1, 0] * n[r2, c2, 0] + n[r1, c1, 1] * n[r2, c2, 1] + n[r1, c1, 2] * n[r2, c2, 2]


@njit(parallel=True, cache=True)
def diag_normal(n, m, masked, out):
    """2003 §4.1.2: ``I_N = (A.H + C.F) / 2`` over unit normals, clipped to [-1, 1]; 1 where the
    centre is masked."""
    h, w = n.shape[:2]
    for r in prange(h):
        r = np.int64(r)
        up, dn = r > 0, r < h - 1
        for c in range(w):
            if not _nvalid(n, m, masked, r, c):
                out[r, c] = 1.0
                continue
            lf, rt = c > 0, c < w - 1
            ah = _ndot(n, m, masked, r - 1, c - 1, up and lf, r + 1, c + 1, dn and rt, r, c)
            cf = _ndot(n, m, masked, r - 1, c + 1, up and rt, r + 1, c - 1, dn and lf, r, c)
            out[r, c] = min(1.0, max(-1.0, 0.5 * (ah + cf)))
