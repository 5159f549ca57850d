"""Contour polylines for GIS: the vector counterpart of :func:`.contour_lines`.

The raster lines of :func:`.contour_lines` are what a map needs on screen; a GIS needs the lines
themselves. These are traced with marching squares (:func:`skimage.measure.find_contours`) at
the same levels, so the two agree: both put a level where the field crosses it, interpolated
linearly between pixel centres.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from skimage import measure

from .. import _validate
from ..errors import InputError

__all__ = ["ContourPolyline", "contour_polylines", "polylines_to_geojson"]

#: Most levels one call traces (``interval=`` or ``levels=``): ``LIMITS["levels"]``.
MAX_LEVELS = int(_validate.LIMITS["levels"])


class ContourPolyline(NamedTuple):
    """One traced contour line."""

    level: float
    """The field value along the line."""
    major: bool
    """True for a level of the major family (``major_interval``)."""
    points: np.ndarray
    """(N, 2) float64 ``(x, y)``: pixel coordinates (column, row; pixel centres at integers,
    row 0 at the top) or, with a ``transform``, map coordinates."""
    closed: bool
    """True if the first and last point coincide (a ring)."""


def _regular_levels(values: np.ndarray, interval: float, base: float) -> np.ndarray:
    lo, hi = float(values.min()), float(values.max())
    n0, n1 = np.ceil((lo - base) / interval), np.floor((hi - base) / interval)
    if n1 - n0 + 1 > MAX_LEVELS:
        raise InputError(
            f"interval: {interval!r} gives {int(n1 - n0 + 1)} levels over the field's range "
            f"[{lo:g}, {hi:g}]; expected at most {MAX_LEVELS}"
        )
    return base + np.arange(n0, n1 + 1) * interval


def _apply_transform(xy: np.ndarray, transform: Sequence[float] | None) -> np.ndarray:
    if transform is None:
        return xy
    x0, dx, rx, y0, ry, dy = transform
    # GDAL geotransform: pixel (col, row) has its corner at (col, row), its centre at + 0.5.
    c, r = xy[:, 0] + 0.5, xy[:, 1] + 0.5
    return np.column_stack([x0 + c * dx + r * rx, y0 + c * ry + r * dy])


def contour_polylines(
    field: np.ndarray,
    *,
    interval: float | None = None,
    levels: Sequence[float] | np.ndarray | None = None,
    base: float = 0.0,
    mask: np.ndarray | None = None,
    major_interval: float | None = None,
    transform: Sequence[float] | None = None,
) -> list[ContourPolyline]:
    """Trace the contour lines of a scalar image as polylines with their level attributes.

    Parameters
    ----------
    field : (H, W) array
        The scalar image; NaN and inf are treated as masked (DEM nodata).
    interval, levels, base, major_interval
        As in :func:`sciviz_gbuf.filters.contour_lines`: levels ``base + n * interval``
        within the field's range, or the explicit ``levels``; lines at multiples of
        ``major_interval`` (from ``base``) are flagged ``major``. At most
        ``LIMITS["levels"]`` = 100000 levels either way (:data:`MAX_LEVELS`).
    mask : (H, W) bool, optional
        Coverage; lines are traced only between covered, finite pixels.
    transform : 6 floats, optional
        A GDAL geotransform ``(x0, dx, rx, y0, ry, dy)`` mapping pixel corners to map
        coordinates; the points are then map coordinates of the traced positions.

    Returns
    -------
    list of ContourPolyline
        Sorted by level; within a level in tracing order.
    """
    if (interval is None) == (levels is None):
        raise InputError("contour_polylines: give exactly one of interval= or levels=")
    s = _validate.image(field, "field")
    m = _validate.mask(mask, s.shape)
    valid = np.isfinite(s) if m is None else np.isfinite(s) & m
    if transform is not None:
        try:
            transform = tuple(float(v) for v in transform)
        except (TypeError, ValueError, OverflowError):
            transform = (np.nan,)
        if len(transform) != 6 or not all(np.isfinite(transform)):
            raise InputError(f"transform: expected 6 finite numbers, got {transform!r}")
    base = _validate.finite(base, "base")
    # explicit levels are counted (LIMITS["levels"]) before anything is traced
    q = None if interval is None else _validate.positive(interval, "interval")
    lv = None if levels is None else _validate.levels(levels)
    major = None if major_interval is None else _validate.positive(major_interval, "major_interval")
    if not valid.any():
        return []
    if q is not None:
        lv = _regular_levels(s[valid], q, base)
    # find_contours must not see NaN: fill it (the mask keeps the fill out of every line).
    filled = np.where(valid, s, np.float32(s[valid].min()))
    out = []
    for level in lv:
        is_major = major is not None and bool(
            np.isclose((level - base) / major, np.round((level - base) / major), atol=1e-6)
        )
        for rc in measure.find_contours(filled, float(level), mask=valid):
            xy = _apply_transform(rc[:, ::-1].astype(np.float64), transform)
            closed = bool(len(rc) > 2 and np.array_equal(rc[0], rc[-1]))
            out.append(ContourPolyline(float(level), is_major, xy, closed))
    return out


def polylines_to_geojson(
    lines: Sequence[ContourPolyline], *, crs: str | None = None
) -> dict[str, Any]:
    """A GeoJSON FeatureCollection of LineStrings with ``level`` and ``major`` properties.

    ``crs`` (e.g. ``"EPSG:32613"``) is recorded as a legacy named-CRS member; GeoJSON (RFC
    7946) otherwise means WGS 84 longitude/latitude.
    """
    features = [
        {
            "type": "Feature",
            "geometry": {"type": "LineString", "coordinates": line.points.tolist()},
            "properties": {"level": line.level, "major": line.major, "closed": line.closed},
        }
        for line in lines
    ]
    fc: dict[str, Any] = {"type": "FeatureCollection", "features": features}
    if crs is not None:
        fc["crs"] = {"type": "name", "properties": {"name": str(crs)}}
    return fc
