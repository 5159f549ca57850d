"""Per-pixel contour and hatching ink (1990 Eq. 7-8, 10-15, 17-21), inlined into the stencil
kernels of :mod:`._stencil` after the Eq. 9 gradient.

All parameters travel in one float32 vector ``prm`` (layout below) so that one cached kernel
serves every setting; they are loop-invariant, and the arithmetic is branch-free selects so the
row loop still vectorises. Levels of :func:`levels_ink` follow the fixed slots.

:func:`ring_opening` is the generalisation's removal of small rings and specks (an attribute
opening of the ink image, used by :mod:`._contour_generalize`).
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

# Slots of ``prm``. The line profile f1 at distance t (px) from a line's centre is
# ``cap * P(clip(a - b t, 0, 1))`` with ``P(v) = v (p1 + v (p2 + v p3))``; ``a`` and ``cap``
# come from ``contours._line_shape``.
BASE = 0  # p0 of Eq. 12 (hatching: the offset of the line family)
Q = 1  # interval q (hatching: p_d of Eq. 19)
LINE_A = 2  # a and cap of the (minor) lines
LINE_CAP = 3
LINE_B = 4  # b = 1 / filter width, shared
P1 = 5
P2 = 6
P3 = 7
INV_GEPS = 8  # 1 / g_eps of Eq. 11 (huge when g_eps = 0)
C_SPARSE = 9
C_DENSE = 10
DENSE_AT = 11  # spacing (px) where the Eq. 15 blend starts (-huge: no dense handling)
INV_D = 12  # 1 / d
MAJOR_Q = 13  # interval of the major family (0: none)
MAJOR_A = 14
MAJOR_CAP = 15
SPACING = 16  # hatching: d_i of Eq. 18-20
SWITCH = 17  # hatching: spacing ratio where the in-between lines appear
INV_FADE = 18  # hatching: 1 / width of that transition
GAP = 19  # the interval, or the smallest gap between levels (generalisation; not in kernels)
MAJOR_WIDTH = 20  # width of the major lines (generalisation's default ring size; not in kernels)
MODULATE = 21  # hatching: 1 if aux is a modulation and prm[NPRM:] the thin line's (else 0)
NPRM = 22

_Z = np.float32(0.0)
_H = np.float32(0.5)
_ONE = np.float32(1.0)
_BIG = np.float32(1e30)
_TINY = np.float32(1e-30)


@intrinsic
def _bits(typingctx, x):
    """The bits of a float32 as an int32 (a bitcast, which vectorises, unlike frexp)."""
    if isinstance(x, types.Float) and x.bitwidth == 32:

        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], ir.IntType(32))

        return types.int32(x), codegen
    return None


@intrinsic
def _float(typingctx, i):
    """The float32 with the low 32 bits of an integer (numba widens int32 arithmetic)."""
    if isinstance(i, types.Integer):

        def codegen(context, builder, signature, args):
            v = args[0]
            if i.bitwidth > 32:
                v = builder.trunc(v, ir.IntType(32))
            return builder.bitcast(v, ir.FloatType())

        return types.float32(i), codegen
    return None


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _octave(y):
    """``(1 / m, 2^e)`` with ``y = m 2^e``, ``m`` in [0.5, 1), for ``y`` clamped to
    [1e-30, 1e30] (frexp from the float's exponent and mantissa bits)."""
    b = _bits(np.float32(min(max(y, _TINY), _BIG)))
    biased = (b >> 23) & 0xFF  # e + 126
    m = _float((b & 0x807FFFFF) | (126 << 23))
    return _ONE / m, _float((biased + 1) << 23)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _line(t, a, cap, prm):
    """f1: ink at distance ``t >= 0`` px from the centre of a line (Eq. 8, Fig. 4)."""
    v = min(max(a - t * prm[LINE_B], _Z), _ONE)
    return cap * v * (prm[P1] + v * (prm[P2] + v * prm[P3]))


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _spacing(q, g):
    # On-screen spacing q / g of lines q apart, finite even where g = 0.
    return q / max(g, q / _BIG)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _reached(p, lo, hi, ext):
    """1 if level ``p`` lies within the 3x3 neighbourhood's range ``(lo, hi]`` widened by
    ``ext``, else 0: a level the surface comes near but never crosses (a summit just below it)
    draws no line, however small ``|x - p| / g`` is. As in GDAL, a value equal to a level
    counts as above it: ground lying exactly at a level's height (a sea at 0 m) is not
    outlined by that level."""
    return _ONE if (p > lo - ext) & (p <= hi + ext) else _Z


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _reach(a, g, cover, prm):
    """How far beyond the neighbourhood's range a line of profile ``a`` inks, in field units:
    it inks up to ``a / b`` pixels (of ``g``) from the level, the range spans at least one
    pixel each way, ``cover`` (the field's own gradient; = ``g`` unless the caller gave one)."""
    return max(a / prm[LINE_B] * g - cover, _Z)


@njit(inline="always", cache=True)
def _family(x, g, q, a, cap, lo, hi, cover, prm):
    """Ink of the regular levels ``base + n q`` (Eq. 13-14): the nearest line and the one beyond
    it, so antialiased lines that nearly touch still add up; plus the spacing ``q / g``. Levels
    outside the neighbourhood's range (``lo``, ``hi``, see :func:`_reached`) draw nothing."""
    s = _spacing(q, g)
    r = (x - prm[BASE]) * (_ONE / q)  # loop-invariant reciprocal
    n0 = np.floor(r + _H)
    d = r - n0
    frac = abs(d)
    near = prm[BASE] + n0 * q
    far = near + (q if d >= _Z else -q)
    ext = _reach(a, g, cover, prm)
    c = _line(frac * s, a, cap, prm) * _reached(near, lo, hi, ext)
    c += _line((_ONE - frac) * s, a, cap, prm) * _reached(far, lo, hi, ext)
    return min(c, _ONE), s


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _flat(c, g, prm):
    """f_g of Eq. 11: fade to ``c_sparse`` below ``g_eps``."""
    ws = min(g * prm[INV_GEPS], _ONE)
    return ws * c + (_ONE - ws) * prm[C_SPARSE]


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _flat_dense(c, g, s, prm):
    """f_g of Eq. 11 and 15: fade to ``c_sparse`` below ``g_eps``; where lines come closer than
    the dense spacing, fade to ``c_dense`` within one line width further."""
    c = _flat(c, g, prm)
    wd = min(max((s - prm[DENSE_AT]) * prm[INV_D] + _ONE, _Z), _ONE)
    return wd * c + (_ONE - wd) * prm[C_DENSE]


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _finite_ink(v):
    return min(max(v, _Z), _ONE) if v == v else _Z


@njit(inline="always", cache=True)
def regular_ink(x, g, lo, hi, cover, prm):
    """Regular contours (Eq. 10-15), with an optional major family that never thins out;
    ``lo``, ``hi``: the range of the 3x3 neighbourhood, ``cover``: the field's own gradient."""
    c, s = _family(x, g, prm[Q], prm[LINE_A], prm[LINE_CAP], lo, hi, cover, prm)
    v = _flat_dense(c, g, s, prm)
    qm = prm[MAJOR_Q]
    if qm > 0:
        cm, _ = _family(x, g, qm, prm[MAJOR_A], prm[MAJOR_CAP], lo, hi, cover, prm)
        v = max(v, _flat(cm, g, prm))
    return _finite_ink(v)


@njit(inline="always", cache=True)
def levels_ink(x, g, lo, hi, cover, prm):
    """Contours at the sorted levels ``prm[NPRM:]`` (Eq. 7 for the two levels around ``x``),
    each only if the 3x3 neighbourhood's range ``lo``, ``hi`` reaches it."""
    lv = prm[NPRM:]
    n = lv.shape[0]
    i0, i1 = 0, n
    while i0 < i1:  # first level > x
        mid = (i0 + i1) >> 1
        if lv[mid] <= x:
            i0 = mid + 1
        else:
            i1 = mid
    below = lv[i0 - 1] if i0 > 0 else -_BIG
    above = lv[i0] if i0 < n else _BIG
    a, cap = prm[LINE_A], prm[LINE_CAP]
    gg = max(g, _TINY)
    ext = _reach(a, g, cover, prm)
    c = _line((x - below) / gg, a, cap, prm) * _reached(below, lo, hi, ext)
    c += _line((above - x) / gg, a, cap, prm) * _reached(above, lo, hi, ext)
    s = _spacing(above - below, g) if (i0 > 0) & (i0 < n) else _BIG
    return _finite_ink(_flat_dense(min(c, _ONE), g, s, prm))


@njit(inline="always", cache=True)
def hatch_ink(x, g, prm):
    """Curved hatching by binary thinning out (Eq. 17-21).

    The interval ``p_n = 2^n p_d`` is chosen per pixel so that its lines lie ``d_i`` to ``2 d_i``
    pixels apart; the lines halfway between them fade in as that spacing grows past
    ``SWITCH * d_i``, so the spacing stays near ``d_i`` whatever the gradient.
    """
    di = prm[SPACING]
    # Eq. 19-20: with d_i g / p_d = m 2^n, m in [0.5, 1), p_n = 2^n p_d lies (1/m) d_i apart.
    ratio, two_n = _octave(di * g / prm[Q])
    s = di * ratio  # on-screen spacing of the p_n lines
    pn = prm[Q] * two_n
    r = (x - prm[BASE]) / pn
    frac = abs(r - np.floor(r + _H))
    a, cap = prm[LINE_A], prm[LINE_CAP]
    w = min(max((ratio - prm[SWITCH]) * prm[INV_FADE] + _H, _Z), _ONE)
    c = _line(frac * s, a, cap, prm) + _line((_ONE - frac) * s, a, cap, prm)
    c += w * _line(abs(_H - frac) * s, a, cap, prm)
    ok = (g > 0) & (g - g == 0)  # no gradient, no direction for the lines
    return _finite_ink(c) if ok else _Z


# ------------------------------------------------------------------ small rings and specks


@njit(inline="always", cache=True)
def _root(par, x):
    """Union-find root of node ``x``, halving the path on the way."""
    while par[x] != x:
        par[x] = par[par[x]]
        x = par[x]
    return x


@njit(cache=True, nogil=True, _nrt=False)
def ink_order(bits, node, order, tmp, hist):
    """The inked pixels (``bits``: the float32 ink's bit patterns; inked: ink > 0) by
    decreasing ink, ties in raster order, into ``order`` (flat indices); ``node`` (flat,
    int32) their rank, -1 where not inked. Returns their number. A four-pass LSD radix sort
    on the bytes of ``~bits`` (positive float32 patterns order as their values), stable:
    the order of ``argsort(-ink, kind="stable")`` in linear time. ``tmp``: int32 working
    array as long as ``order``; ``hist``: int64 (4, 257). Bytes, not two 16-bit digits: the
    counts then stay in the first-level cache (two 65537-entry tables, zeroed and summed for
    every tile, were a fifth of a ring-opening tile's time)."""
    n = bits.shape[0]
    for d in range(4):
        for k in range(257):
            hist[d, k] = 0
    m = 0
    for p in range(n):
        b = bits[p]
        if b == 0 or b > np.uint32(0x7F800000):  # 0, negative or NaN: not inked
            node[p] = -1
            continue
        key = np.uint32(0xFFFFFFFF) - b
        for d in range(4):
            hist[d, ((key >> np.uint32(8 * d)) & np.uint32(0xFF)) + 1] += 1
        m += 1
    for d in range(4):
        for k in range(256):
            hist[d, k + 1] += hist[d, k]
    for p in range(n):  # by the lowest byte, raster order within a byte
        b = bits[p]
        if b == 0 or b > np.uint32(0x7F800000):
            continue
        lo = (np.uint32(0xFFFFFFFF) - b) & np.uint32(0xFF)
        order[hist[0, lo]] = p
        hist[0, lo] += 1
    for d in range(1, 4):  # then by each higher byte, stable: order -> tmp -> order -> tmp
        src = order if d % 2 == 1 else tmp
        dst = tmp if d % 2 == 1 else order
        shift = np.uint32(8 * d)
        for k in range(m):
            p = src[k]
            digit = ((np.uint32(0xFFFFFFFF) - bits[p]) >> shift) & np.uint32(0xFF)
            dst[hist[d, digit]] = p
            hist[d, digit] += 1
    for k in range(m):  # the last pass ended in tmp
        order[k] = tmp[k]
        node[order[k]] = k
    return m


@njit(cache=True, nogil=True, _nrt=False)
def cut_rows(i0, i1, valid, cut):
    """Rows ``i0 .. i1`` of :func:`._contour_generalize.cut_cells`: True on the grid's edge
    and where a cell of the 3 x 3 around is not ``valid``."""
    h, w = valid.shape
    for i in range(i0, i1):
        o = cut[i]
        if i == 0 or i == h - 1:
            for j in range(w):
                o[j] = True
            continue
        a, b, c = valid[i - 1], valid[i], valid[i + 1]
        o[0] = True
        o[w - 1] = True
        for j in range(1, w - 1):
            o[j] = not (a[j - 1] & a[j] & a[j + 1] & b[j - 1] & b[j] & b[j + 1] & c[j - 1]
                        & c[j] & c[j + 1])  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def ring_opening(ink, node, order, cut, min_ring, min_stub, par, up, at, big, box, touch, level,
                 out, sid, size):  # fmt: skip
    """The attribute opening of ``ink`` by the size of its 8-connected components: each pixel
    keeps ``min(ink, T)`` for the highest ``T`` at which its component of ``ink >= T`` is
    large, 0 if none is (Vincent 1993's area opening, with the attribute of
    :func:`._contour_generalize.drop_small_rings`). Large: the longer side of the bounding box
    exceeds ``min_ring``, or exceeds ``min_stub`` for a component with a pixel in ``cut``.

    ``node``: (H, W) int32, -1 where ``ink`` is 0, else the pixel's rank in ``order`` (the
    flat indices of the inked pixels, by decreasing ink). Components grow as ``T`` falls
    (union-find, pixels added in that order); ``up`` keeps each merge's tree, so a pixel's
    level is that of the first set on its way up that was large, each merge bounded by the
    level it happened at. A set is named by the last pixel added to it (``sid`` of its
    union-find root), which the merge tree and the boxes use; the union-find itself links
    the smaller tree under the larger (``size``), so its paths stay short along long lines
    (the names, and so the opening, are those of linking under the newest pixel)."""
    h, w = ink.shape
    m = order.shape[0]
    # working arrays of the m inked pixels (numba's reference counting is off: the caller's):
    # par, up (the set a set merged into, -1: not merged), at (the level of that merge),
    # big (level where the set became large, -1), box (4, m) int32, touch, level, sid (a
    # root's set), size (a root's pixels); out (H, W)
    r0, r1, c0, c1 = box[0], box[1], box[2], box[3]
    for k in range(m):
        par[k] = k
        up[k] = -1
        at[k] = np.float32(0.0)
        big[k] = np.float32(-1.0)
        touch[k] = False
        sid[k] = k
        size[k] = 1
    for k in range(m):
        p = order[k]
        pr = p // w
        pc = p - pr * w
        v = ink[pr, pc]
        r0[k], r1[k], c0[k], c1[k] = pr, pr, pc, pc
        touch[k] = cut[pr, pc]
        rk = k  # the union-find root of k's set
        for rr in range(max(pr - 1, 0), min(pr + 2, h)):
            for cc in range(max(pc - 1, 0), min(pc + 2, w)):
                q = node[rr, cc]
                if q < 0 or q >= k:  # not inked, or not yet added (k itself included)
                    continue
                ra = _root(par, q)
                if ra == rk:
                    continue
                a = sid[ra]  # the set met, named by its last pixel
                up[a] = k
                at[a] = v
                r0[k] = min(r0[k], r0[a])
                r1[k] = max(r1[k], r1[a])
                c0[k] = min(c0[k], c0[a])
                c1[k] = max(c1[k], c1[a])
                touch[k] = touch[k] or touch[a]
                if size[ra] > size[rk]:
                    ra, rk = rk, ra
                par[ra] = rk
                size[rk] += size[ra]
                sid[rk] = k
        ext = max(r1[k] - r0[k] + 1, c1[k] - c0[k] + 1)
        if ext > min_ring or (touch[k] and ext > min_stub):
            big[k] = v
    # Levels from the last set added back to the first: a set's parent was added after it.
    for r in range(h):
        for c in range(w):
            out[r, c] = np.float32(0.0)
    for k in range(m - 1, -1, -1):
        if big[k] >= 0:
            lv = big[k]
        elif up[k] < 0:
            lv = np.float32(0.0)
        else:
            lv = min(at[k], level[up[k]])
        level[k] = lv
        p = order[k]
        pr = p // w
        out[pr, p - pr * w] = min(lv, ink[pr, p - pr * w])


# ------------------------------------------------------------ band islands (band_heights)
@njit(cache=True, error_model="numpy")
def _band_of(x, b0, step, edges):
    """The band of height ``x``: ``floor((x - b0) / step)`` (float32, as numpy computes it
    for a float32 grid), or with ``edges`` the count of edges <= ``x``."""
    if edges.shape[0] == 0:
        return np.int64(np.floor((x - b0) / step))
    lo = 0
    hi = edges.shape[0]
    while lo < hi:  # bisection: the first edge > x (searchsorted side="right")
        mid = (lo + hi) // 2
        if edges[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return np.int64(lo)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def band_runs(z, valid, b0, step, edges, store, rrow, rc0, rc1, rband, first):
    """The runs of a grid: maximal pieces of a row of valid cells of one band
    (:func:`_band_of`); counted, and with ``store`` written (row, first and last column,
    band; ``first[r]`` the first run of row ``r``, ``first[H]`` their number). Returns
    their number."""
    h, w = z.shape
    n = 0
    for r in range(h):
        if store:
            first[r] = n
        c = 0
        while c < w:
            if not valid[r, c]:
                c += 1
                continue
            b = _band_of(z[r, c], b0, step, edges)
            e = c + 1
            while e < w and valid[r, e] and _band_of(z[r, e], b0, step, edges) == b:
                e += 1
            if store:
                rrow[n] = r
                rc0[n] = c
                rc1[n] = e - 1
                rband[n] = b
            n += 1
            c = e
    if store:
        first[h] = n
    return n


@njit(cache=True, nogil=True, _nrt=False)
def small_islands(valid, rrow, rc0, rc1, rband, first, min_ring, small, par, box, touch):
    """Mark in ``small`` the band islands of :func:`._contour_generalize.band_heights`: the
    8-connected pieces of one band over the ``valid`` cells whose bounding box is at most
    ``min_ring`` px on its longer side and which touch neither the grid's edge nor a cell
    that is not valid (8-connected).

    Connected runs (Rosenfeld's run-length labelling) of :func:`band_runs`: each run joined
    to the runs of the row above that overlap it or touch it diagonally and have its band
    (union-find), then each piece's box and contact with the edge or nodata gathered over
    its runs. ``par`` (n,), ``box`` (4, n) int32 and ``touch`` (n,) bool: working arrays of
    the n runs."""
    h, w = valid.shape
    n = first[h]
    for k in range(n):
        par[k] = k
        box[0, k] = h
        box[1, k] = -1
        box[2, k] = w
        box[3, k] = -1
        touch[k] = False
    for r in range(1, h):
        i = first[r - 1]
        for k in range(first[r], first[r + 1]):
            while i < first[r] and rc1[i] < rc0[k] - 1:
                i += 1
            j = i
            while j < first[r] and rc0[j] <= rc1[k] + 1:
                if rband[j] == rband[k]:
                    a = _root(par, j)
                    b = _root(par, k)
                    if a != b:
                        par[max(a, b)] = min(a, b)
                j += 1
    for k in range(n):
        a = _root(par, k)
        r = rrow[k]
        box[0, a] = min(box[0, a], r)
        box[1, a] = max(box[1, a], r)
        box[2, a] = min(box[2, a], rc0[k])
        box[3, a] = max(box[3, a], rc1[k])
        if touch[a]:
            continue
        # the edge, or a cell that is not valid around the run
        lo = rc0[k] - 1
        hi = rc1[k] + 1
        if r == 0 or r == h - 1 or lo < 0 or hi >= w:
            touch[a] = True
            continue
        for rr in range(r - 1, r + 2):
            for cc in range(lo, hi + 1):
                if not valid[rr, cc]:
                    touch[a] = True
    for k in range(n):
        a = _root(par, k)
        ext = max(box[1, a] - box[0, a] + 1, box[3, a] - box[2, a] + 1)
        if not touch[a] and ext <= min_ring:
            for cc in range(rc0[k], rc1[k] + 1):
                small[rrow[k], cc] = True


@njit(cache=True, nogil=True, _nrt=False)
def fill_from_nearest(s, small, valid, radius, r0, r1, out):
    """``out[r0:r1]``: ``s`` of rows ``r0 .. r1``, where ``small`` the value of the nearest
    cell (Euclidean, in cells) that is ``valid`` and not ``small``, within ``radius`` cells
    along each axis; of equally near cells the first in raster order, so the result depends
    on that window alone. A cell with none within reach keeps its value. The search runs
    over square rings of growing radius and stops once a ring is farther than the best."""
    h, w = s.shape
    for r in range(r0, r1):
        for c in range(w):
            out[r - r0, c] = s[r, c]
            if not small[r, c]:
                continue
            best = -1
            bd = 2 * radius * radius + 1
            for k in range(1, radius + 1):
                if k * k > bd:
                    break
                for rr in range(r - k, r + k + 1):
                    if rr < 0 or rr >= h:
                        continue
                    edge = rr == r - k or rr == r + k
                    step = 1 if edge else 2 * k
                    for cc in range(c - k, c + k + 1, step):
                        if cc < 0 or cc >= w or not valid[rr, cc] or small[rr, cc]:
                            continue
                        d = (rr - r) * (rr - r) + (cc - c) * (cc - c)
                        p = rr * w + cc
                        if d < bd or (d == bd and p < best):
                            bd = d
                            best = p
            if best >= 0:
                out[r - r0, c] = s[best // w, best % w]
