"""Contour polylines for GIS: the vector counterpart of :func:`.contour_lines`.

The raster lines of :func:`.contour_lines` are what a map needs on screen; a GIS needs the lines
themselves. These are traced with marching squares (contourpy, matplotlib's C++ contouring,
all levels in one call) at the same levels, so the two agree: both put a level where the field
crosses it, interpolated linearly between pixel centres.

The work and the output grow with the number of cell crossings (a cell is crossed by every
level between its lowest and highest corner), not the number of levels: they are counted
first, from the cells' ranges, and more than ``LIMITS["segments"]`` is refused before anything
is traced.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from .. import _validate
from ..errors import InputError

__all__ = ["ContourPolyline", "contour_polylines", "polylines_to_geojson"]

#: Most levels one call traces (``interval=`` or ``levels=``): ``LIMITS["levels"]``.
MAX_LEVELS = int(_validate.LIMITS["levels"])
#: Most line segments (cell crossings) one call traces: ``LIMITS["segments"]``.
MAX_SEGMENTS = int(_validate.LIMITS["segments"])


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


def _crossings(s: np.ndarray, valid: np.ndarray, levels: np.ndarray) -> int:
    """How many (cell, level) pairs have the level within the cell's range: an upper bound of
    the segments marching squares makes (sorted ``levels``; cells with a nodata corner cross
    nothing)."""
    if min(s.shape) < 2:
        return 0
    corners = (s[:-1, :-1], s[:-1, 1:], s[1:, :-1], s[1:, 1:])
    ok = valid[:-1, :-1] & valid[:-1, 1:] & valid[1:, :-1] & valid[1:, 1:]
    lo = np.minimum(np.minimum(corners[0], corners[1]), np.minimum(corners[2], corners[3]))[ok]
    hi = np.maximum(np.maximum(corners[0], corners[1]), np.maximum(corners[2], corners[3]))[ok]
    first = np.searchsorted(levels, lo, side="left")
    last = np.searchsorted(levels, hi, side="right")
    return int(np.sum(last - first, dtype=np.int64))


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
    lv = np.unique(np.asarray(lv, dtype=np.float64))
    crossings = _crossings(s, valid, lv)
    if crossings > MAX_SEGMENTS:
        raise InputError(
            f"levels: {len(lv)} levels cross the field's cells {crossings} times; expected at "
            f"most {MAX_SEGMENTS} line segments (a coarser interval, fewer levels)"
        )
    import contourpy

    # Masked cells (any corner nodata) are left out whole, as the raster lines leave them.
    z = np.ma.masked_array(np.where(valid, s, 0.0).astype(np.float64), mask=~valid)
    gen = contourpy.contour_generator(
        z=z, name="serial", corner_mask=False, line_type=contourpy.LineType.ChunkCombinedOffset
    )
    if major is None:
        majors = np.zeros(len(lv), bool)
    else:
        n = (lv - base) / major
        majors = np.isclose(n, np.round(n), atol=1e-6)
    # All levels' lines in one array (line k = pts[off[k]:off[k + 1]]): the checks below are
    # then a few array operations, not a few per level (100000 levels are allowed).
    found = [(k, p[0], o[0]) for k, (p, o) in enumerate(gen.multi_lines(lv)) if p[0] is not None]
    if not found:
        return []
    at, parts, offs = zip(*found, strict=True)
    n_points = np.array([len(p) for p in parts], np.int64)
    counts = np.array([len(o) - 1 for o in offs], np.int64)
    base_of = np.repeat(np.cumsum(n_points) - n_points, counts)  # each level's first point
    pts = np.concatenate(parts)
    ends_ = np.concatenate([o[1:] for o in offs]).astype(np.int64) + base_of
    off = np.concatenate(([0], ends_))
    which = np.repeat(np.asarray(at, np.int64), counts)
    starts, ends = off[:-1], off[1:] - 1
    closed = ((ends - starts) > 1) & (pts[starts] == pts[ends]).all(axis=1)
    # a level at a local extremum's own value makes a ring of one point (zero length): dropped
    span = np.maximum.reduceat(pts, starts) - np.minimum.reduceat(pts, starts)
    keep = (span > 0).any(axis=1)
    xy = _apply_transform(pts, transform)
    levels_, majors_ = lv[which].tolist(), majors[which].tolist()
    out = [
        ContourPolyline(levels_[n], majors_[n], xy[a:b], c)
        for n, (a, b, c, k) in enumerate(
            zip(starts.tolist(), off[1:].tolist(), closed.tolist(), keep.tolist(), strict=True)
        )
        if k
    ]
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
