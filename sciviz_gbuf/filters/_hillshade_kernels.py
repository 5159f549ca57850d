"""Numba kernels of :mod:`sciviz_gbuf.filters.hillshade` (GDAL gdaldem_lib.cpp formulas).

Two statements of one method:

- :func:`_pixel` is GDAL's per-cell computation, in float64, with the ``-compute_edges``
  window (extrapolated borders, the centre value for a nodata neighbour). It is the reference
  (:func:`hillshade_reference_kernel`, every cell through it) and the fast kernel's answer for
  the cells it does not take: the first and last row and column, and every cell whose 3 x 3
  window holds nodata.
- :func:`_hillshade_rows` takes each inner row in one branch-free float32 loop (the 3 x 3
  gradient as weighted differences, the variant's shade formula with selects instead of
  branches; ``atan`` by Cephes' float32 polynomial), which LLVM vectorises: about
  20 x the per-cell loop. A nodata cell in the window makes the cell's float32 value NaN
  (NaN propagates; a nodata centre is folded in as ``+ (c - c)``), and such cells are done
  again by :func:`_pixel`. The two agree to float32 rounding (a few 1e-7 of the shade's
  range): GDAL's Byte output, ``round(1 + 254 shade)``, differs only where the float64
  value lies within that of a rounding boundary.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["atan_pos", "fill_ring_kernel", "hillshade_kernel", "hillshade_reference_kernel"]

_INV_SQUARE_OF_HALF_PI = 1.0 / ((math.pi * math.pi) / 4.0)


@njit(cache=True, inline="always")
def _extrapolate(a: float, b: float) -> float:
    """GDAL's ``INTERPOL(a, b)``: the cell beyond ``a``, away from ``b``, 2 a - b; NaN stays NaN."""
    return np.float32(2.0) * a - b


@njit(cache=True)
def _window(z: np.ndarray, i: int, j: int) -> tuple:
    """The 3x3 window (row-major, 0 = north-west) GDAL builds for cell (i, j) with -compute_edges.

    First/last row: the missing row is extrapolated vertically and missing columns repeat the centre
    column; other rows: a missing column is extrapolated horizontally. Nodata (NaN) neighbours,
    including extrapolations from nodata, are replaced by the centre value (+-inf is nodata too,
    so the caller need not look for it first).
    """
    h, w = z.shape
    if i == 0 or i == h - 1:
        jm = max(j - 1, 0)
        jp = min(j + 1, w - 1)
        if i == 0:
            a0, a1, a2 = z[0, jm], z[0, j], z[0, jp]
            b0, b1, b2 = z[1, jm], z[1, j], z[1, jp]
            w0, w1, w2 = _extrapolate(a0, b0), _extrapolate(a1, b1), _extrapolate(a2, b2)
            w3, w4, w5 = a0, a1, a2
            w6, w7, w8 = b0, b1, b2
        else:
            a0, a1, a2 = z[h - 2, jm], z[h - 2, j], z[h - 2, jp]
            b0, b1, b2 = z[h - 1, jm], z[h - 1, j], z[h - 1, jp]
            w0, w1, w2 = a0, a1, a2
            w3, w4, w5 = b0, b1, b2
            w6, w7, w8 = _extrapolate(b0, a0), _extrapolate(b1, a1), _extrapolate(b2, a2)
    else:
        w1, w4, w7 = z[i - 1, j], z[i, j], z[i + 1, j]
        if j == 0:
            w0 = _extrapolate(z[i - 1, 0], z[i - 1, 1])
            w3 = _extrapolate(z[i, 0], z[i, 1])
            w6 = _extrapolate(z[i + 1, 0], z[i + 1, 1])
        else:
            w0, w3, w6 = z[i - 1, j - 1], z[i, j - 1], z[i + 1, j - 1]
        if j == w - 1:
            w2 = _extrapolate(z[i - 1, j], z[i - 1, j - 1])
            w5 = _extrapolate(z[i, j], z[i, j - 1])
            w8 = _extrapolate(z[i + 1, j], z[i + 1, j - 1])
        else:
            w2, w5, w8 = z[i - 1, j + 1], z[i, j + 1], z[i + 1, j + 1]
    c = w4
    w0 = c if not np.isfinite(w0) else w0
    w1 = c if not np.isfinite(w1) else w1
    w2 = c if not np.isfinite(w2) else w2
    w3 = c if not np.isfinite(w3) else w3
    w5 = c if not np.isfinite(w5) else w5
    w6 = c if not np.isfinite(w6) else w6
    w7 = c if not np.isfinite(w7) else w7
    w8 = c if not np.isfinite(w8) else w8
    return w0, w1, w2, w3, w4, w5, w6, w7, w8


@njit(cache=True)
def _difference_between_angles(a1: float, a2: float) -> float:
    """GDAL's ``DifferenceBetweenAngles(a1, a2, 2 pi)``: unsigned angular distance in [0, pi]."""
    two_pi = 2.0 * math.pi
    n1 = np.fmod(a1, two_pi)
    if n1 < 0.0:
        n1 += two_pi
    n2 = np.fmod(a2, two_pi)
    if n2 < 0.0:
        n2 += two_pi
    diff = abs(n1 - n2)
    if diff > math.pi:
        diff = two_pi - diff
    return diff


@njit(cache=True, error_model="numpy")
def _pixel(
    z: np.ndarray, i: int, j: int, inv_ew: float, inv_ns: float, z_factor: float,
    azimuth: float, altitude: float, algorithm: int, variant: int,
) -> float:  # fmt: skip
    """GDAL's shade of cell (i, j), in float64 (NaN at a nodata cell), unclamped."""
    if not np.isfinite(z[i, j]):
        return np.nan
    zf = z_factor / (2.0 if algorithm == 1 else 8.0)
    sin_alt = math.sin(math.radians(altitude))
    cos_alt_z = math.cos(math.radians(altitude)) * zf
    az = math.radians(azimuth)
    w0, w1, w2, w3, _, w5, w6, w7, w8 = _window(z, i, j)
    if algorithm == 0:  # Horn (1981)
        gx = np.float64((w0 + w3 + w3 + w6) - (w2 + w5 + w5 + w8))
        gy = np.float64((w6 + w7 + w7 + w8) - (w0 + w1 + w1 + w2))
    else:  # Zevenbergen & Thorne (1987)
        gx = np.float64(w3 - w5)
        gy = np.float64(w7 - w1)
    x = gx * inv_ew
    y = gy * inv_ns
    xx_plus_yy = x * x + y * y
    if variant == 3:  # -igor
        slope_strength = math.degrees(math.atan(math.sqrt(xx_plus_yy) * zf)) / 90.0
        aspect = math.atan2(gy, gx)  # GDAL: atan2(dy, -dx) with dx = -gx, no resolution
        diff = _difference_between_angles(aspect, 1.5 * math.pi - az)
        return 1.0 - slope_strength * (1.0 - diff / math.pi)
    if variant == 2:  # -multidirectional (Mark 1992)
        if xx_plus_yy == 0.0:
            return sin_alt
        diag_c = math.cos(math.radians(225.0)) * cos_alt_z
        v225 = max(sin_alt + (x - y) * diag_c, 0.0)
        v270 = max(sin_alt - x * cos_alt_z, 0.0)
        v315 = max(sin_alt + (x + y) * diag_c, 0.0)
        v360 = max(sin_alt - y * cos_alt_z, 0.0)
        w225 = 0.5 * xx_plus_yy - x * y
        w315 = xx_plus_yy - w225
        num = w225 * v225 + x * x * v270 + w315 * v315 + y * y * v360
        return 0.5 * num / xx_plus_yy / math.sqrt(1.0 + zf * zf * xx_plus_yy)
    slope = zf * zf * xx_plus_yy
    cang = (sin_alt - (y * math.cos(az) - x * math.sin(az)) * cos_alt_z) / math.sqrt(1.0 + slope)
    if variant == 1:  # -combined
        ang = math.acos(min(max(cang, -1.0), 1.0))
        return 1.0 - ang * math.atan(math.sqrt(slope)) * _INV_SQUARE_OF_HALF_PI
    return cang


def hillshade_reference_kernel(
    z: np.ndarray, inv_ew: float, inv_ns: float, z_factor: float, azimuth: float,
    altitude: float, algorithm: int, variant: int,
) -> np.ndarray:  # fmt: skip
    """Every cell by :func:`_pixel`: the plain statement the fast kernel is tested against."""
    h, w = z.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    if h >= 2 and w >= 2:
        run_bands(_reference_rows, h, z, inv_ew, inv_ns, z_factor, azimuth, altitude,
                  algorithm, variant, out)  # fmt: skip
    return out


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _reference_rows(i0, i1, z, inv_ew, inv_ns, z_factor, azimuth, altitude, algorithm,
                    variant, out) -> None:  # fmt: skip
    for i in range(i0, i1):
        for j in range(z.shape[1]):
            s = _pixel(z, i, j, inv_ew, inv_ns, z_factor, azimuth, altitude, algorithm, variant)
            out[i, j] = min(max(s, 0.0), 1.0) if not np.isnan(s) else np.nan


def hillshade_kernel(
    z: np.ndarray,
    inv_ew: float,
    inv_ns: float,
    z_factor: float,
    azimuth: float,
    altitude: float,
    algorithm: int,
    variant: int,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """The shade of every cell of ``z`` (C-contiguous float32, NaN nodata) into ``out`` (a new
    array if None; C-contiguous float32 of ``z``'s shape, not overlapping it), returned."""
    h, w = z.shape
    if out is None:
        out = np.empty((h, w), dtype=np.float32)
    if h < 2 or w < 2:
        out.fill(np.nan)  # GDAL writes nodata everywhere: no 3x3 neighbourhood to extrapolate
        return out
    run_bands(
        _hillshade_rows, h, z, inv_ew, inv_ns, z_factor, azimuth, altitude, algorithm, variant,
        out,
    )  # fmt: skip
    return out


# Cephes' atanf (single precision, relative error ~1e-7), branch-free: the range reduction
# by selects, so that the loops calling it vectorise.
_TP8 = 0.4142135623730950  # tan(pi / 8)


@njit(cache=True, inline="always", error_model="numpy")
def _atan_ratio(lo: np.float32, hi: np.float32) -> np.float32:
    """atan(lo / hi) for 0 <= lo <= hi (0 where hi is 0), float32, with one division: Cephes'
    reduction by pi/4 above tan(pi/8) folded into the quotient, (lo - hi) / (lo + hi)."""
    mid = lo > np.float32(_TP8) * hi
    num = lo - hi if mid else lo
    den = lo + hi if mid else hi
    x = num / den if den > np.float32(0) else np.float32(0)
    zz = x * x
    p = np.float32(8.05374449538e-2) * zz - np.float32(1.38776856032e-1)
    p = p * zz + np.float32(1.99777106478e-1)
    p = p * zz - np.float32(3.33329491539e-1)
    base = np.float32(math.pi / 4) if mid else np.float32(0)
    return base + p * zz * x + x


@njit(cache=True, inline="always", error_model="numpy")
def atan_pos(t: np.float32) -> np.float32:
    """atan(t) for t >= 0 (inf included), float32: atan(1/t) = pi/2 - atan(t) above 1."""
    one = np.float32(1)
    r = _atan_ratio(min(t, one), max(t, one))
    return np.float32(math.pi / 2) - r if t > one else r


@njit(cache=True, inline="always")
def _gradient(zn: np.ndarray, zc: np.ndarray, zs: np.ndarray, j: int, cw: np.float32) -> tuple:
    """GDAL's 3x3 gradient sums at column ``j`` of the rows north, centre and south, in its
    order of float32 additions: Horn (``cw`` = 1) or Zevenbergen & Thorne (0: its terms drop
    out exactly)."""
    gx = (cw * zn[j - 1] + zc[j - 1] + cw * zc[j - 1] + cw * zs[j - 1]) - (
        cw * zn[j + 1] + zc[j + 1] + cw * zc[j + 1] + cw * zs[j + 1]
    )
    gy = (cw * zs[j - 1] + zs[j] + cw * zs[j] + cw * zs[j + 1]) - (
        cw * zn[j - 1] + zn[j] + cw * zn[j] + cw * zn[j + 1]
    )
    return gx, gy


@njit(cache=True, inline="always")
def _clamp01(s: np.float32) -> np.float32:
    """``s`` clamped to [0, 1], NaN kept (``min``/``max`` may drop it)."""
    return np.float32(0) if s < np.float32(0) else (np.float32(1) if s > np.float32(1) else s)


@njit(cache=True, inline="always", error_model="numpy")
def _angle(y: np.float32, x: np.float32) -> np.float32:
    """atan2(y, x) for y >= 0, in [0, pi], float32 (0 at (0, 0), as libm)."""
    ax = abs(x)
    r = _atan_ratio(min(ax, y), max(ax, y))
    r = np.float32(math.pi / 2) - r if y > ax else r
    return np.float32(math.pi) - r if x < np.float32(0) else r


# The -combined and -igor rows: two arctangents a cell, compute-bound, so their loops may
# contract a * b + c into fused multiply-adds (the gradient sums stay GDAL's: their products
# are by 1 or 0, exact either way; the shade moves by float32 rounding, ~1e-7).
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy", fastmath={"contract"})
def _combined_row(
    zn: np.ndarray, zc: np.ndarray, zs: np.ndarray, o: np.ndarray, cw: np.float32,
    ex: np.float32, ny: np.float32, sq: np.float32, sa: np.float32, ca: np.float32,
    cu: np.float32, su: np.float32, inv_sq_half_pi: np.float32,
) -> bool:  # fmt: skip
    """Inner cells of one row of ``-combined`` into ``o``; True if one of them is NaN.

    GDAL's ``acos(cang)`` with ``cang = (sin alt - cos alt u) / sqrt(1 + u^2 + v^2)`` (``u``,
    ``v`` the scaled gradient along and across the light) is the angle between the light and
    the normal, ``atan2(sqrt((cos alt + sin alt u)^2 + v^2), sin alt - cos alt u)``: the same
    angle without a cancelling ``1 - cang^2``, one division and one root fewer."""
    f1 = np.float32(1.0)
    bad = False
    for j in range(1, o.shape[0] - 1):
        gx, gy = _gradient(zn, zc, zs, j, cw)
        x = gx * ex
        y = gy * ny
        slope = sq * (x * x + y * y)
        u = y * cu - x * su
        v = y * su + x * cu
        m = ca + sa * u
        ang = _angle(np.sqrt(m * m + v * v), sa - ca * u)
        s = f1 - ang * atan_pos(np.sqrt(slope)) * inv_sq_half_pi
        # NaN where the centre is nodata or the gradient overflowed: the float64 path
        s = s + (zc[j] - zc[j]) + (slope - slope)
        bad |= s != s
        o[j] = _clamp01(s)
    return bad


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy", fastmath={"contract"})
def _igor_row(
    zn: np.ndarray, zc: np.ndarray, zs: np.ndarray, o: np.ndarray, cw: np.float32,
    ex: np.float32, ny: np.float32, zf32: np.float32, ax: np.float32, ay: np.float32,
    deg_per_90: np.float32, inv_pi: np.float32,
) -> bool:  # fmt: skip
    """Inner cells of one row of ``-igor`` into ``o``; True if one of them is NaN. The
    difference between the aspect ``atan2(gy, gx)`` and ``1.5 pi - az`` is the angle between
    the gradient and the unit vector ``(ax, ay)`` there: one arctangent of the cross and dot
    products (no fold of the angles into [0, pi])."""
    f1 = np.float32(1.0)
    bad = False
    for j in range(1, o.shape[0] - 1):
        gx, gy = _gradient(zn, zc, zs, j, cw)
        x = gx * ex
        y = gy * ny
        xx = x * x + y * y
        strength = atan_pos(np.sqrt(xx) * zf32) * deg_per_90
        diff = _angle(abs(gx * ay - gy * ax), gx * ax + gy * ay)
        s = f1 - strength * (f1 - diff * inv_pi)
        # xx is inf or NaN wherever gx or gy is
        s = s + (zc[j] - zc[j]) + (xx - xx)
        bad |= s != s
        o[j] = _clamp01(s)
    return bad


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _hillshade_rows(
    i0: int,
    i1: int,
    z: np.ndarray,
    inv_ew: float,
    inv_ns: float,
    z_factor: float,
    azimuth: float,
    altitude: float,
    algorithm: int,
    variant: int,
    out: np.ndarray,
) -> None:
    """Rows ``i0 .. i1`` of :func:`hillshade_kernel` into ``out`` (one band of
    :func:`.run_bands`; needs at least 2 x 2 cells)."""
    h, w = z.shape
    f0 = np.float32(0.0)
    f1 = np.float32(1.0)
    # Horn: gx = (nw + w + w + sw) - (ne + e + e + se); Zevenbergen & Thorne: w - e. One
    # loop for both, in GDAL's order of float32 additions (so gx and gy are GDAL's bit for
    # bit): the terms only Horn has are weighted by cw, 1 or 0, exact either way (0 * NaN is
    # NaN: a nodata corner still sends the cell to the per-cell path, which is right).
    cw = np.float32(1.0) if algorithm == 0 else np.float32(0.0)
    zf = z_factor / (2.0 if algorithm == 1 else 8.0)
    ex = np.float32(inv_ew)
    ny = np.float32(inv_ns)
    sin_alt = math.sin(math.radians(altitude))
    cos_alt_z = math.cos(math.radians(altitude)) * zf
    az = math.radians(azimuth)
    sa = np.float32(sin_alt)
    cc = np.float32(math.cos(az) * cos_alt_z)
    sc = np.float32(math.sin(az) * cos_alt_z)
    caz = np.float32(cos_alt_z)
    dc = np.float32(math.cos(math.radians(225.0)) * cos_alt_z)
    sq = np.float32(zf * zf)
    zf32 = np.float32(zf)
    half = np.float32(0.5)
    # -combined: the light's altitude and the gradient's components along and across it
    ca = np.float32(math.cos(math.radians(altitude)))
    cu = np.float32(math.cos(az) * zf)
    su = np.float32(math.sin(az) * zf)
    # -igor: GDAL's DifferenceBetweenAngles(aspect, 1.5 pi - az), the angle between the
    # gradient and the unit vector (ax, ay) at 1.5 pi - az
    ax = np.float32(math.cos(1.5 * math.pi - az))
    ay = np.float32(math.sin(1.5 * math.pi - az))
    inv_pi = np.float32(1.0 / math.pi)
    deg_per_90 = np.float32(180.0 / math.pi / 90.0)
    inv_sq_half_pi = np.float32(_INV_SQUARE_OF_HALF_PI)
    for i in range(i0, i1):
        o = out[i]
        if i == 0 or i == h - 1 or w < 3:
            for j in range(w):
                s = _pixel(z, i, j, inv_ew, inv_ns, z_factor, azimuth, altitude, algorithm,
                           variant)  # fmt: skip
                o[j] = min(max(s, 0.0), 1.0) if not np.isnan(s) else np.nan
            continue
        zn = z[i - 1]
        zc = z[i]
        zs = z[i + 1]
        bad = False
        if variant == 0:
            for j in range(1, w - 1):
                gx, gy = _gradient(zn, zc, zs, j, cw)
                x = gx * ex
                y = gy * ny
                slope = sq * (x * x + y * y)
                # + (slope - slope): NaN where float32 overflowed (inf), for the float64 path
                s = (sa - (y * cc - x * sc)) / np.sqrt(f1 + slope)
                s = s + (zc[j] - zc[j]) + (slope - slope)
                bad |= s != s
                o[j] = _clamp01(s)
        elif variant == 1:  # -combined
            bad = _combined_row(zn, zc, zs, o, cw, ex, ny, sq, sa, ca, cu, su, inv_sq_half_pi)
        elif variant == 2:  # -multidirectional (Mark 1992)
            for j in range(1, w - 1):
                gx, gy = _gradient(zn, zc, zs, j, cw)
                x = gx * ex
                y = gy * ny
                xx = x * x + y * y
                v225 = max(sa + (x - y) * dc, f0)
                v270 = max(sa - x * caz, f0)
                v315 = max(sa + (x + y) * dc, f0)
                v360 = max(sa - y * caz, f0)
                w225 = half * xx - x * y
                w315 = xx - w225
                num = w225 * v225 + x * x * v270 + w315 * v315 + y * y * v360
                safe = xx if xx > f0 else f1
                s = half * num / safe / np.sqrt(f1 + sq * xx)
                s = (s if xx > f0 else sa) + (zc[j] - zc[j]) + (xx - xx) + (num - num)
                bad |= s != s
                o[j] = _clamp01(s)
        else:  # -igor
            bad = _igor_row(zn, zc, zs, o, cw, ex, ny, zf32, ax, ay, deg_per_90, inv_pi)
        for j in (0, w - 1):
            s = _pixel(z, i, j, inv_ew, inv_ns, z_factor, azimuth, altitude, algorithm, variant)
            o[j] = min(max(s, 0.0), 1.0) if not np.isnan(s) else np.nan
        if bad:  # nodata in a window: those cells by the per-cell statement
            for j in range(1, w - 1):
                if o[j] != o[j]:
                    s = _pixel(z, i, j, inv_ew, inv_ns, z_factor, azimuth, altitude,
                               algorithm, variant)  # fmt: skip
                    o[j] = min(max(s, 0.0), 1.0) if not np.isnan(s) else np.nan


def fill_ring_kernel(z: np.ndarray, out: np.ndarray) -> None:
    run_bands(_fill_ring_rows, z.shape[0], z, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _fill_ring_rows(i0: int, i1: int, z: np.ndarray, out: np.ndarray) -> None:
    """Rows ``i0 .. i1`` of :func:`fill_ring_kernel` (one band of :func:`.run_bands`)."""
    h, w = z.shape
    for i in range(i0, i1):
        for j in range(w):
            v = z[i, j]
            out[i, j] = v
            if not np.isnan(v):
                continue
            total = 0.0
            count = 0
            near = 0.0
            n_near = 0
            for di in range(-1, 2):
                for dj in range(-1, 2):
                    if di == 0 and dj == 0:
                        continue
                    i1, j1 = i + di, j + dj
                    if i1 < 0 or i1 >= h or j1 < 0 or j1 >= w or np.isnan(z[i1, j1]):
                        continue
                    a = np.float64(z[i1, j1])
                    near += a
                    n_near += 1
                    i2, j2 = i1 + di, j1 + dj
                    if 0 <= i2 < h and 0 <= j2 < w and not np.isnan(z[i2, j2]):
                        total += 2.0 * a - z[i2, j2]
                        count += 1
            if count > 0:
                out[i, j] = total / count
            elif n_near > 0:
                out[i, j] = near / n_near
