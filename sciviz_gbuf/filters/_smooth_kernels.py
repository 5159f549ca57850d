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
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["blend_kernel", "local_linear_kernel"]


def local_linear_kernel(
    z: np.ndarray, valid: np.ndarray, g: np.ndarray, gd: np.ndarray, gdd: np.ndarray,
    sigma: float, out: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """``(a, b, c)`` float64: at each cell the least-squares plane ``a + b dx + c dy`` of the
    valid cells around it, weighted ``g(dx) g(dy)`` (taps ``g``, ``g d``, ``g d^2`` of one
    Gaussian, odd length); the weighted mean and no slope where fewer cells span no plane.
    ``out``: an optional (3, H, W) C-contiguous float64 array to write them into."""
    h, w = z.shape
    zc = np.ascontiguousarray(z, dtype=np.float64)
    vc = np.ascontiguousarray(valid, dtype=np.bool_)
    xs = np.empty((5, h, w), np.float64)
    run_bands(_x_rows, h, zc, vc, g, gd, gdd, xs,
              scratch=lambda: (np.empty(w), np.empty(w)))  # fmt: skip
    if out is None:
        out = np.empty((3, h, w), np.float64)
    a, b, c = out[0], out[1], out[2]
    run_bands(_y_rows, h, xs, g, gd, gdd, float(sigma), a, b, c,
              scratch=lambda: (np.empty((9, w)),))  # fmt: skip
    return a, b, c


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _taps5(
    o0: np.ndarray, o1: np.ndarray, o2: np.ndarray, o3: np.ndarray, o4: np.ndarray,
    v: np.ndarray, vz: np.ndarray, wg: float, wd: float, wdd: float,
) -> None:  # fmt: skip
    for j in range(o0.shape[0]):
        o0[j] += wg * v[j]
        o1[j] += wd * v[j]
        o2[j] += wdd * v[j]
        o3[j] += wg * vz[j]
        o4[j] += wd * vz[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _x_rows(
    i0: int, i1: int, z: np.ndarray, valid: np.ndarray, g: np.ndarray, gd: np.ndarray,
    gdd: np.ndarray, xs: np.ndarray, v: np.ndarray, vz: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``i0 .. i1`` of the x-passes: ``xs[0..2]`` of ``v`` with ``g``, ``g d``,
    ``g d^2``; ``xs[3..4]`` of ``v z`` with ``g``, ``g d``."""
    w = z.shape[1]
    r = g.shape[0] // 2
    for i in range(i0, i1):
        for j in range(w):
            ok = valid[i, j]
            v[j] = 1.0 if ok else 0.0
            vz[j] = z[i, j] if ok else 0.0
            for f in range(5):
                xs[f, i, j] = 0.0
        for t in range(2 * r + 1):
            off = t - r
            lo = max(0, -off)
            hi = min(w, w - off)
            if lo >= hi:
                continue
            _taps5(xs[0, i, lo:hi], xs[1, i, lo:hi], xs[2, i, lo:hi], xs[3, i, lo:hi],
                   xs[4, i, lo:hi], v[lo + off : hi + off], vz[lo + off : hi + off], g[t],
                   gd[t], gdd[t])  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _taps9(acc: np.ndarray, x0: np.ndarray, x1: np.ndarray, x2: np.ndarray, x3: np.ndarray,
           x4: np.ndarray, wg: float, wd: float, wdd: float) -> None:  # fmt: skip
    a0, a1, a2 = acc[0], acc[1], acc[2]
    a3, a4, a5 = acc[3], acc[4], acc[5]
    a6, a7, a8 = acc[6], acc[7], acc[8]
    for j in range(x0.shape[0]):
        a0[j] += wg * x0[j]  # m0
        a1[j] += wd * x0[j]  # my
        a2[j] += wdd * x0[j]  # myy
        a3[j] += wg * x1[j]  # mx
        a4[j] += wd * x1[j]  # mxy
        a5[j] += wg * x2[j]  # mxx
        a6[j] += wg * x3[j]  # mz
        a7[j] += wd * x3[j]  # myz
        a8[j] += wg * x4[j]  # mxz


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _y_rows(
    i0: int, i1: int, xs: np.ndarray, g: np.ndarray, gd: np.ndarray, gdd: np.ndarray,
    sigma: float, a: np.ndarray, b: np.ndarray, c: np.ndarray, acc: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``i0 .. i1`` of the y-passes of the moments and the plane's solution."""
    h, w = xs.shape[1], xs.shape[2]
    r = g.shape[0] // 2
    s4 = 1e-3 * sigma**4
    for i in range(i0, i1):
        for f in range(9):
            for j in range(w):
                acc[f, j] = 0.0
        for t in range(2 * r + 1):
            row = i + t - r
            if row < 0 or row >= h:
                continue
            _taps9(acc, xs[0, row], xs[1, row], xs[2, row], xs[3, row], xs[4, row], g[t],
                   gd[t], gdd[t])  # fmt: skip
        for j in range(w):
            m0, my, myy, mx, mxy = acc[0, j], acc[1, j], acc[2, j], acc[3, j], acc[4, j]
            mxx, mz, myz, mxz = acc[5, j], acc[6, j], acc[7, j], acc[8, j]
            # [[m0 mx my] [mx mxx mxy] [my mxy myy]] (a b c) = (mz mxz myz), Cramer's rule
            c00 = mxx * myy - mxy * mxy
            c01 = mxy * my - mx * myy
            c02 = mx * mxy - mxx * my
            det = m0 * c00 + mx * c01 + my * c02
            c11 = m0 * myy - my * my
            c12 = mx * my - m0 * mxy
            c22 = m0 * mxx - mx * mx
            # a plane needs a spread of cells: det relative to m0^3 sigma^4 (~1 when full)
            ok = det > s4 * m0 * m0 * m0
            inv = 1.0 / det if ok else 0.0
            a[i, j] = (c00 * mz + c01 * mxz + c02 * myz) * inv if ok else mz / m0
            b[i, j] = (c01 * mz + c11 * mxz + c12 * myz) * inv
            c[i, j] = (c02 * mz + c12 * mxz + c22 * myz) * inv


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


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _blend_rows(
    i0: int, i1: int, z: np.ndarray, valid: np.ndarray, fits: np.ndarray, interval: float,
    per_px: float, steep: float, sigma_max: float, sigma_grad: float, k_axis: float,
    k_diag: float, out: np.ndarray, grad: np.ndarray,
) -> None:  # fmt: skip
    """Rows ``i0 .. i1`` of :func:`blend_kernel`."""
    h, w = z.shape
    nan = np.float32(np.nan)
    for i in range(i0, i1):
        for j in range(w):
            if not valid[i, j]:
                out[i, j] = nan
                grad[i, j] = nan
                continue
            zc = z[i, j]
            # the width asked by the line spacing interval / g of the SIGMA_SLOPE (= 1) fit
            g = np.hypot(fits[1, i, j], fits[2, i, j])
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
            out[i, j] = np.float32(v)
            grad[i, j] = np.float32(0.0) if zmax == zmin else np.float32(np.hypot(gx, gy))


def blend_kernel(
    z: np.ndarray, valid: np.ndarray, fits: np.ndarray, interval: float, *, per_px: float,
    steep: float, sigma_max: float, sigma_grad: float, displace: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The generalised field and its gradient magnitude from the fits (float32, NaN where
    not ``valid``): what ``_contour_generalize.smooth_strip_reference`` computes with some
    thirty float64 temporaries of the grid, one pass per cell.

    ``fits``: (9, H, W) float64, ``(a, b, c)`` of the local linear fits at widths 1, 2, 4.
    Per cell: the width ``clip(per_px (interval / g - steep), 0, sigma_max)`` from the width-1
    fit's gradient ``g``; the value blended between the fits around that width (the height
    itself at width 0), the gradient between those around ``max(width, sigma_grad)``; the
    value clipped to the tolerance band (the range of the bilinear interpolant within
    ``displace`` cells); the gradient 0 where the 3 x 3 valid heights are all equal."""
    h, w = z.shape
    zc = np.ascontiguousarray(z, dtype=np.float64)
    vc = np.ascontiguousarray(valid, dtype=np.bool_)
    out = np.empty((h, w), np.float32)
    grad = np.empty((h, w), np.float32)
    run_bands(_blend_rows, h, zc, vc, np.ascontiguousarray(fits), float(interval),
              float(per_px), float(steep), float(sigma_max), float(sigma_grad),
              float(displace), float(displace / np.sqrt(2.0)), out, grad)  # fmt: skip
    return out, grad
