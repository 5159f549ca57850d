"""Maps at any size: the output grid that ``size=``, ``scale=`` and ``dpi=`` ask for, and the DEM
resampled onto it before any map layer is made (shared by the plan-view and bird's-eye maps).

A map is drawn on the grid of its heights, one output pixel per height sample (1990 §4.3: the
DEM grid is the G-buffer). To draw it larger, the heights are first resampled onto the output
grid, so that contour lines (Eq. 9: distance to the level set from the local gradient), relief
and bands are computed per output pixel and come out smooth, with widths in output pixels, and
the relief's pixel size (``dx``, ``dy``) follows the output pixel. To draw it smaller the heights
are area-averaged (anti-aliased) instead of decimated.

The semantics follow GDAL and QGIS:

- ``size=N``: the long side is ``N`` pixels, the other keeps the grid's aspect (``gdal_translate
  -outsize N 0``); ``size=(W, H)``: exactly ``W x H`` over the DEM's extent (pixels may then be
  non-square, as with ``-outsize W H``); ``(W, 0)`` or ``(0, H)`` keep the aspect.
- ``scale=s`` (a number, no ``dpi``): ``s`` output pixels per DEM cell along both axes.
- ``scale=N`` with ``dpi=D``, or ``scale="1:N"`` with ``dpi=D``: the map scale 1:N printed at D
  dots per inch, as in a QGIS print layout: ``N * 0.0254 / D`` metres of ground per output pixel
  (``scale=25000, dpi=300``: 2.117 m), in both directions (so a degree grid, whose cells are
  not square in metres, becomes a map with square pixels).

Sides are rounded to whole pixels and the map always covers the DEM's extent exactly, so the
output pixel is ``extent / side`` (within half a pixel of the asked-for size).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from .. import _validate
from ..errors import InputError
from ..filters import fill_nodata_ring
from ..readers import DEM

__all__ = [
    "INCH",
    "check_size_options",
    "map_grid",
    "map_shape",
    "resample_heights",
    "view_size",
]

#: Metres per inch (the ``dpi`` of a map scale).
INCH = 0.0254
# Bytes per output pixel of a plan-view map while it is made: heights, ink, relief, the RGBA
# composite and the numpy temporaries of the layers (peak measured: 20 bytes per pixel for a
# 4804^2 map of a 1201^2 DEM at scale=4; the rest is room for the optional layers).
_MAP_BYTES_PER_PIXEL = 48
# Output rows per block of the resampling passes: bounds the temporaries to a few blocks.
_BLOCK = 1024


def _size_value(size: object) -> tuple[int, int] | int | None:
    """``size`` checked: None, a long side N, or (W, H) with 0 for 'keep the aspect'."""
    if size is None:
        return None
    if np.ndim(size) == 0:
        return _validate.count(size, "size", "image_side")
    try:
        parts = list(size)  # type: ignore[call-overload]
    except TypeError:
        parts = []
    if len(parts) != 2:
        raise InputError(
            "size: expected a long side N or (width, height) in pixels, "
            f"got {_validate.brief(size)}"
        )
    w, h = (0 if v is None else _validate.count(v, "size", "image_side", low=0) for v in parts)
    if w == 0 and h == 0:
        raise InputError(f"size: expected at least one side > 0, got {_validate.brief(size)}")
    return w, h


def _map_scale(scale: object) -> float | None:
    """The denominator N of a map scale ``"1:N"``, or None if ``scale`` is not such a string."""
    if not isinstance(scale, str):
        return None
    head, _, tail = scale.replace(" ", "").partition(":")
    try:
        n = float(tail) if head == "1" else float("nan")
    except ValueError:
        n = float("nan")
    if not (math.isfinite(n) and n >= 1):
        raise InputError(
            f"scale: expected pixels per cell (a number) or a map scale '1:N' with N >= 1, "
            f"got {scale!r}"
        )
    return n


def check_size_options(
    size: object = None, scale: object = None, dpi: object = None, *, map_scale: bool = True
) -> dict:
    """The size options of a map, checked before anything is read: ``{"size": ...}``,
    ``{"cells": s}`` (pixels per DEM cell), ``{"metres": m}`` (metres per output pixel of a
    map scale) or ``{}`` (one pixel per cell). ``map_scale=False`` (a perspective view, which
    has no single scale) refuses a map scale and ``dpi``.

    Raises
    ------
    InputError
        A bad value, a value beyond its bound (``LIMITS["image_side"]``, ``LIMITS["dpi"]``),
        or a conflicting combination: ``size`` with ``scale``, a map scale without ``dpi``,
        ``dpi`` without a map scale.
    """
    s = _size_value(size)
    if s is not None and scale is not None:
        raise InputError(
            f"scale: expected size= or scale=, not both (size={_validate.brief(size)}, "
            f"scale={_validate.brief(scale)})"
        )
    if dpi is not None:
        if not map_scale:
            raise InputError(
                "dpi: a perspective view has no map scale, so its pixels do not depend on a "
                "print resolution: give size= or scale= (pixels per cell); write_png(dpi=) "
                "records a DPI in the file"
            )
        dpi = _validate.size(dpi, "dpi", "dpi")
        if scale is None:
            raise InputError(
                f"dpi: expected together with a map scale (scale=N or '1:N', printed at "
                f"{dpi:g} dpi); without one the pixels do not depend on dpi (write_png(dpi=) "
                "records it in a PNG)"
            )
    if s is not None:
        return {"size": s}
    if scale is None:
        return {}
    denominator = _map_scale(scale)
    if denominator is None and dpi is not None:
        denominator = _validate.number_in(scale, "scale", 1.0, math.inf)
    if denominator is not None:
        if not map_scale:
            raise InputError(
                f"scale: a map scale {scale!r} applies to plan-view maps; a perspective view "
                "has none: give size= or scale= in pixels per DEM cell"
            )
        if dpi is None:
            raise InputError(
                f"dpi: a map scale {scale!r} needs dpi= (the print resolution) to give a "
                "ground size per pixel"
            )
        return {"metres": denominator * INCH / dpi}
    return {"cells": _validate.positive(scale, "scale")}


def _side(cells: float, name: str, value: object) -> int:
    """A side of ``cells`` output pixels rounded, at least 1 and at most LIMITS["image_side"]."""
    side = round(cells) if math.isfinite(cells) else math.inf
    if side < 1:
        raise InputError(
            f"{name}: {_validate.brief(value)} gives a map under one pixel wide ({cells:.3g} px)"
        )
    bound = _validate.LIMITS["image_side"]
    if side > bound:
        raise InputError(
            f"{name}: {_validate.brief(value)} gives a map side of {cells:.0f} px, expected at "
            f"most {bound:g} (LIMITS['image_side'])"
        )
    return int(side)


def map_shape(
    shape: Sequence[int], pixel_size: Sequence[float], options: dict, value: object = None
) -> tuple[int, int]:
    """``(rows, columns)`` of the map of a grid of ``shape`` cells of ``pixel_size`` metres
    under the checked ``options`` of :func:`check_size_options` (``value``: the option as given,
    for the messages)."""
    h, w = (int(v) for v in shape)
    if "size" in options:
        s = options["size"]
        if isinstance(s, int):
            long = max(h, w)
            return _side(h * s / long, "size", value), _side(w * s / long, "size", value)
        sw, sh = s
        if sw == 0:
            sw = _side(w * sh / h, "size", value)
        if sh == 0:
            sh = _side(h * sw / w, "size", value)
        return sh, sw
    if "cells" in options:
        c = options["cells"]
        return _side(h * c, "scale", value), _side(w * c, "scale", value)
    if "metres" in options:
        m = options["metres"]
        dx, dy = (float(v) for v in pixel_size)
        return _side(h * dy / m, "scale", value), _side(w * dx / m, "scale", value)
    return h, w


def map_grid(
    dem: DEM,
    *,
    size: int | Sequence[int] | None = None,
    scale: float | str | None = None,
    dpi: float | None = None,
) -> DEM:
    """The DEM resampled onto the grid of its map at ``size``/``scale``/``dpi`` (semantics in
    the module's docstring): heights of :func:`resample_heights`, a transform and pixel size
    (metres) of the output pixel over the same extent. The DEM itself when the grid is its
    own (the default: one pixel per cell).

    Raises
    ------
    InputError
        As :func:`check_size_options`; a map larger than the memory available; a lazy (dask)
        DEM whose map would not be on its own grid (maps of those are drawn chunk by chunk,
        one pixel per cell: resample the DEM first, e.g. ``gdalwarp -ts``/``-tr``).
    """
    options = check_size_options(size, scale, dpi)
    if not options:
        return dem
    given = ("size", size) if "size" in options else ("scale", scale)
    out = map_shape(dem.shape, dem.pixel_size, options, given[1])
    if out == tuple(dem.shape):
        return dem
    if not isinstance(dem.heights, np.ndarray):
        raise InputError(
            f"{given[0]}: a DEM read in chunks (out of core) is mapped one pixel per cell; "
            "resample it first (gdalwarp -ts/-tr) or read it into memory for a map at another "
            "size"
        )
    _validate.check_memory(
        out[0] * out[1] * _MAP_BYTES_PER_PIXEL, given[0], f"a {out[1]}x{out[0]} map"
    )
    h, w = dem.shape
    fy, fx = h / out[0], w / out[1]  # source cells per output pixel
    x0, dx, rx, y0, ry, dy = dem.transform
    heights = resample_heights(dem.heights, out)
    return replace(
        dem,
        heights=heights,
        mask=np.isfinite(heights),
        transform=(x0, dx * fx, rx * fy, y0, ry * fx, dy * fy),
        pixel_size=(dem.pixel_size[0] * fx, dem.pixel_size[1] * fy),
    )


def view_size(
    window_size: Sequence[int] | None,
    size: int | Sequence[int] | None,
    scale: float | None,
    grid_shape: Sequence[int] | None = None,
) -> tuple[int, int]:
    """``(width, height)`` of a perspective view (bird's-eye map, sumi-e): ``window_size``
    (default 1024 x 768), or ``size`` (a long side keeps ``window_size``'s aspect; (W, H);
    (W, 0)), or ``scale`` pixels per DEM cell along the long side of ``grid_shape`` (the
    terrain fills most of the frame's width, so about that many pixels per cell). Call without
    ``grid_shape`` to check the options before the DEM is read."""
    options = check_size_options(size, scale, map_scale=False)
    if window_size is not None and options:
        other = "size" if size is not None else "scale"
        raise InputError(f"window_size: expected window_size= or {other}=, not both")
    base = (1024, 768) if window_size is None else window_size
    try:
        bw, bh = (int(v) for v in base)
    except (TypeError, ValueError):
        raise InputError(
            f"window_size: expected (width, height), got {_validate.brief(base)}"
        ) from None
    if bw < 1 or bh < 1:
        raise InputError(f"window_size: expected positive sides, got {_validate.brief(base)}")
    if "cells" in options:
        if grid_shape is None:
            return bw, bh
        long = options["cells"] * max(int(v) for v in grid_shape)
        options = {"size": _side(long, "scale", scale)}
    if "size" not in options:
        return bw, bh
    h, w = map_shape((bh, bw), (1.0, 1.0), options, size if size is not None else scale)
    return w, h


# ------------------------------------------------------------------------------ resampling


def _keys_weights(t: np.ndarray) -> tuple[np.ndarray, ...]:
    """Keys' cubic convolution weights (a = -0.5, GDAL's ``cubic``) of the taps at
    ``i-1, i, i+1, i+2`` for the fraction ``t`` in [0, 1) past tap ``i``: C1, exact on
    quadratics, four taps, so a value depends only on the 4 x 4 cells around it."""
    t2, t3 = t * t, t * t * t
    return (
        -0.5 * t3 + t2 - 0.5 * t,
        1.5 * t3 - 2.5 * t2 + 1.0,
        -1.5 * t3 + 2.0 * t2 + 0.5 * t,
        0.5 * t3 - 0.5 * t2,
    )


def _with_ghost_rows(z: np.ndarray) -> np.ndarray:
    """``z`` with two rows before and after it, linear extrapolations of the first and last two
    (the edge row where that is NaN or there is one row): the grid's cells reach half a cell
    beyond its first and last centres, and a plane stays a plane out to its edges."""
    n = z.shape[0]
    zp = np.empty((n + 4, *z.shape[1:]), dtype=np.float32)
    zp[2 : n + 2] = z
    for edge, inner, ghost, step in ((2, 3, 1, -1), (n + 1, n, n + 2, 1)):
        a = zp[edge]
        slope = a - zp[inner] if n > 1 else np.zeros_like(a)
        slope = np.where(np.isfinite(slope), slope, np.float32(0.0))
        zp[ghost] = a + slope
        zp[ghost + step] = a + 2 * slope
    return zp


def _cubic_axis0(z: np.ndarray, m: int) -> np.ndarray:
    """``z`` (n rows) resampled to ``m >= n`` rows by cubic convolution over the same extent
    (row ``j``'s centre at source row ``(j + 0.5) n / m - 0.5``; beyond the first and last row
    the grid is extrapolated linearly), each value clamped to the range of its four taps, so
    that a cliff does not ring (overshoot beyond its own heights would draw false rings)."""
    n = z.shape[0]
    u = (np.arange(m, dtype=np.float64) + 0.5) * (n / m) - 0.5
    i = np.floor(u).astype(np.int64)
    t = (u - i).astype(np.float32)
    zp = _with_ghost_rows(z)
    taps = [i + k + 2 for k in (-1, 0, 1, 2)]  # rows of zp
    weights = _keys_weights(t)
    out = np.empty((m, *z.shape[1:]), dtype=np.float32)
    for r0 in range(0, m, _BLOCK):
        r1 = min(r0 + _BLOCK, m)
        rows = [zp[tap[r0:r1]] for tap in taps]
        acc = np.zeros_like(rows[0])
        for wk, rk in zip(weights, rows, strict=True):
            acc += wk[r0:r1, None] * rk
        lo = np.minimum(np.minimum(rows[0], rows[1]), np.minimum(rows[2], rows[3]))
        hi = np.maximum(np.maximum(rows[0], rows[1]), np.maximum(rows[2], rows[3]))
        out[r0:r1] = np.clip(acc, lo, hi)
    return out


def _nearest_axis0(a: np.ndarray, m: int) -> np.ndarray:
    """``a`` resampled to ``m`` rows by the nearest row (the cell an output pixel centre is in)."""
    n = a.shape[0]
    idx = np.minimum(((np.arange(m) + 0.5) * (n / m)).astype(np.int64), n - 1)
    return a[idx]


def _area_axis0(a: np.ndarray, m: int) -> np.ndarray:
    """``a`` (n rows) resampled to ``m <= n`` rows by exact area averaging: output row ``j``
    is the mean of ``a`` over source rows ``[j n / m, (j + 1) n / m)``, fractional rows
    weighted by their overlap (an integral of the piecewise-constant rows, by cumulative
    sums in float64, block by block of columns)."""
    n = a.shape[0]
    edges = np.arange(m + 1, dtype=np.float64) * (n / m)
    k = np.minimum(np.floor(edges).astype(np.int64), n - 1)
    frac = (edges - k)[:, None]
    out = np.empty((m, *a.shape[1:]), dtype=np.float32)
    cols = a.shape[1]
    step = max(1, (1 << 22) // max(n, 1))
    for c0 in range(0, cols, step):
        c1 = min(c0 + step, cols)
        block = a[:, c0:c1].astype(np.float64)
        csum = np.zeros((n + 1, c1 - c0))
        np.cumsum(block, axis=0, out=csum[1:])
        integral = csum[k] + frac * block[k]
        out[:, c0:c1] = (integral[1:] - integral[:-1]) * (m / n)
    return out


def resample_heights(z: np.ndarray, shape: Sequence[int]) -> np.ndarray:
    """Heights (NaN at nodata) resampled onto a grid of ``shape`` over the same extent.

    Each axis on its own: where the output has more pixels than the grid, cubic convolution
    (Keys, GDAL's ``cubic``) clamped to the range of its taps (no ringing at cliffs); where it
    has fewer, the area average of the valid cells (anti-aliased, never decimated). An output
    pixel is valid where its centre lies in a valid cell (upsampling: the nodata cells keep
    their square footprint) or at least half its area is valid (downsampling). Nodata does not
    bleed: before the cubic pass two rings of nodata cells around the data are filled by linear
    extrapolation (:func:`~sciviz_gbuf.filters.fill_nodata_ring`, exact on a plane), and a
    valid output pixel reads no cell further from the data than that.

    Parameters
    ----------
    z : (H, W) float32
    shape : (rows, columns)

    Returns
    -------
    (rows, columns) float32, NaN at nodata
    """
    z = np.asarray(z, dtype=np.float32)
    m_rows, m_cols = (int(v) for v in shape)
    valid = np.isfinite(z)
    num = np.where(valid, z, np.float32(0.0))
    den = valid.astype(np.float32)
    # Downsampling axes first: they make the grid smaller.
    if m_rows < z.shape[0]:
        num, den = _area_axis0(num, m_rows), _area_axis0(den, m_rows)
    if m_cols < z.shape[1]:
        num, den = _area_axis0(num.T, m_cols).T, _area_axis0(den.T, m_cols).T
    with np.errstate(invalid="ignore", divide="ignore"):
        mid = np.where(den >= 0.5, num / np.maximum(den, np.float32(1e-30)), np.float32(np.nan))
    mid = mid.astype(np.float32)
    up_rows, up_cols = m_rows > mid.shape[0], m_cols > mid.shape[1]
    if not (up_rows or up_cols):
        return np.ascontiguousarray(mid)
    ok = np.isfinite(mid)
    filled = fill_nodata_ring(fill_nodata_ring(mid)) if not ok.all() else mid
    if up_cols:
        filled, ok = _cubic_axis0(filled.T, m_cols).T, _nearest_axis0(ok.T, m_cols).T
    if up_rows:
        filled, ok = _cubic_axis0(filled, m_rows), _nearest_axis0(ok, m_rows)
    return np.ascontiguousarray(np.where(ok, filled, np.float32(np.nan)), dtype=np.float32)
