"""Numba kernels of the contour generalisation (:mod:`._contour_generalize`): the
Gaussian-weighted local linear fit of a height field.

:func:`local_linear_kernel` computes what ``_contour_generalize.local_linear_reference`` does
with fourteen ``scipy.ndimage.correlate1d`` passes and some forty float64 temporaries of the
grid: the five x-passes (of the valid mask ``v`` and of ``v z``, with the weights ``G(d)``,
``G(d) d`` and ``G(d) d^2``) in one loop per tap over a row, then for each output row the nine
y-passes accumulated in nine rows and the 3 x 3 system solved there (Cramer's rule), without a
moment field of the grid. Both loops run over views that start at the span, so LLVM vectorises
them. Taps outside the grid count as no data (``correlate1d``'s ``mode="constant", cval=0``),
so a cell's fit depends only on its window, as before: chunks of a grid agree with the whole.
The sums are taken in another order than scipy's: the fits agree with the reference within
float64 rounding (tested).

A tile whose cells all have full windows (most of a DEM) takes :func:`fused_rows`: the same
sums and blend in one pass of rows, the x-moments in rings of rows and the fits of a row in
nine rows, so no plane of moments or fits is written and read back (the same bits, tested).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["blend_kernel", "full_moments", "fused_rows", "least_gradient", "local_linear_kernel"]


def local_linear_kernel(
    z: np.ndarray, valid: np.ndarray, g: np.ndarray, gd: np.ndarray, gdd: np.ndarray,
    sigma: float, out: np.ndarray | None = None, work: np.ndarray | None = None,
    serial: bool = False, rows: tuple[int, int] | None = None,
    cols: tuple[int, int] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """``(a, b, c)`` float64: at each cell the least-squares plane ``a + b dx + c dy`` of the
    valid cells around it, weighted ``g(dx) g(dy)`` (taps ``g``, ``g d``, ``g d^2`` of one
    Gaussian, odd length); the weighted mean and no slope where fewer cells span no plane.
    ``out``: an optional (3, H, W) C-contiguous float64 array to write them into; ``work``:
    an optional flat float64 buffer of at least ``5 H W`` for the x-passes (a caller that
    fits strip after strip reuses its memory: fresh memory costs more to touch than the
    sums); ``serial``: on the calling thread only (for a caller that runs tiles on threads);
    ``rows``: with ``serial``, the rows ``(r0, r1)`` to fit (the others are read, not fitted:
    ``a``, ``b``, ``c`` hold no values there); ``cols``: likewise the columns ``(c0, c1)``.

    The six moments of the valid mask are the same at every cell whose whole window is valid
    and inside the grid (most of a DEM): there they are computed once, from a row of ones by
    the same loops, and only the three moments of the heights are summed per cell; rows
    without nodata copy their mask moments from that row. A cell's path depends on its window
    alone, so chunks of a grid still agree with the whole bit for bit."""
    h, w = z.shape
    r = g.shape[0] // 2
    zc = np.ascontiguousarray(z, dtype=np.float64)
    vc = np.ascontiguousarray(valid, dtype=np.bool_)
    # the mask moments of a row of ones (x-passes) and of a full window (y-passes)
    full_x = np.empty((5, 1, w), np.float64)
    _x_rows(0, 1, np.zeros((1, w)), np.ones((1, w), np.bool_), g, gd, gdd, full_x,
            np.zeros((3, w)), np.zeros(1, np.bool_), 0, w, np.empty(w),
            np.empty(w + 2 * r))  # fmt: skip
    # the y-sums of a full window (the same bits as from this row: an interior column's
    # x-sums do not depend on the row's length)
    full_y = full_moments(g, gd, gdd) if w > 2 * r else np.zeros(6, np.float64)
    row_ok = np.ascontiguousarray(vc.all(axis=1))
    if work is None:
        work = np.empty(5 * h * w, np.float64)
    xs = work[: 5 * h * w].reshape(5, h, w)
    bands = _serial if serial else run_bands
    # the x-passes of the fitted columns only: the y-passes read no others
    c0, c1 = (0, w) if cols is None or not serial else cols
    bands(_x_rows, h, zc, vc, g, gd, gdd, xs, full_x[:3, 0], row_ok, c0, c1,
          scratch=lambda: (np.empty(w), np.empty(w + 2 * r)))  # fmt: skip
    if out is None:
        out = np.empty((3, h, w), np.float64)
    a, b, c = out[0], out[1], out[2]
    y_args = (xs, vc, g, gd, gdd, float(sigma), full_y, a, b, c, c0, c1)
    if rows is not None and serial:
        _y_rows(rows[0], rows[1], *y_args, np.empty((9, w)), np.empty(w, np.int32),
                np.empty(w + 1, np.int32))  # fmt: skip
    else:
        bands(_y_rows, h, *y_args, scratch=lambda: (np.empty((9, w)), np.empty(w, np.int32),
                                                    np.empty(w + 1, np.int32)))  # fmt: skip
    return a, b, c


def _serial(kernel, n: int, *args: object, scratch=None) -> None:
    """:func:`.run_bands`' call on the calling thread alone: ``kernel(0, n, *args)``."""
    kernel(0, n, *args, *(scratch() if scratch is not None else ()))


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _taps3(o0: np.ndarray, o1: np.ndarray, o2: np.ndarray, x: np.ndarray, w0: float,
           w1: float, w2: float) -> None:  # fmt: skip
    for j in range(o0.shape[0]):
        o0[j] += w0 * x[j]
        o1[j] += w1 * x[j]
        o2[j] += w2 * x[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _taps1(o0: np.ndarray, x: np.ndarray, w0: float) -> None:
    for j in range(o0.shape[0]):
        o0[j] += w0 * x[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _taps2(o0: np.ndarray, o1: np.ndarray, x: np.ndarray, w0: float, w1: float) -> None:
    for j in range(o0.shape[0]):
        o0[j] += w0 * x[j]
        o1[j] += w1 * x[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _taps2x4(
    o0: np.ndarray, o1: np.ndarray, x0: np.ndarray, x1: np.ndarray, x2: np.ndarray,
    x3: np.ndarray, g0: float, g1: float, g2: float, g3: float, d0: float, d1: float,
    d2: float, d3: float,
) -> None:  # fmt: skip
    """Four x-taps at once: ``o0 += g x``, ``o1 += d x`` for the shifted rows ``x0..x3``,
    added one tap after the other as four calls of one tap would (the same bits, a quarter
    of the loads and stores of the sums)."""
    for j in range(o0.shape[0]):
        o0[j] = (((o0[j] + g0 * x0[j]) + g1 * x1[j]) + g2 * x2[j]) + g3 * x3[j]
        o1[j] = (((o1[j] + d0 * x0[j]) + d1 * x1[j]) + d2 * x2[j]) + d3 * x3[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _x_rows(
    i0: int, i1: int, z: np.ndarray, valid: np.ndarray, g: np.ndarray, gd: np.ndarray,
    gdd: np.ndarray, xs: np.ndarray, full: np.ndarray, row_ok: np.ndarray, c0: int, c1: int,
    v: np.ndarray, vzp: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``i0 .. i1``, columns ``c0 .. c1`` of the x-passes: ``xs[0..2]`` of ``v`` with
    ``g``, ``g d``, ``g d^2``; ``xs[3..4]`` of ``v z`` with ``g``, ``g d``. A row without nodata
    (``row_ok``) copies ``xs[0..2]`` from ``full``, the same sums of a row of ones.

    ``vzp``: scratch of ``W + 2 r`` for ``v z`` with ``r`` zeros on each side, so every tap
    reads the whole row. A tap outside the grid then adds ``+-0.0``, which leaves a sum that
    started at ``+0.0`` as it is (such a sum is never ``-0.0``): the same bits as skipping
    the tap, and the taps run four at a time in one vector loop."""
    w = z.shape[1]
    r = g.shape[0] // 2
    n = c1 - c0
    for q in range(r):
        vzp[q] = 0.0
        vzp[r + w + q] = 0.0
    for i in range(i0, i1):
        ok_row = row_ok[i]
        for j in range(w):
            ok = valid[i, j]
            v[j] = 1.0 if ok else 0.0
            vzp[r + j] = z[i, j] if ok else 0.0
        for j in range(c0, c1):
            xs[3, i, j] = 0.0
            xs[4, i, j] = 0.0
        if ok_row:
            for f in range(3):
                for j in range(c0, c1):
                    xs[f, i, j] = full[f, j]
        else:
            for f in range(3):
                for j in range(c0, c1):
                    xs[f, i, j] = 0.0
            for t in range(2 * r + 1):
                off = t - r
                lo = max(c0, -off)
                hi = min(c1, w - off)
                if lo < hi:
                    _taps3(xs[0, i, lo:hi], xs[1, i, lo:hi], xs[2, i, lo:hi],
                           v[lo + off : hi + off], g[t], gd[t], gdd[t])  # fmt: skip
        t = 0
        while t < 2 * r + 1:
            x = t + c0
            if t + 3 < 2 * r + 1:
                _taps2x4(xs[3, i, c0:c1], xs[4, i, c0:c1], vzp[x : x + n], vzp[x + 1 : x + 1 + n],
                         vzp[x + 2 : x + 2 + n], vzp[x + 3 : x + 3 + n], g[t], g[t + 1],
                         g[t + 2], g[t + 3], gd[t], gd[t + 1], gd[t + 2], gd[t + 3])  # fmt: skip
                t += 4
            else:
                _taps2(xs[3, i, c0:c1], xs[4, i, c0:c1], vzp[x : x + n], g[t], gd[t])
                t += 1


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _ztaps4(
    mz: np.ndarray, myz: np.ndarray, mxz: np.ndarray, a0: np.ndarray, a1: np.ndarray,
    a2: np.ndarray, a3: np.ndarray, b0: np.ndarray, b1: np.ndarray, b2: np.ndarray,
    b3: np.ndarray, g0: float, g1: float, g2: float, g3: float, d0: float, d1: float,
    d2: float, d3: float,
) -> None:  # fmt: skip
    """Four y-taps of the height moments at once: ``mz += g a``, ``myz += g d a``,
    ``mxz += g b`` for rows ``a0..a3`` (x-pass ``g``) and ``b0..b3`` (x-pass ``g d``), added
    one tap after the other as four calls of one tap would."""
    for j in range(mz.shape[0]):
        mz[j] = (((mz[j] + g0 * a0[j]) + g1 * a1[j]) + g2 * a2[j]) + g3 * a3[j]
        myz[j] = (((myz[j] + d0 * a0[j]) + d1 * a1[j]) + d2 * a2[j]) + d3 * a3[j]
        mxz[j] = (((mxz[j] + g0 * b0[j]) + g1 * b1[j]) + g2 * b2[j]) + g3 * b3[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _v_taps(acc: np.ndarray, xs: np.ndarray, i: int, g: np.ndarray, gd: np.ndarray,
            gdd: np.ndarray) -> None:  # fmt: skip
    """The y-passes of the six mask moments of row ``i`` into ``acc[0..5]`` (zeroed by the
    caller), over the columns of ``xs`` (a view of the span)."""
    h = xs.shape[1]
    r = g.shape[0] // 2
    for t in range(2 * r + 1):
        row = i + t - r
        if row < 0 or row >= h:
            continue
        _taps3(acc[0], acc[1], acc[2], xs[0, row], g[t], gd[t], gdd[t])  # m0, my, myy
        _taps2(acc[3], acc[4], xs[1, row], g[t], gd[t])  # mx, mxy
        _taps1(acc[5], xs[2, row], g[t])  # mxx


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _y_rows(
    i0: int, i1: int, xs: np.ndarray, valid: np.ndarray, g: np.ndarray, gd: np.ndarray,
    gdd: np.ndarray, sigma: float, full: np.ndarray, a: np.ndarray, b: np.ndarray,
    c: np.ndarray, c0: int, c1: int, acc: np.ndarray, bad: np.ndarray, run: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``i0 .. i1``, columns ``c0 .. c1`` of the y-passes of the moments and the plane's
    solution.

    ``bad[j]``: the cells of column ``j`` in the row's window that are nodata or outside the
    grid (kept row to row); a cell with no such cell within ``r`` columns (and ``r`` cells
    from the grid's sides) takes the mask moments ``full``, the others sum them in runs."""
    h, w = xs.shape[1], xs.shape[2]
    r = g.shape[0] // 2
    s4 = 1e-3 * sigma**4
    for j in range(w):
        bad[j] = 0
        for row in range(i0 - r, i0 + r + 1):
            if row < 0 or row >= h or not valid[row, j]:
                bad[j] += 1
    for i in range(i0, i1):
        if i > i0:  # slide the window one row down
            for j in range(w):
                out_row = i - r - 1
                in_row = i + r
                bad[j] -= 1 if out_row < 0 or not valid[out_row, j] else 0
                bad[j] += 1 if in_row >= h or not valid[in_row, j] else 0
        # run[j]: columns before j with a bad window column (a prefix count)
        run[0] = 0
        for j in range(w):
            run[j + 1] = run[j] + (1 if bad[j] > 0 else 0)
        for f in range(6, 9):
            for j in range(c0, c1):
                acc[f, j] = 0.0
        # mz, myz, mxz: four taps a pass where four rows are in the grid (each sum still
        # taken tap by tap in order, so the same bits; a quarter of the loads and stores)
        t = 0
        while t < 2 * r + 1:
            row = i + t - r
            if row < 0 or row >= h:
                t += 1
            elif t + 3 < 2 * r + 1 and row + 3 < h:
                _ztaps4(acc[6, c0:c1], acc[7, c0:c1], acc[8, c0:c1], xs[3, row, c0:c1],
                        xs[3, row + 1, c0:c1], xs[3, row + 2, c0:c1], xs[3, row + 3, c0:c1],
                        xs[4, row, c0:c1], xs[4, row + 1, c0:c1], xs[4, row + 2, c0:c1],
                        xs[4, row + 3, c0:c1], g[t], g[t + 1], g[t + 2], g[t + 3], gd[t],
                        gd[t + 1], gd[t + 2], gd[t + 3])  # fmt: skip
                t += 4
            else:
                _taps2(acc[6, c0:c1], acc[7, c0:c1], xs[3, row, c0:c1], g[t], gd[t])
                _taps1(acc[8, c0:c1], xs[4, row, c0:c1], g[t])
                t += 1
        # the mask moments: constants where the window is full, summed over runs elsewhere;
        # a full window's system is the same at every cell, so its cofactors are taken once
        j = c0
        while j < c1:
            jl = max(j - r, 0)
            jh = min(j + r + 1, w)
            full_here = j >= r and j < w - r and run[jh] - run[jl] == 0
            k = j + 1
            while k < c1:
                kl = max(k - r, 0)
                kh = min(k + r + 1, w)
                if (k >= r and k < w - r and run[kh] - run[kl] == 0) != full_here:
                    break
                k += 1
            if full_here:
                _solve_full(acc[6, j:k], acc[7, j:k], acc[8, j:k], full, s4, a[i, j:k],
                            b[i, j:k], c[i, j:k])  # fmt: skip
            else:
                for f in range(6):
                    for q in range(j, k):
                        acc[f, q] = 0.0
                _v_taps(acc[:, j:k], xs[:, :, j:k], i, g, gd, gdd)
                _solve(acc[:, j:k], s4, a[i, j:k], b[i, j:k], c[i, j:k])
            j = k


@njit(cache=True, inline="always", error_model="numpy")
def _cofactors(m0: float, my: float, myy: float, mx: float, mxy: float, mxx: float,
               s4: float) -> tuple:  # fmt: skip
    """The cofactors ``c00 c01 c02 c11 c12 c22`` of ``[[m0 mx my] [mx mxx mxy] [my mxy
    myy]]``, whether the cells span a plane (``det > s4 m0^3``) and ``1 / det`` (0 if not)."""
    c00 = mxx * myy - mxy * mxy
    c01 = mxy * my - mx * myy
    c02 = mx * mxy - mxx * my
    det = m0 * c00 + mx * c01 + my * c02
    c11 = m0 * myy - my * my
    c12 = mx * my - m0 * mxy
    c22 = m0 * mxx - mx * mx
    ok = det > s4 * m0 * m0 * m0
    inv = 1.0 / det if ok else 0.0
    return c00, c01, c02, c11, c12, c22, ok, inv


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _solve(acc: np.ndarray, s4: float, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> None:
    """The plane ``(a, b, c)`` of each cell from its nine moments ``acc``: the 3 x 3 system
    ``[[m0 mx my] [mx mxx mxy] [my mxy myy]] (a b c) = (mz mxz myz)`` by Cramer's rule; where
    the cells span no plane (``det <= s4 m0^3``, ``s4 = 1e-3 sigma^4``: det relative to
    ``m0^3 sigma^4``, ~1 when full) the weighted mean and no slope."""
    for j in range(a.shape[0]):
        m0, my, myy, mx, mxy = acc[0, j], acc[1, j], acc[2, j], acc[3, j], acc[4, j]
        mxx, mz, myz, mxz = acc[5, j], acc[6, j], acc[7, j], acc[8, j]
        c00, c01, c02, c11, c12, c22, ok, inv = _cofactors(m0, my, myy, mx, mxy, mxx, s4)
        a[j] = (c00 * mz + c01 * mxz + c02 * myz) * inv if ok else mz / m0
        b[j] = (c01 * mz + c11 * mxz + c12 * myz) * inv
        c[j] = (c02 * mz + c12 * mxz + c22 * myz) * inv


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _solve_full(mz: np.ndarray, myz: np.ndarray, mxz: np.ndarray, full: np.ndarray, s4: float,
                a: np.ndarray, b: np.ndarray, c: np.ndarray) -> None:  # fmt: skip
    """:func:`_solve` where every cell has the mask moments ``full`` (the same operations on
    the same values: the same bits), the cofactors taken once."""
    m0, my, myy, mx, mxy, mxx = full[0], full[1], full[2], full[3], full[4], full[5]
    c00, c01, c02, c11, c12, c22, ok, inv = _cofactors(m0, my, myy, mx, mxy, mxx, s4)
    for j in range(a.shape[0]):
        a[j] = (c00 * mz[j] + c01 * mxz[j] + c02 * myz[j]) * inv if ok else mz[j] / m0
        b[j] = (c01 * mz[j] + c11 * mxz[j] + c12 * myz[j]) * inv
        c[j] = (c02 * mz[j] + c12 * mxz[j] + c22 * myz[j]) * inv


# ------------------------------------------------ the blend of the fits, the band, the flats
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _lerp_fit(s: float, f0: float, f1: float, f2: float, f3: float) -> float:
    """The value at smoothing width ``s`` of the fits ``f0 .. f3`` at widths 0, 1, 2, 4
    (``SIGMAS``): linear between the two widths around ``s``, as the reference's ``where``
    chain (a width of exactly 0 keeps ``f0``)."""
    if s > 2.0:
        t = min(max((s - 2.0) / 2.0, 0.0), 1.0)
        return (1.0 - t) * f2 + t * f3
    if s > 1.0:
        t = min(max(s - 1.0, 0.0), 1.0)
        return (1.0 - t) * f1 + t * f2
    if s > 0.0:
        t = min(max(s, 0.0), 1.0)
        return (1.0 - t) * f0 + t * f1
    return f0


@njit(cache=True, inline="always", error_model="numpy")
def _neighbour(zn: float, zc: float, k: float, lo: float, hi: float, zmax: float,
               zmin: float) -> tuple:  # fmt: skip
    """One neighbour ``zn`` of :func:`_blend_rows`' loop: the band ``(lo, hi)`` widened to the
    interpolant ``k`` of the way towards it, the 3 x 3 range ``(zmax, zmin)`` to it."""
    step = zn - zc
    t = zc + k * step
    if np.isfinite(step):
        lo = min(lo, t)
        hi = max(hi, t)
    return lo, hi, max(zmax, zn), min(zmin, zn)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _blend_full(
    up: np.ndarray, mid: np.ndarray, down: np.ndarray, a1: np.ndarray, b1s: np.ndarray,
    c1s: np.ndarray, a2: np.ndarray, b2: np.ndarray, c2: np.ndarray, a4: np.ndarray,
    b4: np.ndarray, c4: np.ndarray, interval: float, per_px: float, steep: float,
    sigma_max: float, sigma_grad: float, k_axis: float, k_diag: float, out: np.ndarray,
    grad: np.ndarray,
) -> None:  # fmt: skip
    """:func:`_blend_rows` of a run of cells whose 3 x 3 neighbours are all valid (rows
    ``up``, ``mid``, ``down`` one cell wider on each side; the fits' rows ``a1 .. c4``): the
    same operations in the same order, the neighbours written out."""
    for q in range(out.shape[0]):
        zc = mid[q + 1]
        b1 = b1s[q]
        c1 = c1s[q]
        g = np.sqrt(b1 * b1 + c1 * c1)
        spacing = interval / g if g > 0.0 else np.inf
        sigma = min(max(per_px * (spacing - steep), 0.0), sigma_max)
        sg = max(sigma, sigma_grad)
        v = _lerp_fit(sigma, zc, a1[q], a2[q], a4[q])
        gx = _lerp_fit(sg, 0.0, b1, b2[q], b4[q])
        gy = _lerp_fit(sg, 0.0, c1, c2[q], c4[q])
        lo = zc
        hi = zc
        zmax = zc
        zmin = zc
        # the neighbours in _blend_rows' order: rows -1, 0, 1, columns -1, 0, 1
        lo, hi, zmax, zmin = _neighbour(up[q], zc, k_diag, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(up[q + 1], zc, k_axis, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(up[q + 2], zc, k_diag, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(mid[q], zc, k_axis, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(mid[q + 2], zc, k_axis, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(down[q], zc, k_diag, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(down[q + 1], zc, k_axis, lo, hi, zmax, zmin)
        lo, hi, zmax, zmin = _neighbour(down[q + 2], zc, k_diag, lo, hi, zmax, zmin)
        v = min(max(v, lo), hi)
        out[q] = np.float32(v)
        grad[q] = np.float32(0.0) if zmax == zmin else np.float32(np.sqrt(gx * gx + gy * gy))


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _blend_rows(
    i0: int, i1: int, z: np.ndarray, valid: np.ndarray, fits: np.ndarray, interval: float,
    per_px: float, steep: float, sigma_max: float, sigma_grad: float, k_axis: float,
    k_diag: float, r0: int, c0: int, c1: int, out: np.ndarray, grad: np.ndarray,
    row_ok: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``r0 + i0 .. r0 + i1``, columns ``c0 .. c1`` of :func:`blend_kernel`, cell
    ``(i, j)`` into ``out[i - r0, j - c0]`` and ``grad[i - r0, j - c0]``."""
    h, w = z.shape
    nan = np.float32(np.nan)
    for i in range(r0 + i0, r0 + i1):
        # rows whose 3 x 3 windows are all valid and inside the grid: the same operations
        # in a loop without branches on the neighbours, which LLVM vectorises
        fa, fb = c0, c0
        if 0 < i < h - 1 and row_ok[i - 1] and row_ok[i] and row_ok[i + 1]:
            fa, fb = max(c0, 1), min(c1, w - 1)
            if fa < fb:
                _blend_full(z[i - 1, fa - 1 : fb + 1], z[i, fa - 1 : fb + 1],
                            z[i + 1, fa - 1 : fb + 1], fits[0, i, fa:fb], fits[1, i, fa:fb],
                            fits[2, i, fa:fb], fits[3, i, fa:fb], fits[4, i, fa:fb],
                            fits[5, i, fa:fb], fits[6, i, fa:fb], fits[7, i, fa:fb],
                            fits[8, i, fa:fb], interval, per_px, steep, sigma_max, sigma_grad,
                            k_axis, k_diag, out[i - r0, fa - c0 : fb - c0],
                            grad[i - r0, fa - c0 : fb - c0])  # fmt: skip
            else:
                fa, fb = c0, c0
        for j in range(c0, c1):
            if fa <= j < fb:
                continue
            if not valid[i, j]:
                out[i - r0, j - c0] = nan
                grad[i - r0, j - c0] = nan
                continue
            zc = z[i, j]
            # the width asked by the line spacing interval / g of the SIGMA_SLOPE (= 1) fit
            g = np.sqrt(fits[1, i, j] * fits[1, i, j] + fits[2, i, j] * fits[2, i, j])
            spacing = interval / g if g > 0.0 else np.inf
            sigma = min(max(per_px * (spacing - steep), 0.0), sigma_max)
            sg = max(sigma, sigma_grad)
            v = _lerp_fit(sigma, zc, fits[0, i, j], fits[3, i, j], fits[6, i, j])
            gx = _lerp_fit(sg, 0.0, fits[1, i, j], fits[4, i, j], fits[7, i, j])
            gy = _lerp_fit(sg, 0.0, fits[2, i, j], fits[5, i, j], fits[8, i, j])
            # the tolerance band of the bilinear interpolant, and the flat test (3 x 3
            # maximum == minimum of the valid heights; outside the grid is not looked at)
            lo = zc
            hi = zc
            zmax = zc
            zmin = zc
            for dr in range(-1, 2):
                for dc in range(-1, 2):
                    if dr == 0 and dc == 0:
                        continue
                    r = i + dr
                    c = j + dc
                    if r < 0 or r >= h or c < 0 or c >= w or not valid[r, c]:
                        continue
                    zn = z[r, c]
                    k = k_axis if dr == 0 or dc == 0 else k_diag
                    step = zn - zc
                    if np.isfinite(step):
                        t = zc + k * step
                        lo = min(lo, t)
                        hi = max(hi, t)
                    zmax = max(zmax, zn)
                    zmin = min(zmin, zn)
            v = min(max(v, lo), hi)
            out[i - r0, j - c0] = np.float32(v)
            grad[i - r0, j - c0] = (
                np.float32(0.0) if zmax == zmin else np.float32(np.sqrt(gx * gx + gy * gy))
            )


def blend_kernel(
    z: np.ndarray, valid: np.ndarray, fits: np.ndarray, interval: float, *, per_px: float,
    steep: float, sigma_max: float, sigma_grad: float, displace: float, serial: bool = False,
    inner: tuple[int, int, int, int] | None = None, out: np.ndarray | None = None,
    grad: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The generalised field and its gradient magnitude from the fits (float32, NaN where
    not ``valid``): what ``_contour_generalize.smooth_strip_reference`` computes with some
    thirty float64 temporaries of the grid, one pass per cell.

    ``fits``: (9, H, W) float64, ``(a, b, c)`` of the local linear fits at widths 1, 2, 4.
    Per cell: the width ``clip(per_px (interval / g - steep), 0, sigma_max)`` from the width-1
    fit's gradient ``g``; the value blended between the fits around that width (the height
    itself at width 0), the gradient between those around ``max(width, sigma_grad)``; the
    value clipped to the tolerance band (the range of the bilinear interpolant within
    ``displace`` cells); the gradient 0 where the 3 x 3 valid heights are all equal.
    ``inner``: only the cells ``(r0, r1, c0, c1)`` (rows, columns), into ``out`` and ``grad``
    of that shape when given (views of a larger output)."""
    h, w = z.shape
    r0, r1, c0, c1 = (0, h, 0, w) if inner is None else inner
    zc = np.ascontiguousarray(z, dtype=np.float64)
    vc = np.ascontiguousarray(valid, dtype=np.bool_)
    if out is None:
        out = np.empty((r1 - r0, c1 - c0), np.float32)
    if grad is None:
        grad = np.empty((r1 - r0, c1 - c0), np.float32)
    bands = _serial if serial else run_bands
    bands(_blend_rows, r1 - r0, zc, vc, np.ascontiguousarray(fits), float(interval),
          float(per_px), float(steep), float(sigma_max), float(sigma_grad), float(displace),
          float(displace / np.sqrt(2.0)), r0, c0, c1, out, grad,
          np.ascontiguousarray(vc.all(axis=1)))  # fmt: skip
    return out, grad


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def least_gradient(b: np.ndarray, c: np.ndarray, valid: np.ndarray) -> float:
    """The least ``sqrt(b^2 + c^2)`` over the ``valid`` cells (inf if none): one pass, no
    temporaries (the smoothing asks it of every strip's slope fit); the root of the least
    square, the same value."""
    h, w = b.shape
    best = np.inf
    for i in range(h):
        for j in range(w):
            q = b[i, j] * b[i, j] + c[i, j] * c[i, j]
            best = q if valid[i, j] and q < best else best
    return np.sqrt(best)


# ------------------------------------------------ the fused route of a tile without nodata
def full_moments(g: np.ndarray, gd: np.ndarray, gdd: np.ndarray) -> np.ndarray:
    """The six mask moments ``m0 my myy mx mxy mxx`` of a window inside the grid without
    nodata, as :func:`local_linear_kernel` takes them (the x-sums of a row of ones, then the
    y-sums in :func:`_v_taps`' order: the same bits)."""
    r = g.shape[0] // 2
    w = 2 * r + 2
    full_x = np.empty((5, 1, w), np.float64)
    _x_rows(0, 1, np.zeros((1, w)), np.ones((1, w), np.bool_), g, gd, gdd, full_x,
            np.zeros((3, w)), np.zeros(1, np.bool_), 0, w, np.empty(w),
            np.empty(w + 2 * r))  # fmt: skip
    x0, x1, x2 = (float(full_x[f, 0, r]) for f in range(3))
    m = [0.0] * 6
    for t in range(2 * r + 1):
        m[0] += float(g[t]) * x0
        m[1] += float(gd[t]) * x0
        m[2] += float(gdd[t]) * x0
        m[3] += float(g[t]) * x1
        m[4] += float(gd[t]) * x1
        m[5] += float(g[t]) * x2
    return np.array(m, np.float64)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _x_moments(zrow: np.ndarray, c0: int, c1: int, g: np.ndarray, gd: np.ndarray,
               o0: np.ndarray, o1: np.ndarray) -> None:  # fmt: skip
    """The height x-moments ``o0 = sum g z``, ``o1 = sum g d z`` of columns ``c0 .. c1`` of
    one row whose taps all lie inside it: :func:`_x_rows`' sums, in its order and grouping
    of four taps (the same bits)."""
    r = g.shape[0] // 2
    n = c1 - c0
    for j in range(n):
        o0[j] = 0.0
        o1[j] = 0.0
    t = 0
    while t < 2 * r + 1:
        x = c0 + t - r
        if t + 3 < 2 * r + 1:
            _taps2x4(o0, o1, zrow[x : x + n], zrow[x + 1 : x + 1 + n], zrow[x + 2 : x + 2 + n],
                     zrow[x + 3 : x + 3 + n], g[t], g[t + 1], g[t + 2], g[t + 3], gd[t],
                     gd[t + 1], gd[t + 2], gd[t + 3])  # fmt: skip
            t += 4
        else:
            _taps2(o0, o1, zrow[x : x + n], g[t], gd[t])
            t += 1


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _y_fit(ring: np.ndarray, i: int, g: np.ndarray, gd: np.ndarray, full: np.ndarray,
           s4: float, acc: np.ndarray, a: np.ndarray, b: np.ndarray,
           c: np.ndarray) -> None:  # fmt: skip
    """The plane of every cell of row ``i`` from the x-moment rows in ``ring`` (slot ``row
    % len(ring)``): :func:`_y_rows`' sums of a full window, in its order and grouping, and
    :func:`_solve_full` (the same bits)."""
    r = g.shape[0] // 2
    m = ring.shape[0]
    n = a.shape[0]
    for f in range(3):
        for j in range(n):
            acc[f, j] = 0.0
    t = 0
    while t < 2 * r + 1:
        row = i + t - r
        if t + 3 < 2 * r + 1:
            _ztaps4(acc[0], acc[1], acc[2], ring[row % m, 0], ring[(row + 1) % m, 0],
                    ring[(row + 2) % m, 0], ring[(row + 3) % m, 0], ring[row % m, 1],
                    ring[(row + 1) % m, 1], ring[(row + 2) % m, 1], ring[(row + 3) % m, 1],
                    g[t], g[t + 1], g[t + 2], g[t + 3], gd[t], gd[t + 1], gd[t + 2],
                    gd[t + 3])  # fmt: skip
            t += 4
        else:
            _taps2(acc[0], acc[1], ring[row % m, 0], g[t], gd[t])
            _taps1(acc[2], ring[row % m, 1], g[t])
            t += 1
    _solve_full(acc[0], acc[1], acc[2], full, s4, a, b, c)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def fused_rows(
    z: np.ndarray, r0: int, r1: int, c0: int, c1: int, g1: np.ndarray, gd1: np.ndarray,
    g2: np.ndarray, gd2: np.ndarray, g4: np.ndarray, gd4: np.ndarray, full: np.ndarray,
    s4: np.ndarray, interval: float, per_px: float, steep: float, sigma_max: float,
    sigma_grad: float, k_axis: float, k_diag: float, out: np.ndarray, grad: np.ndarray,
    ring1: np.ndarray, ring2: np.ndarray, ring4: np.ndarray, acc: np.ndarray,
    fit: np.ndarray,
) -> None:  # fmt: skip
    """:func:`local_linear_kernel` at the widths 1, 2 and 4, then :func:`blend_kernel`, of
    the cells ``(r0 .. r1, c0 .. c1)`` of ``z`` whose windows at width 4 lie inside ``z``
    and hold no nodata (the caller checks), into ``out`` and ``grad`` (that shape): the same
    operations on the same values, so the same bits, in one pass of rows.

    The separate kernels write the x-moments of the tile (five float64 planes) and nine fit
    planes, then read them back: memory traffic, not the sums, bounded them. Here the
    x-moments of a row are kept in rings of rows (``ring1/2/4``: at least ``2 r + 1`` rows
    of each width's ``2 x n`` moments), each row's three fits in ``fit`` (9 x n), and the
    blend runs as soon as a row is fitted; the wider fits are taken only for rows where a
    cell asks for them (the width grows as the width-1 slope falls), their x-moments on
    demand. ``full``: (3, 6) mask moments of each width (:func:`full_moments`); ``s4``:
    ``1e-3 sigma^4`` of each; ``acc``: (3, n) scratch."""
    n = c1 - c0
    r_1 = g1.shape[0] // 2
    r_2 = g2.shape[0] // 2
    r_4 = g4.shape[0] // 2
    m1 = ring1.shape[0]
    m2 = ring2.shape[0]
    m4 = ring4.shape[0]
    for row in range(r0 - r_1, r0 + r_1):
        _x_moments(z[row], c0, c1, g1, gd1, ring1[row % m1, 0], ring1[row % m1, 1])
    done2 = r0 - r_2 - 1  # the last row whose width-2 x-moments are in ring2
    done4 = r0 - r_4 - 1
    for i in range(r0, r1):
        row = i + r_1
        _x_moments(z[row], c0, c1, g1, gd1, ring1[row % m1, 0], ring1[row % m1, 1])
        _y_fit(ring1, i, g1, gd1, full[0], s4[0], acc, fit[0], fit[1], fit[2])
        # the widest width a cell of the row asks for: _blend_full's width of the least
        # gradient (every step from b^2 + c^2 to the width is monotone in IEEE arithmetic,
        # so this is the largest of the cells' widths, bit for bit)
        least = np.inf
        for q in range(n):
            sq = fit[1, q] * fit[1, q] + fit[2, q] * fit[2, q]
            least = sq if sq < least else least
        gm = np.sqrt(least)
        spacing = interval / gm if gm > 0.0 else np.inf
        widest = min(max(per_px * (spacing - steep), 0.0), sigma_max)
        if widest > 1.0:
            for row in range(max(done2 + 1, i - r_2), i + r_2 + 1):
                _x_moments(z[row], c0, c1, g2, gd2, ring2[row % m2, 0], ring2[row % m2, 1])
            done2 = i + r_2
            _y_fit(ring2, i, g2, gd2, full[1], s4[1], acc, fit[3], fit[4], fit[5])
        if widest > 2.0:
            for row in range(max(done4 + 1, i - r_4), i + r_4 + 1):
                _x_moments(z[row], c0, c1, g4, gd4, ring4[row % m4, 0], ring4[row % m4, 1])
            done4 = i + r_4
            _y_fit(ring4, i, g4, gd4, full[2], s4[2], acc, fit[6], fit[7], fit[8])
        _blend_full(z[i - 1, c0 - 1 : c1 + 1], z[i, c0 - 1 : c1 + 1], z[i + 1, c0 - 1 : c1 + 1],
                    fit[0], fit[1], fit[2], fit[3], fit[4], fit[5], fit[6], fit[7], fit[8],
                    interval, per_px, steep, sigma_max, sigma_grad, k_axis, k_diag,
                    out[i - r0], grad[i - r0])  # fmt: skip
