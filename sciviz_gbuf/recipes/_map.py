"""The layers of a plan-view map and their one-pass composite, shared by the in-memory
(:mod:`.terrain`) and the chunked (:mod:`.terrain_chunked`) topographic maps and the bird's-eye
recipes."""

from __future__ import annotations

import math
import os

import numpy as np

from .. import _dask, _validate
from ..errors import InputError
from ..filters import (
    band_heights,
    cast_shadows,
    composite_map,
    contour_lines,
)
from ..filters import sky_view as sky_view_factor
from ..filters.bands import band_tables
from ..filters.contours import MIN_RING_WIDTHS, contour_halo
from ..readers import DEM, read_dem
from ._intervals import contour_intervals, median_ground_slope, slope_lattice
from ._relief import relief_flat, relief_shade, relief_style

__all__ = [
    "CONTOUR_COLOR",
    "RELIEF_SLOPE",
    "RELIEF_Z_MAX",
    "as_dem",
    "check_bands",
    "check_line_sizes",
    "check_z_factor",
    "composite",
    "grid_z_factor",
    "lazy_dem",
    "lit",
    "map_band_heights",
    "map_band_tables",
    "map_contour_halo",
    "map_contours",
    "map_layers",
    "map_min_ring",
    "relief_light",
    "relief_z_factor",
    "rgba",
]


#: Dark brown, the colour of contour lines on most topographic maps.
CONTOUR_COLOR = (0.36, 0.20, 0.08)


def as_dem(dem: DEM | str | os.PathLike | np.ndarray) -> DEM:
    """A :class:`~sciviz_gbuf.readers.DEM` as is; a dask array kept lazy (1 m pixels);
    anything else through :func:`~sciviz_gbuf.readers.read_dem` (a file, an array in metres,
    an xarray DataArray)."""
    if isinstance(dem, DEM):
        return dem
    if _dask.is_dask(dem):
        return lazy_dem(dem)
    return read_dem(dem)


#: Median ground slope (degrees) that the automatic z factor of a map's relief lifts a
#: low-relief DEM to: that of hilly ground, whose relief shade reads at z = 1.
RELIEF_SLOPE = 10.0
#: The largest automatic z factor (a plain's relief is exaggerated at most this much).
RELIEF_Z_MAX = 20.0


def relief_z_factor(z_factor: float | None, ground_slope: float) -> float:
    """The z factor of a map's relief: ``z_factor`` when given (as it is), else the automatic
    ``clip(tan(RELIEF_SLOPE) / ground_slope, 1, RELIEF_Z_MAX)`` for the median ground slope
    ``ground_slope`` (rise over run, :func:`~._intervals.median_ground_slope`): ground whose
    median slope is below 10 degrees is exaggerated until it reaches 10 degrees (at most 20
    times), steeper ground keeps z = 1; 1 without a slope (flat or no valid cell)."""
    if z_factor is not None:
        return z_factor
    if not (math.isfinite(ground_slope) and ground_slope > 0):
        return 1.0
    target = math.tan(math.radians(RELIEF_SLOPE))
    return float(min(max(target / ground_slope, 1.0), RELIEF_Z_MAX))


def grid_z_factor(z: np.ndarray, z_factor: float | None, dx: float, dy: float) -> float:
    """The relief's z factor of in-memory heights ``z``: ``z_factor``, or with None
    :func:`relief_z_factor` of the median ground slope on the cells ``dx`` by ``dy`` of
    :func:`~._intervals.slope_lattice`."""
    if z_factor is not None:
        return z_factor
    lattice = slope_lattice(z)
    slope = float("nan") if lattice is None else median_ground_slope(*lattice, dx, dy)
    return relief_z_factor(None, slope)


def check_z_factor(z_factor) -> float | None:
    """``z_factor``: None (automatic, :func:`relief_z_factor`) or a finite number."""
    return None if z_factor is None else _validate.finite(z_factor, "z_factor")


def relief_light(direct: np.ndarray, ambient: np.ndarray | float = 1.0) -> np.ndarray:
    """Light of a relief relative to open flat ground (1 there): two parts sun, ``direct`` (the
    shade over that of flat ground, 0 in cast shadow), to one part sky, ``ambient``."""
    return (np.float32(1 / 3) * ambient + np.float32(2 / 3) * direct).astype(np.float32)


def lit(rgb: np.ndarray, light: np.ndarray) -> np.ndarray:
    """Colours under a relief ``light``: below 1 it multiplies; above 1 (slopes facing the sun)
    it lifts the colour up to halfway towards white. NaN light leaves the colour as it is."""
    lt = np.nan_to_num(light, nan=1.0)[..., None]
    return rgb * np.minimum(lt, 1.0) + (1.0 - rgb) * (0.5 * np.clip(lt - 1.0, 0.0, 1.0))


def check_line_sizes(
    *, width: float, major_width: float, dense_spacing: float, profile_width: float | None = None
) -> None:
    """The line sizes of a map in output pixels, each within its bound, checked before any
    work (the filters see them multiplied by the supersample, against a wider bound):
    ``width``, ``major_width`` at most ``LIMITS["line_width"]``, ``dense_spacing`` at most
    ``LIMITS["spacing"]``, ``profile_width`` in [1, ``LIMITS["line_width"]``]."""
    _validate.size(width, "width", "line_width")
    _validate.size(major_width, "major_width", "line_width")
    _validate.size(dense_spacing, "dense_spacing", "spacing")
    if profile_width is not None:
        _validate.size(profile_width, "profile_width", "line_width", low=1.0, closed=True)


def check_bands(bands, major: float):
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
        raise InputError(f"bands: expected finite band edges, got {_validate.brief(bands)}")
    return {"levels": _validate.levels(levels, "bands", limit="bands")}


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
    generalize: bool,
    bands: object,
    cmap: object,
    sea_level: float | None,
    relief: bool,
    azimuth: float,
    altitude: float,
    z_factor: float | None,
    variant: str,
    shadows: bool,
    sky_view: bool,
    vmin: float | None = None,
    vmax: float | None = None,
    bar=None,
) -> dict[str, np.ndarray | None]:
    """The layers of a plan-view map, see :func:`topographic_map`: ``ink`` (contours or None),
    ``sh`` (hillshade), ``flat`` (its value on flat ground), ``lit`` (cast shadows), ``sky``
    (sky view) when asked for, ``tables`` (the band colours' kernel arguments, or None) and
    ``z_factor`` (that of the relief: ``z_factor``, or None for :func:`relief_z_factor` of the
    median ground slope on the cells ``dx`` by ``dy`` of :func:`~._intervals.slope_lattice`).
    Every option is checked before the work starts."""
    z = heights
    style = relief_style(relief)
    relief = style is not None
    lo, hi, interval, major_interval = contour_intervals(
        z, interval, major_interval, check_spacing=bool(contours)
    )
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
            generalize=generalize,
        )
    if generalize and layers["tables"] is not None:
        # the band edges follow the generalised lines (no islands of colour where rings went)
        layers["band_z"] = map_band_heights(
            z, bands, interval=interval, major_interval=major_interval, width=width,
            major_width=major_width,
        )  # fmt: skip
    if bar is not None:
        bar.step("relief")
    if relief:
        z_factor = grid_z_factor(z, z_factor, dx, dy)
        layers["z_factor"] = z_factor
        opts = {"azimuth": azimuth, "altitude": altitude, "z_factor": z_factor, "variant": variant}
        layers["sh"] = relief_shade(z, style, dx=dx, dy=dy, **opts)
        layers["flat"] = relief_flat(style, dx=dx, dy=dy, **opts)
        if shadows:
            layers["lit"] = cast_shadows(
                z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude, z_factor=z_factor
            )
        if sky_view:
            layers["sky"] = sky_view_factor(z, dx=dx, dy=dy, z_factor=z_factor)
    return layers


def map_band_tables(bands, interval, major_interval, cmap, vmin, vmax, sea_level):
    """The band colours' kernel arguments of a map (None for no bands): one band per major
    interval (five minors) unless ``bands`` says otherwise (see :func:`topographic_map`)."""
    band_interval = major_interval if major_interval is not None else 5.0 * float(interval)
    opts = check_bands(bands, band_interval)
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


def map_band_heights(
    z, bands, *, interval: float, major_interval: float | None, width: float, major_width: float
):
    """The heights a generalised map colours its bands by (numpy or dask): those of
    :func:`~sciviz_gbuf.filters.band_heights`, without the band islands whose rings the lines
    drop (rings up to 3 widths of the widest line, as in
    :func:`map_contours`); None when the bands need the heights as they are (no bands, a
    continuous ramp)."""
    band_interval = major_interval if major_interval is not None else 5.0 * float(interval)
    opts = check_bands(bands, band_interval)
    if not opts:
        return None
    return band_heights(
        z,
        band_interval=opts.get("interval"),
        band_levels=opts.get("levels"),
        min_ring=map_min_ring(width, major_width, major_interval),
    )


def map_min_ring(width: float, major_width: float, major_interval: float | None) -> float:
    """The largest ring (px) a generalised map's lines drop, and so the largest band island
    filled: ``contour_lines``' default, 3 widths of the widest line (majors only if any)."""
    widest = max(width, major_width) if major_interval is not None else width
    return MIN_RING_WIDTHS * float(widest)


def map_contours(
    z,
    *,
    interval: float,
    major_interval: float | None,
    width: float,
    major_width: float,
    dense_spacing: float,
    generalize: bool = True,
):
    """The contour ink of a map (numpy or dask heights): majors never thin out, minors fade
    where they crowd closer than ``dense_spacing`` (Eq. 15, Fig. 11); without a major interval
    the one family fades like minors. ``generalize``: the cartographic generalisation of
    :func:`~sciviz_gbuf.filters.contour_lines` (default ring size: 3 widths of the widest
    line)."""
    return contour_lines(
        z,
        **_contour_options(interval, major_interval, width, major_width, dense_spacing),
        generalize=generalize,
    )


def map_contour_halo(
    *,
    interval: float,
    major_interval: float | None,
    width: float,
    major_width: float,
    dense_spacing: float,
    generalize: bool = True,
) -> int:
    """The halo (cells) a chunk of :func:`map_contours` with these options needs (checks
    them)."""
    return contour_halo(
        **_contour_options(interval, major_interval, width, major_width, dense_spacing),
        generalize=generalize,
    )


def _contour_options(interval, major_interval, width, major_width, dense_spacing) -> dict:
    if major_interval is None:
        return {"interval": interval, "width": width, "c_dense": 0.0,
                "dense_spacing": dense_spacing}  # fmt: skip
    return {"interval": interval, "major_interval": major_interval, "width": width,
            "major_width": major_width, "dense_spacing": dense_spacing}  # fmt: skip


def composite(layers: dict, heights: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """The map's layers (of :func:`map_layers`) into one RGBA uint8 image in one fused pass
    (:func:`~sciviz_gbuf.filters.composite_map`; no float image of the whole map is made)."""
    band_z = layers.get("band_z")
    return composite_map(
        heights if band_z is None else band_z,
        tables=layers["tables"],
        relief=layers["sh"] if layers["relief"] else None,
        flat=layers.get("flat", 1.0),
        shadow=layers.get("lit"),
        sky=layers.get("sky"),
        ink=layers.get("ink"),
        ink_color=colour,
    )


def lazy_dem(heights) -> DEM:
    """A :class:`DEM` around a 2-D dask array of heights in metres on 1 m pixels (like an
    in-memory array given to :func:`~sciviz_gbuf.readers.read_dem`), kept lazy: float32 with
    NaN at non-finite values."""
    import dask.array as da

    z = _dask.as_dask("heights", heights, None)
    if min(z.shape) == 0:
        raise InputError(f"heights: expected a non-empty 2-D array, got shape {z.shape}")
    z = z.astype(np.float32)
    z = da.where(da.isinf(z), np.float32(np.nan), z)
    h = z.shape[0]
    return DEM(z, da.isfinite(z), None, (0.0, 1.0, 0.0, float(h), 0.0, -1.0), (1.0, 1.0), False)


def rgba(rgb: np.ndarray, alpha: np.ndarray, background) -> np.ndarray:
    """uint8 RGBA: ``rgb`` with coverage ``alpha``, transparent where nothing was rendered (or
    over an opaque ``background`` colour)."""
    rgb = np.clip(np.asarray(rgb, np.float32), 0.0, 1.0)
    if rgb.ndim == 2:
        rgb = np.repeat(rgb[..., None], 3, axis=2)
    a = np.clip(alpha, 0.0, 1.0)[..., None]
    if background is not None:
        bg = _validate.rgb(background, "background")
        rgb, a = rgb * a + bg * (1.0 - a), np.ones_like(a)
    out = np.empty((*rgb.shape[:2], 4), dtype=np.uint8)
    out[..., :3] = np.rint(rgb * 255.0)
    out[..., 3] = np.rint(a[..., 0] * 255.0)
    return out
