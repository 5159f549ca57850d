"""GDAL-compatible relief shading of a height grid (Saito & Takahashi 1990 §4.3, topographic maps).

A re-implementation of ``gdaldem hillshade -compute_edges`` (GDAL ``apps/gdaldem_lib.cpp``): the
same gradient operators, shade formulas, border extrapolation and nodata substitution, so that
``round(1 + 254 * hillshade(...))`` is GDAL's Byte output (``round(255 * ...)`` for ``-igor``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .. import _dask as _chunks
from ..errors import InputError

__all__ = ["hillshade"]

#: Cells read around each output cell (GDAL's 3x3 window), for chunked evaluation.
RADIUS = 1

_ALGORITHMS = {"horn": 0, "zevenbergen_thorne": 1}
_VARIANTS = {"regular": 0, "combined": 1, "multidirectional": 2, "igor": 3}
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


@njit(parallel=True, cache=True)
def _hillshade_kernel(
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
    zf = z_factor / (2.0 if algorithm == 1 else 8.0)
    sin_alt = math.sin(math.radians(altitude))
    cos_alt_z = math.cos(math.radians(altitude)) * zf
    az = math.radians(azimuth)
    cos_az_c = math.cos(az) * cos_alt_z
    sin_az_c = math.sin(az) * cos_alt_z
    square_z = zf * zf
    diag_c = math.cos(math.radians(225.0)) * cos_alt_z
    for i in prange(h):
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
    return out


def check_grid(heights: np.ndarray, dx: float, dy: float, z_factor: float) -> np.ndarray:
    """The checks every terrain operator makes: a 2-D real ``heights`` array (returned as an
    array), finite cell sizes ``dx``, ``dy`` > 0, a finite ``z_factor``."""
    z = np.asarray(heights)
    if z.ndim != 2:
        raise InputError(f"heights: expected a 2-D (H, W) array, got shape {z.shape}")
    if not np.issubdtype(z.dtype, np.number) or np.issubdtype(z.dtype, np.complexfloating):
        raise InputError(f"heights: expected real numbers, got dtype {z.dtype}")
    for name, value in (("dx", dx), ("dy", dy)):
        if not (math.isfinite(float(value)) and float(value) > 0.0):
            raise InputError(f"{name}: expected a finite cell size > 0, got {value!r}")
    if not math.isfinite(float(z_factor)):
        raise InputError(f"z_factor: expected a finite number, got {z_factor!r}")
    return z


def float32_heights(
    z: np.ndarray, mask: np.ndarray | None, *, writable: bool = False
) -> np.ndarray:
    """``z`` as contiguous float32 with NaN at infinities and where ``mask`` is False. The
    input is never modified: float32 input without infinities or mask is returned as it is
    (read-only use) unless ``writable``; anything else is a copy."""
    z32 = np.ascontiguousarray(z, dtype=np.float32)
    infinite = bool(np.isinf(z32).any())
    if (infinite or mask is not None or writable) and (z32 is z or np.shares_memory(z32, z)):
        z32 = z32.copy()
    if infinite:
        np.putmask(z32, np.isinf(z32), np.float32(np.nan))
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        if m.shape != z.shape:
            raise InputError(f"mask: expected shape {z.shape}, got {m.shape}")
        z32[~m] = np.nan
    return z32


def hillshade(
    heights: np.ndarray,
    *,
    dx: float = 1.0,
    dy: float = 1.0,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float = 1.0,
    algorithm: str = "horn",
    variant: str = "regular",
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """Shaded relief of a north-up height grid, equal to ``gdaldem hillshade -compute_edges``.

    Parameters
    ----------
    heights : (H, W) array
        Heights; row 0 is the north edge, column 0 the west edge. NaN and +-inf are nodata.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south, in the units of the heights (metres). For a grid in
        degrees pass ``cellsize * 111120`` (GDAL's ``-s 111120``; GDAL 3.6 does not scale x by
        ``cos(latitude)``, so neither do we: multiply ``dx`` by it yourself if wanted).
    azimuth : float, default: 315
        Direction the light comes from, degrees clockwise from north (315 = north-west). Not used
        by ``variant="multidirectional"``.
    altitude : float in [0, 90], default: 45
        Elevation of the light above the horizon, degrees. Not used by ``variant="igor"``.
    z_factor : float, default: 1
        Vertical exaggeration (GDAL ``-z``, matplotlib's ``vert_exag``).
    algorithm : {"horn", "zevenbergen_thorne"}, default: "horn"
        Gradient operator: Horn's 3x3 weighted differences (smooth, GDAL's default) or
        Zevenbergen & Thorne's central differences (``-alg ZevenbergenThorne``, sharper).
    variant : {"regular", "combined", "multidirectional", "igor"}, default: "regular"
        ``"regular"``: ``max(0, cos)`` of the angle between the light and the surface normal.
        ``"combined"``: GDAL's ``-combined``, shade times slope,
        ``1 - acos(cos) * slope / (pi/2)**2``. ``"multidirectional"``: GDAL's
        ``-multidirectional``, the aspect-weighted mean of lights from 225, 270, 315 and 360
        degrees (Mark 1992). ``"igor"``: GDAL's ``-igor``,
        ``1 - slope/90 * (1 - |aspect - az|/180)``, which never darkens flat ground.
    mask : (H, W) bool, optional
        False marks nodata cells, like NaN heights.

    Returns
    -------
    (H, W) float32 in [0, 1]
        1 is fully lit; NaN at nodata cells (and everywhere if H < 2 or W < 2, as GDAL). GDAL's
        Byte output is ``round(1 + 254 * shade)`` (``round(255 * shade)`` for ``"igor"``).
        Next to nodata and at the borders, missing neighbours are handled as GDAL's
        ``-compute_edges``: border rows/columns are linearly extrapolated (2 a - b) and nodata
        neighbours take the centre cell's height.

    Raises
    ------
    InputError
        ``heights`` not 2-D or ``mask`` of another shape; ``dx``/``dy`` not finite and positive;
        ``altitude`` outside [0, 90]; non-finite ``azimuth``/``z_factor``; unknown ``algorithm`` or
        ``variant``.

    References
    ----------
    .. [1] Horn, B. K. P. (1981). Hill shading and the reflectance map. Proceedings of the IEEE
       69(1), 14-47.
    .. [2] Zevenbergen, L. W. & Thorne, C. R. (1987). Quantitative analysis of land surface
       topography. Earth Surface Processes and Landforms 12(1), 47-56.
    .. [3] Mark, R. K. (1992). Multidirectional, oblique-weighted, shaded-relief image of the
       Island of Hawaii. U.S. Geological Survey Open-File Report 92-422.
    .. [4] GDAL, gdaldem: https://gdal.org/programs/gdaldem.html and ``apps/gdaldem_lib.cpp``.
    .. [5] Saito, T. & Takahashi, T. (1990). Comprehensible rendering of 3-D shapes. SIGGRAPH '90,
       197-206, §4.3.
    """
    if _chunks.any_dask(heights, mask):
        return _chunks.map_stencil(
            hillshade,
            {"heights": heights, "mask": mask},
            halo=RADIUS,
            dx=dx,
            dy=dy,
            azimuth=azimuth,
            altitude=altitude,
            z_factor=z_factor,
            algorithm=algorithm,
            variant=variant,
        )
    z = check_grid(heights, dx, dy, z_factor)
    if not 0.0 <= float(altitude) <= 90.0:
        raise InputError(f"altitude: expected degrees in [0, 90], got {altitude!r}")
    if not math.isfinite(float(azimuth)):
        raise InputError(f"azimuth: expected a finite number, got {azimuth!r}")
    if algorithm not in _ALGORITHMS:
        raise InputError(f"algorithm: expected one of {sorted(_ALGORITHMS)}, got {algorithm!r}")
    if variant not in _VARIANTS:
        raise InputError(f"variant: expected one of {sorted(_VARIANTS)}, got {variant!r}")
    z32 = float32_heights(z, mask)  # the kernel only reads it
    # GDAL: inv_ewres = 1 / geotransform[1], inv_nsres = 1 / geotransform[5] (negative: north-up).
    return _hillshade_kernel(
        z32,
        1.0 / float(dx),
        -1.0 / float(dy),
        float(z_factor),
        float(azimuth),
        float(altitude),
        _ALGORITHMS[algorithm],
        _VARIANTS[variant],
    )
