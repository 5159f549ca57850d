"""GDAL-compatible relief shading of a height grid (Saito & Takahashi 1990 §4.3, topographic maps).

A re-implementation of ``gdaldem hillshade -compute_edges`` (GDAL ``apps/gdaldem_lib.cpp``): the
same gradient operators, shade formulas, border extrapolation and nodata substitution, so that
``round(1 + 254 * hillshade(...))`` is GDAL's Byte output (``round(255 * ...)`` for ``-igor``).
"""

from __future__ import annotations

import numpy as np

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from . import _hillshade_kernels as _k

__all__ = ["FILL_RING_RADIUS", "RADIUS", "fill_nodata_ring", "hillshade"]

#: Cells read around each output cell (GDAL's 3x3 window), for chunked evaluation.
RADIUS = 1

#: Cells :func:`fill_nodata_ring` reads around a nodata cell (the extrapolation ``2a - b``).
FILL_RING_RADIUS = 2

_ALGORITHMS = {"horn": 0, "zevenbergen_thorne": 1}
_VARIANTS = {"regular": 0, "combined": 1, "multidirectional": 2, "igor": 3}


def check_grid(heights: np.ndarray, dx: float, dy: float, z_factor: float) -> np.ndarray:
    """The checks every terrain operator makes: a 2-D real ``heights`` array (returned as an
    array), finite cell sizes ``dx``, ``dy`` > 0, a finite ``z_factor``."""
    z = np.asarray(heights)
    if z.ndim != 2:
        raise InputError(f"heights: expected a 2-D (H, W) array, got shape {z.shape}")
    if not np.issubdtype(z.dtype, np.number) or np.issubdtype(z.dtype, np.complexfloating):
        raise InputError(f"heights: expected real numbers, got dtype {z.dtype}")
    for name, value in (("dx", dx), ("dy", dy)):
        if not _validate.finite(value, name) > 0.0:
            raise InputError(f"{name}: expected a finite cell size > 0, got {value!r}")
    _validate.finite(z_factor, "z_factor")
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
    out: np.ndarray | None = None,
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
    out : (H, W) float32 array, optional
        Written with the result and returned (C-contiguous, writeable, not sharing memory with
        ``heights``). For repeated calls on grids of one size: a new array's first touch of
        its memory costs more than the shading itself on some machines.

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
        ``variant``; ``out`` of another shape or dtype, not C-contiguous, read-only or overlapping
        ``heights``; ``out`` with dask input.

    Notes
    -----
    Each inner cell is computed in float32 by a vectorised loop; the border cells and those next
    to nodata by GDAL's per-cell statement in float64. The two agree within 1e-6 of the shade
    (tested), so the Byte output differs from GDAL's at most by one grey level, and that only
    where GDAL's own value lies within 1e-6 of a rounding boundary.

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
        if out is not None:
            raise InputError("out: not supported with dask input (the result is lazy)")
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
    if not 0.0 <= _validate.finite(altitude, "altitude") <= 90.0:
        raise InputError(f"altitude: expected degrees in [0, 90], got {altitude!r}")
    _validate.finite(azimuth, "azimuth")
    algorithm = _validate.choice(algorithm, "algorithm", sorted(_ALGORITHMS))
    variant = _validate.choice(variant, "variant", sorted(_VARIANTS))
    # The kernel only reads it and takes +-inf as nodata itself (a pass looking for
    # infinities first would cost a third of the shading).
    z32 = float32_heights(z, mask) if mask is not None else np.ascontiguousarray(z, np.float32)
    if out is not None:
        out = _validate.out_array(out, z32.shape, heights)
    # GDAL: inv_ewres = 1 / geotransform[1], inv_nsres = 1 / geotransform[5] (negative: north-up).
    return _k.hillshade_kernel(
        z32,
        1.0 / float(dx),
        -1.0 / float(dy),
        float(z_factor),
        float(azimuth),
        float(altitude),
        _ALGORITHMS[algorithm],
        _VARIANTS[variant],
        out,
    )


def fill_nodata_ring(z: np.ndarray) -> np.ndarray:
    """``z`` with each nodata cell next to data replaced by a linear extrapolation of the data.

    Every direction with two valid cells ``a`` (next) and ``b`` (beyond) gives ``2a - b``; their
    mean is exact on a plane, so a 3x3 relief operator sees no step at a nodata border (GDAL's
    rule, the centre value for a missing neighbour, halves the slope there: a bright or dark rim).
    Without such a pair, the mean of the valid neighbours. ``z`` itself when it has no nodata.
    """
    if not np.isnan(z).any():
        return z
    out = np.empty_like(z, dtype=np.float32)
    _k.fill_ring_kernel(np.ascontiguousarray(z, dtype=np.float32), out)
    return out
