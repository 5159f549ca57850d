"""Numba kernels of the 3x3 discontinuity operators (1990 Eq. 1-4, 9; 2003 §4.1.2).

Border rule, shared by every kernel here: a neighbour that is outside the image, masked, or not
finite is replaced by the linear extrapolation ``2X - opposite neighbour`` (the opposite one
across X); when that one is missing too, an axis neighbour by the mean of the two diagonal ones
beside it and a diagonal neighbour by the plane through X and its two axis neighbours, and
only then by X itself; the min/max operators (Eq. 3, 4) use X.
A plane therefore gives the same response up to a coverage border as inside: the border neither
creates nor hides an edge; the profile of an object against the background is drawn from the
mask by :mod:`.edges`. Masked / non-finite centre pixels get the operator's neutral value.

Bands of rows run at the same time, one per thread (:func:`.run_bands`). Each row is copied
into buffers one column wider on each side, so its first and last column take the same path as
the others; a row whose neighbourhoods are all valid skips the border rule, the others take it
branch-free (selects only); LLVM vectorises both. Each operator has its own small kernel;
without a mask one all-True row stands in for it. First-compile time shaped this module
(``benchmarks/bench_cold_start.py``): the operator is inlined at two call sites only, and the
border rule's and the contour codes' small helpers are ordinary jitted functions that LLVM
inlines, not numba's (whose IR inlining was most of the cost).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands
from ._contour_kernels import MODULATE, NPRM, hatch_ink, levels_ink, regular_ink

__all__ = ["diag_normal", "run"]


# float32 constants keep the arithmetic in float32 (twice the SIMD width of float64).
_E = np.float32(0.125)
_Q = np.float32(0.25)
_H = np.float32(0.5)
_ONE = np.float32(1.0)
_TWO = np.float32(2.0)
_EIGHT_THIRDS = np.float32(8.0 / 3.0)
_FMAX = np.float32(np.finfo(np.float32).max)
_TINY = np.float32(1e-30)
# Quartic fit of sqrt(1 + r^2) / (1 + r / 2) on [0, 1] (see _grad).
_A0, _A1, _A2, _A3, _A4 = (
    np.float32(v) for v in (1.000022, -0.50084359, 0.75746694, -0.3989078, 0.08508414)
)


@njit(inline="always", cache=True)
def _sobel(x, a, b, c, d, e, f, g, h, k, aux, prm):
    # Scaled before summing: float32 values near the limit give inf at worst, never inf - inf.
    a, b, c, d, e, f, g, h = a * _E, b * _Q, c * _E, d * _Q, e * _Q, f * _E, g * _Q, h * _E
    return abs(a + b + c - f - g - h) + abs(c + e + h - a - d - f)


@njit(inline="always", cache=True)
def _second(x, a, b, c, d, e, f, g, h, k, aux, prm):
    s = a * _E + b * _E + c * _E + d * _E + e * _E + f * _E + g * _E + h * _E
    return (x - s) * _EIGHT_THIRDS


@njit(inline="always", cache=True)
def _c1(x, a, b, c, d, e, f, g, h, k, aux, prm):
    # float32 weights: an int 2 would promote the whole sum to float64 (half the SIMD width).
    return (
        abs(a - x)
        + _TWO * abs(b - x)
        + abs(c - x)
        + _TWO * abs(d - x)
        + _TWO * abs(e - x)
        + abs(f - x)
        + _TWO * abs(g - x)
        + abs(h - x)
    ) * _E


@njit(inline="always", cache=True)
def _diag_depth(x, a, b, c, d, e, f, g, h, k, aux, prm):
    s = _ONE - _H * min(abs(a - h), _TWO)
    t = _ONE - _H * min(abs(c - f), _TWO)
    return s * s * t * t


@njit(inline="always", cache=True)
def _normalize(x, a, b, c, d, e, f, g, h, k, aux, prm):
    # Eq. 3 on a gradient image: (g - g_min) / max(g_max - g_min, k_g).
    lo = min(x, a, b, c, d, e, f, g, h)
    hi = max(x, a, b, c, d, e, f, g, h)
    return (x * _H - lo * _H) / max(hi * _H - lo * _H, k * _H)


@njit(inline="always", cache=True)
def _suppress(x, a, b, c, d, e, f, g, h, k, aux, prm):
    # Eq. 4: x, a..h are the gradient g around the pixel, aux its second-order value l.
    t = max(x, a, b, c, d, e, f, g, h) / k
    return aux / max(_ONE, t * t)


# The contour kernels may fuse a * b + c into one FMA ("contract": no change to NaN/inf
# handling, ~15% faster); the others keep the strict order their tests compare against.

# Operator codes: they pick the border rule and the neutral value; the operator itself is
# passed to the row loop as a function, so each kernel compiles only its own operator.
SOBEL, SECOND, C1, DIAG_DEPTH, NORMALIZE, SUPPRESS, CONTOUR, LEVELS, HATCH = range(9)


@njit(inline="always", cache=True)
def _grad(x, a, b, c, d, e, f, g, h, k, aux, prm):
    """The gradient magnitude of the contour codes (the caller's own, k > 0, comes in aux).

    Eq. 9 is kept for its robustness at ridges and kinks, where central differences vanish,
    but on a plane it reads ``|grad| (cos + sin / 2)`` of the angle to the nearer axis, up to
    12% high near 27 degrees (lines that much wider). It is divided by that factor, with the
    direction from Sobel sums: ``sqrt(1 + r^2) / (1 + r / 2)`` of their ratio ``r <= 1``, as a
    quartic (error 2e-5), so it is exact on planes in every direction.
    """
    gx = abs((c - a) + _TWO * (e - d) + (h - f))
    gy = abs((f - a) + _TWO * (g - b) + (h - c))
    r = min(gx, gy) / max(gx, gy, _TINY)
    iso = _A0 + r * (_A1 + r * (_A2 + r * (_A3 + r * _A4)))
    return _c1(x, a, b, c, d, e, f, g, h, k, aux, prm) * iso


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _range(x, a, b, c, d, e, f, g, h):
    """Smallest and largest value of the 3x3 neighbourhood (after the border rule)."""
    lo = min(min(min(a, b), min(c, d)), min(min(e, f), min(g, min(h, x))))
    hi = max(max(max(a, b), max(c, d)), max(max(e, f), max(g, max(h, x))))
    return lo, hi


@njit(inline="always", cache=True)
def _contour(x, a, b, c, d, e, f, g, h, k, aux, prm):
    lo, hi = _range(x, a, b, c, d, e, f, g, h)
    own = _grad(x, a, b, c, d, e, f, g, h, k, aux, prm)
    return regular_ink(x, aux if k > 0 else own, lo, hi, own, prm)


@njit(inline="always", cache=True)
def _levels(x, a, b, c, d, e, f, g, h, k, aux, prm):
    lo, hi = _range(x, a, b, c, d, e, f, g, h)
    own = _grad(x, a, b, c, d, e, f, g, h, k, aux, prm)
    return levels_ink(x, aux if k > 0 else own, lo, hi, own, prm)


@njit(inline="always", cache=True)
def _hatch(x, a, b, c, d, e, f, g, h, k, aux, prm):
    """Curved hatching (Eq. 17-21) with the caller's gradient in ``aux`` if ``k > 0``; with
    ``prm[MODULATE]`` set, ``aux`` is a modulation instead (``contours.modulated_hatching``):
    the lines at two widths from one gradient (the thin line's parameters at ``prm[NPRM:]``),
    blended by it. One kernel for both: each kernel costs tens of seconds to compile."""
    modulated = prm[MODULATE] > 0
    own = _grad(x, a, b, c, d, e, f, g, h, k, aux, prm)
    full = hatch_ink(x, aux if (k > 0) & (not modulated) else own, prm)
    if not modulated:
        return full
    thin = hatch_ink(x, own, prm[NPRM:])
    m = min(aux if aux > 0 else np.float32(0.0), _ONE)  # clipped to [0, 1], NaN -> 0
    if m >= _H:
        t = min(max(_TWO * m - _ONE, np.float32(0.0)), _ONE)
        return thin + t * (full - thin)
    return _TWO * m * thin


@njit(inline="always", cache=True)
def _ok(v, mv, inside):
    return (v - v == 0) & inside & mv  # finite, in the image and covered


# The border rule's helpers below are ordinary jitted functions, not inlined by numba: its
# IR inlining copied them into each of a kernel's call sites and was most of each kernel's
# first compile (sobel 15.6 -> 5.5 s, contour 37 -> 17 s); LLVM inlines them anyway, so the
# output bits are the same. (The operators stay inlined: called per pixel, they must be
# vectorised with the row loop.)
@njit(cache=True, error_model="numpy")
def _clamp(e):
    return min(max(e, -_FMAX), _FMAX)  # huge inputs: stay finite, never inf - inf


@njit(cache=True, error_model="numpy")
def _fill_axis(v, ok, opp, ok_opp, s1, ok1, s2, ok2, x, extrapolate):
    """An axis neighbour under the border rule: itself if valid; else the linear extrapolation
    ``2X - opposite``; else the mean of the two diagonal neighbours beside it (both on its
    side); else the centre value. The first two are exact on a plane."""
    if ok:
        return v
    if extrapolate and ok_opp:
        return _clamp(x + (x - opp))
    if extrapolate and ok1 and ok2:
        return _clamp(_H * s1 + _H * s2)
    return x


@njit(cache=True, error_model="numpy")
def _fill_diag(v, ok, opp, ok_opp, p, q, x, extrapolate):
    """A diagonal neighbour: itself if valid; else ``2X - opposite``; else the plane through X
    and its two axis neighbours ``p``, ``q`` (already under the border rule): ``p + q - X``."""
    if ok:
        return v
    if extrapolate and ok_opp:
        return _clamp(x + (x - opp))
    if extrapolate:
        return _clamp(p + q - x)
    return x


@njit(inline="always", cache=True)
def _pixel(code, op, neutral, u, mid, lo, mu, mm, ml, up, dn, c, k, aux, prm, out, co):
    """Pixel ``co`` of a row under the border rule: ``u``, ``mid``, ``lo`` (and their masks)
    are the padded rows, where it is column ``c``; ``aux`` and ``out`` are not padded."""
    cl, cr = c - 1, c + 1
    x = mid[c]
    okx = (x - x == 0) & mm[c]
    ax = x
    if code == SUPPRESS:
        ax = aux[co]
        okx = okx & (ax - ax == 0)
    elif code >= CONTOUR:
        ax = aux[co]
    # Min/max (Eq. 3, 4) take the neighbourhood as it is; differentials extrapolate.
    ext = code != NORMALIZE and code != SUPPRESS
    a0, b0, c0, d0 = u[cl], u[c], u[cr], mid[cl]
    e0, f0, g0, h0 = mid[cr], lo[cl], lo[c], lo[cr]
    oka = _ok(a0, mu[cl], up)
    okb = _ok(b0, mu[c], up)
    okc = _ok(c0, mu[cr], up)
    okd = _ok(d0, mm[cl], True)
    oke = _ok(e0, mm[cr], True)
    okf = _ok(f0, ml[cl], dn)
    okg = _ok(g0, ml[c], dn)
    okh = _ok(h0, ml[cr], dn)
    # Layout: a b c / d x e / f g h. Axis neighbours first, then diagonals from them, so
    # that a neighbour missing together with its opposite one (a corner of a hole, or of the
    # image next to a hole) still continues the plane.
    b = _fill_axis(b0, okb, g0, okg, a0, oka, c0, okc, x, ext)
    d = _fill_axis(d0, okd, e0, oke, a0, oka, f0, okf, x, ext)
    e = _fill_axis(e0, oke, d0, okd, c0, okc, h0, okh, x, ext)
    g = _fill_axis(g0, okg, b0, okb, f0, okf, h0, okh, x, ext)
    a = _fill_diag(a0, oka, h0, okh, b, d, x, ext)
    cc = _fill_diag(c0, okc, f0, okf, b, e, x, ext)
    f = _fill_diag(f0, okf, c0, okc, d, g, x, ext)
    hh = _fill_diag(h0, okh, a0, oka, e, g, x, ext)
    v = op(x, a, b, cc, d, e, f, g, hh, k, ax, prm)
    out[co] = v if okx else neutral


@njit(cache=True, error_model="numpy")
def _rows_valid(with_aux, u, mid, lo, mu, mm, ml, xr, masked):
    """True if three rows (and the aux row ``xr`` if ``with_aux``: Eq. 4) are finite and
    covered throughout.

    Checked in blocks, so a row that meets the background early (most rows of a G-buffer)
    costs one block, not a scan of the whole row."""
    w = mid.shape[0]
    for c0 in range(0, w, _BLOCK):
        c1 = min(c0 + _BLOCK, w)
        bad = False
        if masked:
            for c in range(c0, c1):
                bad |= not (mu[c] & mm[c] & ml[c])
        for c in range(c0, c1):
            bad |= not ((u[c] - u[c] == 0) & (mid[c] - mid[c] == 0) & (lo[c] - lo[c] == 0))
        if with_aux:
            for c in range(c0, c1):
                bad |= not (xr[c] - xr[c] == 0)
        if bad:
            return False
    return True


_BLOCK = 256


@njit(cache=True, error_model="numpy")
def _pad_row(src, out, fill):
    """``out[1:w + 1] = src``, ``out[0] = out[w + 1] = fill``."""
    w = src.shape[0]
    out[0] = fill
    out[w + 1] = fill
    for c in range(w):
        out[c + 1] = src[c]


@njit(cache=True, error_model="numpy")
def _edge_columns(u, mid, lo, pu, pm, pl, ext):
    """The outer columns of the padded rows of a row whose pixels are all valid: each holds,
    for the image column next to it, the border rule's value of that missing neighbour (the
    linear extrapolation ``2X - opposite``; X itself for the min/max operators)."""
    w = mid.shape[0]
    x0, x1 = mid[0], mid[w - 1]
    if ext:
        pu[0] = _clamp(x0 + (x0 - lo[1]))
        pm[0] = _clamp(x0 + (x0 - mid[1]))
        pl[0] = _clamp(x0 + (x0 - u[1]))
        pu[w + 1] = _clamp(x1 + (x1 - lo[w - 2]))
        pm[w + 1] = _clamp(x1 + (x1 - mid[w - 2]))
        pl[w + 1] = _clamp(x1 + (x1 - u[w - 2]))
    else:
        pu[0] = pm[0] = pl[0] = x0
        pu[w + 1] = pm[w + 1] = pl[w + 1] = x1


@njit(inline="always", cache=True)
def _rows(code, op, r0, r1, img, m, k, aux, prm, out, fs, bs):
    """Apply operator ``op`` (of kind ``code``) to every pixel of rows ``r0 .. r1`` (one band
    of :func:`.run_bands`); ``m`` is the (H, W) mask or one all-True row; ``prm`` holds the
    parameters of the contour codes; ``fs`` (3, W + 2) float32 and ``bs`` (3, W + 2) bool are
    the band's scratch rows.

    Inlined into one small kernel per operator with ``code`` a constant and ``op`` a known
    function, so LLVM folds the switches away and vectorises the column loops. The three rows
    are copied into buffers one column wider on each side, so that the image's first and last
    column take the same path as the others: the operator is inlined at two call sites (each
    one more copy to compile; three of them were most of a first run's compile time). A row
    whose neighbourhoods are all valid skips the border rule, its outer columns holding what
    the rule gives there (:func:`_edge_columns`); any other row takes it, with uncovered
    outer columns.
    """
    h, w = img.shape
    neutral = np.float32(1.0) if code == DIAG_DEPTH else np.float32(0.0)
    masked = m.shape[0] > 1
    ext = code != NORMALIZE and code != SUPPRESS
    # A typed flag, not the literal: one compiled _rows_valid serves every kernel.
    with_aux = np.bool_(code == SUPPRESS)
    zero = np.float32(0.0)
    # Scratch rows, one set per band (a band is one thread); every row rewrites all of them.
    pu, pm, pl = fs[0], fs[1], fs[2]
    qu, qm, ql = bs[0], bs[1], bs[2]
    for r in range(r0, r1):
        up = r > 0
        dn = r < h - 1
        ru = r - 1 if up else r
        rd = r + 1 if dn else r
        u, mid, lo = img[ru], img[r], img[rd]
        if masked:
            mu, mm, ml = m[ru], m[r], m[rd]
        else:
            mu, mm, ml = m[0], m[0], m[0]
        xr = aux[r] if aux.shape[0] > 1 else aux[0]
        o = out[r]
        _pad_row(u, pu, zero)
        _pad_row(mid, pm, zero)
        _pad_row(lo, pl, zero)
        if (w >= 2) & up & dn & _rows_valid(with_aux, u, mid, lo, mu, mm, ml, xr, masked):
            # Every neighbour is valid: the border rule is the identity, so skip it.
            _edge_columns(u, mid, lo, pu, pm, pl, ext)
            for c in range(1, w + 1):
                ax = xr[c - 1] if code >= SUPPRESS else pm[c]
                o[c - 1] = op(
                    pm[c], pu[c - 1], pu[c], pu[c + 1], pm[c - 1], pm[c + 1], pl[c - 1], pl[c],
                    pl[c + 1], k, ax, prm,
                )  # fmt: skip
            continue
        _pad_row(mu, qu, False)  # a (1, W) mask is that row's own (an image one row high)
        _pad_row(mm, qm, False)
        _pad_row(ml, ql, False)
        for c in range(1, w + 1):
            _pixel(code, op, neutral, pu, pm, pl, qu, qm, ql, up, dn, c, k, xr, prm, o, c - 1)


# error_model="numpy" in the band kernels, as numba compiled the prange loop bodies they
# replace: a division by zero gives inf / NaN, it does not raise.
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _k_sobel(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(SOBEL, _sobel, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _k_second(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(SECOND, _second, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _k_c1(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(C1, _c1, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _k_diag_depth(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(DIAG_DEPTH, _diag_depth, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _k_normalize(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(NORMALIZE, _normalize, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _k_suppress(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(SUPPRESS, _suppress, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy", fastmath={"contract"})
def _k_contour(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(CONTOUR, _contour, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy", fastmath={"contract"})
def _k_levels(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(LEVELS, _levels, r0, r1, img, m, k, aux, prm, out, fs, bs)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy", fastmath={"contract"})
def _k_hatch(r0, r1, img, m, k, aux, prm, out, fs, bs):
    _rows(HATCH, _hatch, r0, r1, img, m, k, aux, prm, out, fs, bs)


_KERNELS = {
    "sobel": _k_sobel,
    "second": _k_second,
    "c1": _k_c1,
    "diag_depth": _k_diag_depth,
    "normalize": _k_normalize,
    "suppress": _k_suppress,
    "contour": _k_contour,
    "levels": _k_levels,
    "hatch": _k_hatch,
}


def run(
    name: str,
    image: np.ndarray,
    mask: np.ndarray | None,
    k: float = 1.0,
    aux: np.ndarray | None = None,
    prm: np.ndarray | None = None,
) -> np.ndarray:
    """Apply stencil ``name`` to a C-contiguous float32 image; returns a new float32 image.

    ``aux`` is a second (H, W) float32 image (Eq. 4's ``l``; a contour code's own gradient,
    used when ``k > 0``) and ``prm`` the float32 parameters of the contour codes."""
    h, w = image.shape
    out = np.empty((h, w), dtype=np.float32)
    m = mask if mask is not None else np.ones((1, w), dtype=np.bool_)
    if aux is None:
        aux = np.zeros((1, w), dtype=np.float32)
    if prm is None:
        prm = np.zeros(1, dtype=np.float32)
    run_bands(
        _KERNELS[name], h, image, m, np.float32(k), aux, prm, out,
        scratch=lambda: (np.empty((3, w + 2), np.float32), np.empty((3, w + 2), np.bool_)),
    )  # fmt: skip
    return out


@njit(inline="always", cache=True)
def _nrow_ok(n, m, c):
    x, y, z = n[c, 0], n[c, 1], n[c, 2]
    return (x - x == 0) & (y - y == 0) & (z - z == 0) & m[c]


@njit(inline="always", cache=True)
def _ndot_pair(u, mu, cu, lo, ml, cl, inside_u, inside_l, x0, x1, x2):
    """Dot of the normals u[cu] and lo[cl]; an invalid one takes the centre's (x0, x1, x2)."""
    oku = inside_u and _nrow_ok(u, mu, cu)
    okl = inside_l and _nrow_ok(lo, ml, cl)
    a0 = u[cu, 0] if oku else x0
    a1 = u[cu, 1] if oku else x1
    a2 = u[cu, 2] if oku else x2
    b0 = lo[cl, 0] if okl else x0
    b1 = lo[cl, 1] if okl else x1
    b2 = lo[cl, 2] if okl else x2
    return a0 * b0 + a1 * b1 + a2 * b2


def diag_normal(n, m, out):
    """2003 §4.1.2: ``I_N = (A.H + C.F) / 2`` over unit normals, clipped to [-1, 1]; 1 where the
    centre is masked. ``m`` is the (H, W) mask or one all-True row."""
    run_bands(_diag_normal_rows, n.shape[0], n, m, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _diag_normal_rows(r0, r1, n, m, out):
    """Rows ``r0 .. r1`` of :func:`diag_normal` (one band of :func:`.run_bands`)."""
    h, w = n.shape[:2]
    for r in range(r0, r1):
        up, dn = r > 0, r < h - 1
        u, mid, lo = n[r - 1 if up else r], n[r], n[r + 1 if dn else r]
        if m.shape[0] > 1:
            mu, mm, ml = m[r - 1 if up else r], m[r], m[r + 1 if dn else r]
        else:
            mu, mm, ml = m[0], m[0], m[0]
        for c in range(w):
            x0, x1, x2 = mid[c, 0], mid[c, 1], mid[c, 2]
            lf, rt = c > 0, c < w - 1
            cl = c - 1 if lf else c
            cr = c + 1 if rt else c
            ah = _ndot_pair(u, mu, cl, lo, ml, cr, up and lf, dn and rt, x0, x1, x2)
            cf = _ndot_pair(u, mu, cr, lo, ml, cl, up and rt, dn and lf, x0, x1, x2)
            v = min(np.float32(1.0), max(np.float32(-1.0), np.float32(0.5) * (ah + cf)))
            out[r, c] = v if _nrow_ok(mid, mm, c) else np.float32(1.0)
