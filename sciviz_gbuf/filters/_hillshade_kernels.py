"""Numba kernels of :mod:`sciviz_gbuf.filters.hillshade` (GDAL gdaldem_lib.cpp formulas)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.bands import run_bands

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
    including extrapolations from nodata, are replaced by the centre value.
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
    w0 = c if np.isnan(w0) else w0
    w1 = c if np.isnan(w1) else w1
    w2 = c if np.isnan(w2) else w2
    w3 = c if np.isnan(w3) else w3
    w5 = c if np.isnan(w5) else w5
    w6 = c if np.isnan(w6) else w6
    w7 = c if np.isnan(w7) else w7
    w8 = c if np.isnan(w8) else w8
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


def hillshade_kernel(
    z: np.ndarray,
    inv_ew: float,
    inv_ns: float,
    z_factor: float,
    azimuth: float,
    altitude: float,
    algorithm: int,
    variant: int,
) -> np.ndarray:
    h, w = z.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    if h < 2 or w < 2:
        return out  # GDAL writes nodata everywhere: there is no 3x3 neighbourhood to extrapolate
    run_bands(
        _hillshade_rows, h, z, inv_ew, inv_ns, z_factor, azimuth, altitude, algorithm, variant,
        out,
    )  # fmt: skip
    return out


# error_model="numpy" in the band kernels, as numba compiled the prange loop bodies they
# replace: a division by zero gives inf / NaN, it does not raise.
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
    w = z.shape[1]
    zf = z_factor / (2.0 if algorithm == 1 else 8.0)
    sin_alt = math.sin(math.radians(altitude))
    cos_alt_z = math.cos(math.radians(altitude)) * zf
    az = math.radians(azimuth)
    cos_az_c = math.cos(az) * cos_alt_z
    sin_az_c = math.sin(az) * cos_alt_z
    square_z = zf * zf
    diag_c = math.cos(math.radians(225.0)) * cos_alt_z
    for i in range(i0, i1):
        for j in range(w):
            if np.isnan(z[i, j]):
                continue
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
                shade = 1.0 - slope_strength * (1.0 - diff / math.pi)
            elif variant == 2:  # -multidirectional (Mark 1992)
                if xx_plus_yy == 0.0:
                    shade = sin_alt
                else:
                    v225 = max(sin_alt + (x - y) * diag_c, 0.0)
                    v270 = max(sin_alt - x * cos_alt_z, 0.0)
                    v315 = max(sin_alt + (x + y) * diag_c, 0.0)
                    v360 = max(sin_alt - y * cos_alt_z, 0.0)
                    w225 = 0.5 * xx_plus_yy - x * y
                    w315 = xx_plus_yy - w225
                    num = w225 * v225 + x * x * v270 + w315 * v315 + y * y * v360
                    shade = 0.5 * num / xx_plus_yy / math.sqrt(1.0 + square_z * xx_plus_yy)
            else:
                slope = square_z * xx_plus_yy
                cang = (sin_alt - (y * cos_az_c - x * sin_az_c)) / math.sqrt(1.0 + slope)
                if variant == 1:  # -combined
                    ang = math.acos(min(max(cang, -1.0), 1.0))
                    shade = 1.0 - ang * math.atan(math.sqrt(slope)) * _INV_SQUARE_OF_HALF_PI
                else:
                    shade = cang
            out[i, j] = min(max(shade, 0.0), 1.0)


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
