"""Topographic maps of DEM grids (Saito & Takahashi 1990 §4.3, Fig. 11 ``mx3``).

A plan-view map needs no rendering: the DEM grid is the G-buffer (``wz`` = height). The map is
colour bands of height, lit by a relief shade (GDAL-compatible hillshade, optionally with cast
shadows and a sky-view term) and overdrawn with major and minor contour lines whose minors thin
out where they crowd (Eq. 15). Nodata cells are transparent and leave no trace at their border:
the relief is computed on a grid whose first ring of nodata cells is linearly extrapolated, and
the contour operator extrapolates the same way.

Bird's-eye maps (Fig. 12) and the sumi-e (Fig. 13) are in :mod:`.birdseye`.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Sequence

import numpy as np
from numba import njit, prange

from .. import _dask as _chunks
from .. import _validate
from .._progress import progress
from ..errors import InputError
from ..filters import _band_kernels as _bk
from ..filters import contour_lines, hillshade
from ..filters.bands import band_tables
from ..readers import DEM, read_dem

__all__ = ["as_dem", "map_layers", "nice_intervals", "topographic_map", "typical_slope"]

#: Cells :func:`_fill_ring` reads around a nodata cell (the extrapolation ``2a - b``).
FILL_RING_RADIUS = 2

#: Dark brown, the colour of contour lines on most topographic maps.
CONTOUR_COLOR = (0.36, 0.20, 0.08)


def as_dem(dem: DEM | str | os.PathLike | np.ndarray) -> DEM:
    """A :class:`~sciviz_gbuf.readers.DEM` as is; a dask array kept lazy (1 m pixels);
    anything else through :func:`~sciviz_gbuf.readers.read_dem` (a file, an array in metres,
    an xarray DataArray)."""
    if isinstance(dem, DEM):
        return dem
    if _chunks.is_dask(dem):
        from .terrain_chunked import lazy_dem

        return lazy_dem(dem)
    return read_dem(dem)


def _round_up(value: float) -> float:
    """The smallest of 1, 2, 2.5, 5 times a power of ten that is >= ``value`` (> 0)."""
    e = math.floor(math.log10(value))
    return min(m * 10.0**k for k in (e, e + 1) for m in (1.0, 2.0, 2.5, 5.0, 10.0)
               if m * 10.0**k >= value * (1 - 1e-12))  # fmt: skip


def nice_intervals(
    lo: float, hi: float, *, majors: int = 8, slope: float | None = None, spacing: float = 6.0
) -> tuple[float, float]:
    """Minor and major contour intervals for heights in ``[lo, hi]``: the round major interval
    (1, 2, 2.5 or 5 times a power of ten) giving closest to ``majors`` lines (in ratio), and
    five minors to each major. With ``slope`` (a typical height change per pixel), majors are
    at least ``spacing`` pixels apart there: steep or coarse grids get fewer lines rather than
    solid ink.

    >>> nice_intervals(250.0, 1150.0)
    (20.0, 100.0)
    """
    span = float(hi) - float(lo)
    if not (math.isfinite(span) and span > 0):
        return 0.2, 1.0
    e = math.floor(math.log10(span / majors))
    candidates = [m * 10.0**k for k in (e - 1, e, e + 1) for m in (1.0, 2.0, 2.5, 5.0)]
    major = min(candidates, key=lambda c: abs(math.log(span / c / majors)))
    if slope is not None and math.isfinite(slope) and slope > 0:
        major = max(major, _round_up(slope * spacing))
    return major / 5.0, major


def typical_slope(z: np.ndarray, samples: int = 1_000_000) -> float:
    """Median height change per pixel (gradient magnitude) of a height image where it is not
    flat (a sea or a lake would outvote the land), from about ``samples`` pixels on a regular
    lattice; NaN without such a pixel."""
    lattice = slope_lattice(z, samples)
    return float("nan") if lattice is None else median_slope(*lattice)


def slope_lattice(z, samples: int = 1_000_000) -> tuple | None:
    """The cells :func:`typical_slope` samples: ``(base, east, south)`` views of ``z`` on a
    regular lattice, each cell's east and south neighbours (None for a grid under 2x2). Works
    on dask arrays too (lazy slices)."""
    h, w = z.shape
    if h < 2 or w < 2:
        return None
    k = max(1, int(math.sqrt(h * w / samples)))
    base = z[: h - 1 : k, : w - 1 : k]
    return base, z[: h - 1 : k, 1::k][:, : base.shape[1]], z[1::k, : w - 1 : k][: base.shape[0]]


def median_slope(base: np.ndarray, east: np.ndarray, south: np.ndarray) -> float:
    """:func:`typical_slope` of the lattice cells of :func:`slope_lattice`."""
    g = np.hypot(east - base, south - base)
    g = g[np.isfinite(g) & (g > 0)]
    return float(np.median(g)) if g.size else float("nan")


def contour_intervals(
    z: np.ndarray,
    interval: float | None,
    major_interval: float | None,
    *,
    pixels_per_sample: float = 1.0,
) -> tuple[float, float, float, float | None]:
    """``(lo, hi, interval, major_interval)`` of a height image: its valid range (0, 1 if
    none) and the contour intervals, the given ones or :func:`nice_intervals` on its slope;
    ``major_interval`` alone implies minors at a fifth of it. ``pixels_per_sample``: output
    pixels per sample of ``z`` (1 / supersampling), for the slope in output pixels."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: no range
        lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
    slope = None
    if interval is None and major_interval is None:
        slope = typical_slope(z) / pixels_per_sample
    return choose_intervals(lo, hi, slope, interval, major_interval)


def choose_intervals(
    lo: float,
    hi: float,
    slope: float | None,
    interval: float | None,
    major_interval: float | None,
) -> tuple[float, float, float, float | None]:
    """:func:`contour_intervals` from the height range and typical slope (NaN range: none)."""
    if not np.isfinite(lo):
        lo, hi = 0.0, 1.0
    if interval is None and major_interval is None:
        interval, major_interval = nice_intervals(lo, hi, slope=slope)
    elif interval is None:
        interval = float(major_interval) / 5.0
    return lo, hi, interval, major_interval


def _fill_ring(z: np.ndarray) -> np.ndarray:
    """``z`` with each nodata cell next to data replaced by a linear extrapolation of the data.

    Every direction with two valid cells ``a`` (next) and ``b`` (beyond) gives ``2a - b``; their
    mean is exact on a plane, so a 3x3 relief operator sees no step at a nodata border (GDAL's
    rule, the centre value for a missing neighbour, halves the slope there: a bright or dark rim).
    Without such a pair, the mean of the valid neighbours. ``z`` itself when it has no nodata.
    """
    if not np.isnan(z).any():
        return z
    out = np.empty_like(z, dtype=np.float32)
    _fill_ring_kernel(np.ascontiguousarray(z, dtype=np.float32), out)
    return out


@njit(parallel=True, cache=True)
def _fill_ring_kernel(z: np.ndarray, out: np.ndarray) -> None:
    h, w = z.shape
    for i in prange(h):
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


def relief_light(direct: np.ndarray, ambient: np.ndarray | float = 1.0) -> np.ndarray:
    """Light of a relief relative to open flat ground (1 there): two parts sun, ``direct`` (the
    shade over that of flat ground, 0 in cast shadow), to one part sky, ``ambient``."""
    return (np.float32(1 / 3) * ambient + np.float32(2 / 3) * direct).astype(np.float32)


def lit(rgb: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Colours under a relief ``light``: below 1 it multiplies; above 1 (slopes facing the sun)
    it lifts the colour up to halfway towards white. NaN light leaves the colour as it is."""
    lt = np.nan_to_num(light, nan=1.0)[..., None]
    return rgb * np.minimum(lt, 1.0) + (1.0 - rgb) * (0.5 * np.clip(lt - 1.0, 0.0, 1.0))


def _flat_shade(**opts) -> float:
    """The hillshade of flat ground for these options (``sin(altitude)`` for most variants)."""
    return float(hillshade(np.zeros((3, 3), np.float32), **opts)[1, 1])


def _check_bands(bands, major: float):
    """``bands`` -> the ``interval=``/``levels=`` options of the band colours (empty for a
    continuous ramp), or None for no bands."""
    if bands is False or bands is None:
        return None
    if bands is True:
        return {"interval": major}
    if isinstance(bands, str):
        if bands == "continuous":
            return {}
        raise InputError(
            f"bands: expected True, False, 'continuous', an interval or a list of levels, "
            f"got {bands!r}"
        )
    if np.ndim(bands) == 0:
        try:
            v = float(bands)
        except (TypeError, ValueError):
            v = float("nan")
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"bands: expected an interval > 0, got {bands!r}")
        return {"interval": v}
    try:
        levels = np.asarray(bands, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        levels = np.array([np.nan])
    if levels.size == 0 or not np.isfinite(levels).all():
        raise InputError(f"bands: expected finite band edges, got {bands!r}")
    return {"levels": levels}


def map_layers(
    heights: np.ndarray,
    *,
    dx: float,
    dy: float,
    interval: float | None,
    major_interval: float | None,
    contours: bool,
    width: float,
    major_width: float,
    dense_spacing: float,
    bands: object,
    cmap: object,
    sea_level: float | None,
    relief: bool,
    azimuth: float,
    altitude: float,
    z_factor: float,
    variant: str,
    shadows: bool,
    sky_view: bool,
    vmin: float | None = None,
    vmax: float | None = None,
    bar=None,
) -> dict[str, np.ndarray | None]:
    """The layers of a plan-view map, see :func:`topographic_map`: ``ink`` (contours or None),
    ``sh`` (hillshade), ``flat`` (its value on flat ground), ``lit`` (cast shadows), ``sky``
    (sky view) when asked for, and ``tables`` (the band colours' kernel arguments, or None).
    Every option is checked before the work starts."""
    z = heights
    lo, hi, interval, major_interval = contour_intervals(z, interval, major_interval)
    layers: dict[str, object] = {"ink": None, "relief": relief}
    layers["tables"] = map_band_tables(
        bands, interval, major_interval, cmap, lo if vmin is None else vmin,
        hi if vmax is None else vmax, sea_level,
    )  # fmt: skip
    if contours:
        layers["ink"] = map_contours(
            z,
            interval=interval,
            major_interval=major_interval,
            width=width,
            major_width=major_width,
            dense_spacing=dense_spacing,
        )
    if bar is not None:
        bar.step("relief")
    if relief:
        opts = {"azimuth": azimuth, "altitude": altitude, "z_factor": z_factor, "variant": variant}
        layers["sh"] = hillshade(_fill_ring(z), dx=dx, dy=dy, **opts)
        layers["flat"] = max(_flat_shade(dx=dx, dy=dy, **opts), 1e-3)
        if shadows:
            from ..filters import cast_shadows

            layers["lit"] = cast_shadows(
                z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude, z_factor=z_factor
            )
        if sky_view:
            from ..filters import sky_view as sky_view_factor

            layers["sky"] = sky_view_factor(z, dx=dx, dy=dy, z_factor=z_factor)
    return layers


def map_band_tables(bands, interval, major_interval, cmap, vmin, vmax, sea_level):
    """The band colours' kernel arguments of a map (None for no bands): one band per major
    interval (five minors) unless ``bands`` says otherwise (see :func:`topographic_map`)."""
    band_interval = major_interval if major_interval is not None else 5.0 * float(interval)
    opts = _check_bands(bands, band_interval)
    if opts is None:
        return None
    return band_tables(
        np.zeros(1, np.float32),  # unused: the range is given
        interval=opts.get("interval"),
        levels=opts.get("levels"),
        base=0.0,
        cmap=cmap,
        vmin=vmin,
        vmax=vmax,
        sea_level=sea_level,
        sea_cmap=None,
    )


def map_contours(
    z,
    *,
    interval: float,
    major_interval: float | None,
    width: float,
    major_width: float,
    dense_spacing: float,
):
    """The contour ink of a map (numpy or dask heights): majors never thin out, minors fade
    where they crowd closer than ``dense_spacing`` (Eq. 15, Fig. 11); without a major interval
    the one family fades like minors."""
    if major_interval is None:
        return contour_lines(
            z, interval=interval, width=width, c_dense=0.0, dense_spacing=dense_spacing
        )
    return contour_lines(
        z,
        interval=interval,
        major_interval=major_interval,
        width=width,
        major_width=major_width,
        dense_spacing=dense_spacing,
    )


def composite(layers: dict, heights: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """The map's layers into one RGBA uint8 image in one fused pass (no float image of the
    whole map is made)."""
    z = np.ascontiguousarray(heights, dtype=np.float32)
    tables = layers["tables"]
    if tables is None:  # no bands: white paper (the kernel ignores the tables)
        tables = band_tables(
            np.zeros(1, np.float32),
            interval=None,
            levels=None,
            base=0.0,
            cmap=None,
            vmin=0.0,
            vmax=1.0,
            sea_level=None,
            sea_cmap=None,
        )
    empty = np.zeros((0, 0), np.float32)

    def layer(name: str) -> np.ndarray:
        # contiguous float32 always: one compiled signature of the kernel, not one per layout
        a = layers.get(name)
        return empty if a is None else np.ascontiguousarray(a, dtype=np.float32)

    out = np.empty((*z.shape, 4), dtype=np.uint8)
    _bk.map_image(
        z,
        layers["tables"] is not None,
        *tables,
        bool(layers["relief"]),
        layer("sh"),
        np.float32(layers.get("flat", 1.0)),
        layer("lit"),
        layer("sky"),
        layer("ink"),
        colour.astype(np.float32),
        out,
    )
    return out


def topographic_map(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    contours: bool = True,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    contour_color: Sequence[float] = CONTOUR_COLOR,
    bands: bool | str | float | Sequence[float] = True,
    cmap: str | object | None = None,
    sea_level: float | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    relief: bool = True,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float = 1.0,
    variant: str = "regular",
    shadows: bool = False,
    sky_view: bool = False,
    progress_bar: bool = False,
) -> np.ndarray:
    """A plan-view topographic map of a DEM: colour bands, relief and contour lines (1990 Fig. 11
    ``mx3``), one pixel per DEM cell.

    Parameters
    ----------
    dem : DEM, path, array or xarray.DataArray
        Anything :func:`~sciviz_gbuf.readers.read_dem` reads (arrays: 1 m pixels).
    interval, major_interval : float, optional
        Minor and major contour intervals in height units. Default: round intervals giving
        about eight majors over the height range, but majors at least 6 pixels apart on the
        median slope, five minors to a major (:func:`nice_intervals`); ``major_interval``
        alone implies minors at a fifth of it.
    contours : bool, default: True
        Draw contour lines at all.
    width, major_width : float, default: 1, 2
        Line widths in pixels.
    dense_spacing : float, default: 4
        Minor lines fade out where they come closer than this many pixels (Eq. 15,
        ``c_dense`` = background for minors, = line for majors, as in Fig. 11).
    contour_color : RGB, default: dark brown
    bands : bool, 'continuous', float or sequence of float, default: True
        Colour bands: True one band per major interval; a number, the band interval; a list,
        the band edges; ``'continuous'`` a smooth ramp; False none (white paper).
    cmap, sea_level : optional
        Colour map and topo-bathymetry sea level of :func:`~sciviz_gbuf.filters.color_bands`.
    vmin, vmax : float, optional
        Heights at the ends of the colour map (default the data range): fix them to colour
        several tiles alike.
    relief : bool, default: True
        Multiply the colours by a relief shade, normalised to 1 on open flat ground; slopes
        facing the sun are lifted towards white.
    azimuth, altitude, z_factor, variant
        Of the relief, as in :func:`~sciviz_gbuf.filters.hillshade` (GDAL's conventions).
    shadows : bool, default: False
        Darken cells in the cast shadow of other terrain (rayshader's ``ray_shade``).
    sky_view : bool, default: False
        Darken cells that see less of the sky (valleys, pits; rayshader's ``ambient_shade``).
        Slow: about 1 MPix/s (16 directions, 50 cells out), minutes for a large DEM.
    progress_bar : bool, default: False
        Show a progress bar.

    Returns
    -------
    (H, W, 4) uint8 RGBA
        On the DEM's grid (row 0 north): its transform and CRS georeference the map
        (:func:`~sciviz_gbuf.compose.write_geotiff`). Nodata cells are transparent (alpha 0).

    Raises
    ------
    InputError
        For anything :func:`read_dem` rejects, or an invalid parameter.
    """
    colour = _validate.rgb(contour_color, "contour_color")
    d = as_dem(dem)
    if _chunks.is_dask(d.heights):
        from .terrain_chunked import lazy_topographic_map

        return lazy_topographic_map(
            d,
            colour,
            interval=interval,
            major_interval=major_interval,
            contours=contours,
            width=width,
            major_width=major_width,
            dense_spacing=dense_spacing,
            bands=bands,
            cmap=cmap,
            sea_level=sea_level,
            vmin=vmin,
            vmax=vmax,
            relief=relief,
            azimuth=azimuth,
            altitude=altitude,
            z_factor=z_factor,
            variant=variant,
            shadows=shadows,
            sky_view=sky_view,
        )
    with progress(progress_bar, 4, "topographic map") as bar:
        bar.step("contours")
        layers = map_layers(
            d.heights,
            dx=d.pixel_size[0],
            dy=d.pixel_size[1],
            interval=interval,
            major_interval=major_interval,
            contours=contours,
            width=width,
            major_width=major_width,
            dense_spacing=dense_spacing,
            bands=bands,
            cmap=cmap,
            sea_level=sea_level,
            relief=relief,
            azimuth=azimuth,
            altitude=altitude,
            z_factor=z_factor,
            variant=variant,
            shadows=shadows,
            sky_view=sky_view,
            vmin=vmin,
            vmax=vmax,
            bar=bar,
        )
        bar.step("composite")
        out = composite(layers, d.heights, colour)
        bar.step("done")
    return out
