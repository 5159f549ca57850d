"""Map furniture of topographic maps: the hypsometric legend and the scale bar.

The legend's classes are the map's own colour bands: their edges are the band edges the map
uses (one band per major contour interval by default) and their colours come from the map's
band kernel itself, evaluated at a height inside each class, so a swatch is the colour of the
band on the map (before the relief shade). The scale bar has a round length (1, 2 or 5 times a
power of ten metres, at most a quarter of the map's width) and its length in pixels comes from
the georeference: on a projected grid the pixel size, on a geographic grid the length of a
degree of longitude on the WGS 84 ellipsoid at the map's centre latitude (the bar runs east).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from .. import _validate
from ..errors import InputError
from ..filters import composite_map
from ..readers import DEM, metres_per_degree
from ._intervals import contour_intervals
from ._map import as_dem, check_bands, map_band_tables
from ._resample import map_grid

__all__ = ["LegendClass", "ScaleBar", "legend_classes", "scale_bar"]

#: Most classes a legend lists (a continuous ramp is sampled with this many).
MAX_CLASSES = 64


class LegendClass(NamedTuple):
    """One class of a hypsometric legend."""

    low: float
    """Lowest height of the class (a band edge, or the map's lowest height)."""
    high: float
    """Highest height of the class."""
    rgb: tuple[int, int, int]
    """The band's colour on the map (uint8), before the relief shade."""


class ScaleBar(NamedTuple):
    """A scale bar of a map."""

    metres: float
    """Ground length of the bar."""
    pixels: float
    """Its length in output pixels of the map (along a row)."""
    text: str
    """Its label, e.g. ``"500 m"`` or ``"2 km"``."""


def _band_colours(tables: tuple, heights: np.ndarray) -> np.ndarray:
    """The map's band colours (uint8 RGB) at ``heights``: the map's own fused kernel."""
    z = np.asarray(heights, np.float32)[None, :]
    return composite_map(z, tables=tables)[0, :, :3]


def legend_classes(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    bands: bool | str | float | Sequence[float] = True,
    cmap: str | object | None = None,
    sea_level: float | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    size: int | Sequence[int] | None = None,
    scale: float | str | None = None,
    dpi: float | None = None,
) -> list[LegendClass]:
    """The hypsometric legend of :func:`~sciviz_gbuf.recipes.terrain.topographic_map` with the
    same options: one class per colour band the map's heights reach, lowest first.

    Class edges are the map's band edges (clipped to the heights' range at the ends); a class
    that a ``sea_level`` cuts is split there (sea colours below it). A ``'continuous'`` ramp is
    listed as :data:`MAX_CLASSES` equal steps of the range, each with the colour at its middle.
    No bands (``bands=False``): an empty list.
    """
    d = as_dem(dem)
    if not isinstance(d.heights, np.ndarray):
        raise InputError("legend: the DEM is read in chunks; a legend needs it in memory")
    d = map_grid(d, size=size, scale=scale, dpi=dpi)
    lo, hi, minor, major = contour_intervals(d.heights, interval, major_interval)
    band_interval = major if major is not None else 5.0 * float(minor)
    opts = check_bands(bands, band_interval)
    tables = map_band_tables(
        bands, minor, major, cmap, lo if vmin is None else vmin, hi if vmax is None else vmax,
        sea_level,
    )  # fmt: skip
    if tables is None or opts is None:
        return []
    if not opts:  # continuous
        edges = np.linspace(lo, hi, MAX_CLASSES + 1) if hi > lo else np.array([lo, hi])
    elif "interval" in opts:
        q = float(opts["interval"])
        k0, k1 = math.floor(lo / q), math.floor(hi / q) + 1
        if k1 - k0 > _validate.LIMITS["bands"]:
            raise InputError(
                f"bands: {k1 - k0} bands over [{lo:g}, {hi:g}]; expected at most "
                f"{int(_validate.LIMITS['bands'])}"
            )
        edges = np.arange(k0, k1 + 1, dtype=np.float64) * q
    else:
        lv = np.asarray(opts["levels"], np.float64)
        inner = lv[(lv > lo) & (lv < hi)]
        edges = np.concatenate([[lo], inner, [hi]])
    edges = np.clip(edges, lo, hi)
    if sea_level is not None and lo < float(sea_level) < hi:
        edges = np.union1d(edges, [float(sea_level)])
    edges = np.unique(edges)
    if edges.size == 1:
        edges = np.array([lo, hi])
    lows, highs = edges[:-1], edges[1:]
    mids = (lows + highs) / 2.0
    colours = _band_colours(tables, mids)
    return [
        LegendClass(float(a), float(b), (int(c[0]), int(c[1]), int(c[2])))
        for a, b, c in zip(lows, highs, colours, strict=True)
    ]


def _nice_length(limit: float) -> float:
    """The largest of 1, 2, 5 times a power of ten that is at most ``limit`` (> 0)."""
    e = math.floor(math.log10(limit))
    best = 10.0**e
    for m in (2.0, 5.0, 10.0):
        if m * 10.0**e <= limit * (1 + 1e-12):
            best = m * 10.0**e
    return best


def _length_text(metres: float) -> str:
    if metres >= 1000.0:
        return f"{metres / 1000.0:g} km"
    return f"{metres:g} m"


def scale_bar(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    size: int | Sequence[int] | None = None,
    scale: float | str | None = None,
    dpi: float | None = None,
    fraction: float = 0.25,
) -> ScaleBar:
    """A scale bar for the map of ``dem`` at ``size``/``scale``/``dpi``: the longest round
    length (1, 2, 5 x 10^k m) at most ``fraction`` of the map's width, and its length in output
    pixels along a row (east) at the map's centre.

    On a geographic grid a pixel's width in metres is that of its longitude step on the WGS 84
    ellipsoid at the centre latitude (the parallel's radius ``N(phi) cos(phi)``), so the bar is
    true there and off by ``cos(phi) / cos(phi_centre)`` towards the map's north and south
    edges, as on any map in geographic coordinates.
    """
    fraction = _validate.number_in(fraction, "fraction", 0.01, 1.0)
    d = map_grid(as_dem(dem), size=size, scale=scale, dpi=dpi)
    h, w = d.shape
    _x0, dx, _rx, y0, ry, dy = d.transform
    if d.geographic:
        lat = y0 + (w / 2) * ry + (h / 2) * dy
        per_lon, per_lat = metres_per_degree(lat)
        metres_per_px = math.hypot(dx * per_lon, ry * per_lat)
    else:
        metres_per_px = float(d.pixel_size[0])
    if not (math.isfinite(metres_per_px) and metres_per_px > 0):
        raise InputError(f"{d.source or 'heights'}: the grid has no pixel size for a scale bar")
    metres = _nice_length(fraction * w * metres_per_px)
    return ScaleBar(metres, metres / metres_per_px, _length_text(metres))
