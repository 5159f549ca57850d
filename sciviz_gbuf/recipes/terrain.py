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

import itertools
import os
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext

import numpy as np

from .. import _dask, _validate
from .._progress import progress
from ..core.bands import on_this_thread, threads
from ..errors import InputError
from ..readers import DEM
from ..writers.cog import BLOCK, check_cog_target, cog_target, write_cog
from ..writers.png import LARGE_IMAGE, encode_png_rows, write_png, write_png_blocks
from ._intervals import (
    contour_intervals,
    nice_intervals,
    typical_slope,
)
from ._map import (
    CONTOUR_COLOR,
    as_dem,
    check_line_sizes,
    check_z_factor,
    composite,
    grid_z_factor,
    map_band_tables,
    map_layers,
    map_min_ring,
)
from ._relief import RELIEFS, relief_reach, relief_style
from ._resample import check_size_options, map_grid, resample_heights
from .labels import check_in_memory, draw_labels, label_boxes, label_options, labels_of_grid
from .terrain_chunked import RELIEF_HALO, lazy_topographic_map, map_parts, window_map

__all__ = [
    "CONTOUR_COLOR",
    "RELIEFS",
    "as_dem",
    "composite",
    "contour_intervals",
    "map_grid",
    "map_layers",
    "map_min_ring",
    "nice_intervals",
    "resample_heights",
    "topographic_map",
    "typical_slope",
    "write_topographic_cog",
    "write_topographic_png",
]

#: Rows of a block of a map written as it is made (:func:`write_topographic_png`), at least;
#: and at least ``STREAM_HALOS`` halos, so that the rows mapped twice (a generalised map's
#: halo is ~20 rows) stay under a tenth: 256-row blocks of such a map took 7.4 s at 8192²,
#: 608-row blocks 6.4 s.
STREAM_ROWS = 256
STREAM_HALOS = 32


def topographic_map(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    contours: bool = True,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    generalize: bool = True,
    contour_color: Sequence[float] = CONTOUR_COLOR,
    bands: bool | str | float | Sequence[float] = True,
    cmap: str | object | None = None,
    sea_level: float | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    relief: bool = True,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float | None = None,
    variant: str = "regular",
    shadows: bool = False,
    sky_view: bool = False,
    labels: bool = False,
    label_size: float | None = None,
    label_spacing: float | None = None,
    label_color: Sequence[float] | None = None,
    size: int | Sequence[int] | None = None,
    scale: float | str | None = None,
    dpi: float | None = None,
    progress_bar: bool = False,
) -> np.ndarray:
    """A plan-view topographic map of a DEM: colour bands, relief and contour lines (1990 Fig. 11
    ``mx3``), one pixel per DEM cell unless ``size``/``scale`` ask for another size.

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
        Line widths in pixels; each at most ``LIMITS["line_width"]`` = 64.
    dense_spacing : float, default: 4
        Minor lines fade out where they come closer than this many pixels (Eq. 15,
        ``c_dense`` = background for minors, = line for majors, as in Fig. 11).
    generalize : bool, default: True
        Cartographic generalisation of the contour lines
        (:func:`~sciviz_gbuf.filters.contour_lines` ``generalize=True``): the heights are
        smoothed before contouring as much as the local line spacing allows (none where lines
        are at most 3 px apart, up to a 4 px Gaussian on flat ground, but no line moves more
        than 0.6 px from the exact one), so integer-metre terraces and noise draw no specks or
        dashes; rings and specks within 3 widths of the widest line (6 px by default) are
        dropped. The band islands whose rings were dropped take the colour of the band around
        them (:func:`~sciviz_gbuf.filters.band_heights`): no specks of colour, and band edges
        run along the lines (within their 0.6 px). False draws the exact lines and bands of
        the heights (lines those of ``gdal_contour``).
    contour_color : RGB, default: dark brown
    bands : bool, 'continuous', float or sequence of float, default: True
        Colour bands: True one band per major interval; a number, the band interval; a list,
        the band edges; ``'continuous'`` a smooth ramp; False none (white paper).
    cmap, sea_level : optional
        Colour map and topo-bathymetry sea level of :func:`~sciviz_gbuf.filters.color_bands`.
    vmin, vmax : float, optional
        Heights at the ends of the colour map (default the data range): fix them to colour
        several tiles alike.
    relief : bool or str, default: True
        Multiply the colours by a relief shade, normalised to 1 on open flat ground; slopes
        facing the sun are lifted towards white. True is ``'hillshade'`` (GDAL's); the other
        styles blend more layers into it as RVT's blender does (``RELIEFS``):
        ``'vat'`` RVT's VAT (hillshade; slope 0-50 deg, inverted, luminosity 50 %; positive
        openness 68-93 deg, overlay 50 %; sky-view factor 0.7-1, multiply 25 %; openness and
        sky view over 16 directions of 10 cells), ``'openness'`` positive openness 68-93 deg
        (normal, 50 %), ``'texture'`` Brown's texture shading (alpha 0.5) and
        ``'local_relief'`` the simple local relief model (20 cells), each scaled to mid grey
        +- its 99th percentile (normal, 50 %). Texture and local relief take their contrast
        from the whole map: not for a DEM read in chunks.
    azimuth, altitude, variant
        Of the relief, as in :func:`~sciviz_gbuf.filters.hillshade` (GDAL's conventions).
    z_factor : float, optional
        Vertical exaggeration of the relief (and of ``shadows``/``sky_view``), GDAL's ``-z``.
        Default: automatic, so that low-relief DEMs are not washed out:
        ``clip(tan(10 deg) / m, 1, 20)`` for ``m`` the median ground slope (rise over run,
        heights and pixel size in metres; flat cells left out, sampled as for the default
        intervals). Ground whose median slope is under 10 degrees is exaggerated until it is
        10 degrees (at most 20 times); steeper ground keeps ``z_factor=1``. A number is used
        as it is (``z_factor=1`` is the true relief).
    shadows : bool, default: False
        Darken cells in the cast shadow of other terrain (rayshader's ``ray_shade``).
    sky_view : bool, default: False
        Darken cells that see less of the sky (valleys, pits; rayshader's ``ambient_shade``).
        Slower than the other layers: about 15 MPix/s (16 directions, 50 cells out).
    labels : bool, default: False
        Write the heights of the index (major) contours into the lines
        (:func:`~sciviz_gbuf.recipes.labels.contour_labels` gives the placements): the text
        follows the line with its top uphill, the line is knocked out under it, labels keep
        ``label_spacing`` apart along a line and clear of each other, of the frame, of nodata
        and of the other index contours. In memory only (not for a DEM read in chunks).
    label_size, label_spacing : float, optional
        Font height in output pixels (default 11 px; 7 pt with a map scale's ``dpi``) and the
        least distance between labels along a line (default 25 font sizes).
    label_color : RGB, optional
        Colour of the label text (default ``contour_color``).
    size : int or (int, int), optional
        Output size in pixels: ``N`` the long side (the other keeps the grid's aspect, GDAL's
        ``-outsize N 0``); ``(W, H)`` exactly, over the DEM's extent (``-outsize W H``; pixels
        may be non-square); ``(W, 0)``/``(0, H)`` keep the aspect. Each side at most
        ``LIMITS["image_side"]`` = 16384.
    scale : float or str, optional
        Instead of ``size``: output pixels per DEM cell (``scale=4``: four times the grid); or,
        with ``dpi``, a map scale: ``scale=25000, dpi=300`` (or ``scale="1:25000"``) is 1:25000
        printed at 300 dpi, ``25000 * 0.0254 / 300`` = 2.117 m of ground per output pixel in
        both directions (QGIS print layout's scale and resolution).
    dpi : float, optional
        Print resolution of a map scale, at most ``LIMITS["dpi"]`` = 9600; only with
        ``scale`` (to record a DPI in a PNG: :func:`~sciviz_gbuf.compose.write_png` ``dpi=``).
    progress_bar : bool, default: False
        Show a progress bar.

    Returns
    -------
    (H, W, 4) uint8 RGBA
        On the DEM's grid (row 0 north), or on the output grid of ``size``/``scale`` over the
        same extent: sides rounded to whole pixels, the pixel size ``extent / side``. The
        DEM's transform and CRS georeference it (:func:`~sciviz_gbuf.compose.write_geotiff`
        scales the transform to the image's size). Nodata cells are transparent (alpha 0).

    Notes
    -----
    At another size the heights are first resampled onto the output grid
    (:func:`resample_heights`: clamped cubic convolution where the map is larger than the grid,
    area averages where it is smaller), then mapped as always: contour lines, relief and bands
    are computed per output pixel, so lines are smooth rather than stair-stepped, line widths
    and ``dense_spacing`` stay in output pixels, the relief uses the output pixel's size in
    metres, and the default intervals follow the output pixels (majors at least 6 output
    pixels apart). A DEM read in chunks (dask heights, out of core) is mapped one pixel per
    cell only: ``size``/``scale`` giving another grid are refused with an InputError.

    Raises
    ------
    InputError
        For anything :func:`read_dem` rejects, or an invalid parameter.
    """
    colour = _validate.rgb(contour_color, "contour_color")
    # before the DEM is read
    z_factor = _check_map_args(width, major_width, dense_spacing, size, scale, dpi, z_factor)
    labels = _validate.boolean(labels, "labels")
    relief_style(relief)
    font_px, spacing_px = label_options(label_size, label_spacing, dpi if scale else None)
    text_colour = colour if label_color is None else _validate.rgb(label_color, "label_color")
    d, options = _map_dem(
        dem, interval=interval, major_interval=major_interval, contours=contours, width=width,
        major_width=major_width, dense_spacing=dense_spacing, generalize=generalize,
        bands=bands, cmap=cmap, sea_level=sea_level, vmin=vmin, vmax=vmax, relief=relief,
        azimuth=azimuth, altitude=altitude, z_factor=z_factor, variant=variant,
        shadows=shadows, sky_view=sky_view, size=size, scale=scale, dpi=dpi, in_memory=labels,
    )  # fmt: skip
    if _dask.is_dask(d.heights):
        return lazy_topographic_map(d, colour, **options)
    with progress(progress_bar, 4, "topographic map") as bar:
        bar.step("contours")
        dx, dy = d.pixel_size
        layers = map_layers(d.heights, dx=dx, dy=dy, **options, bar=bar)
        placed = []
        if labels:
            placed = labels_of_grid(d, interval, major_interval, font_px, spacing_px)
            if layers["ink"] is not None:
                # the line is broken under the label (every line there, as a cartographer's mask)
                layers["ink"] = layers["ink"] * (1.0 - label_boxes(placed, d.shape))
        bar.step("composite")
        out = composite(layers, d.heights, colour)
        if placed:
            out = draw_labels(out, placed, font_px, text_colour)
        bar.step("done")
    return out


def _check_map_args(width, major_width, dense_spacing, size, scale, dpi, z_factor):
    """The checks of a map's sizes before its DEM is read; returns the checked ``z_factor``."""
    check_line_sizes(width=width, major_width=major_width, dense_spacing=dense_spacing)
    check_size_options(size, scale, dpi)
    return check_z_factor(z_factor)


def _map_dem(
    dem, *, size, scale, dpi, generalize, in_memory: bool = False, **rest
) -> tuple[DEM, dict]:
    """``(dem, options of map_layers)`` of :func:`topographic_map`'s arguments (checked by
    :func:`_check_map_args`): the DEM read and on the map's grid (resampled for another
    ``size``/``scale``). ``in_memory``: refuse chunked heights."""
    d = as_dem(dem)
    if in_memory:
        check_in_memory(d)
    if not _dask.is_dask(d.mask) and not d.mask.any():
        # A fully transparent picture would look like success.
        raise InputError(f"{d.source or 'heights'}: every cell is nodata: nothing to map")
    # Another size: the heights on the output grid first, then the map as always.
    d = map_grid(d, size=size, scale=scale, dpi=dpi)
    # The map's options, the same for the in-memory and the chunked map.
    return d, {**rest, "generalize": _validate.boolean(generalize, "generalize")}


def write_topographic_png(
    path: str | os.PathLike,
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    contours: bool = True,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    generalize: bool = True,
    contour_color: Sequence[float] = CONTOUR_COLOR,
    bands: bool | str | float | Sequence[float] = True,
    cmap: str | object | None = None,
    sea_level: float | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    relief: bool = True,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float | None = None,
    variant: str = "regular",
    shadows: bool = False,
    sky_view: bool = False,
    size: int | Sequence[int] | None = None,
    scale: float | str | None = None,
    dpi: float | None = None,
    geotiff: str | os.PathLike | None = None,
) -> tuple[int, int]:
    """Write :func:`topographic_map` of a DEM as a PNG, block of rows by block of rows as
    they are mapped: the same pixels, the whole map never in memory; with ``geotiff``, the
    same map as a Cloud-Optimised GeoTIFF too, from the same blocks.

    The in-memory map makes each layer of the whole grid (relief, contour ink, band
    heights) and then the RGBA image, one after the other, and only then deflates it. Here
    what needs the whole grid comes first, as the in-memory map computes it (the height
    range, the contour intervals, the relief's automatic z factor); then the map is cut into
    blocks of at least ``STREAM_ROWS`` rows, and on every core a block is read from the
    heights with the halo its layers need, mapped by the function the chunked map computes a
    chunk with (:func:`~.terrain_chunked.window_map`: each layer's cells see the neighbourhood
    they see in memory, so the pixels are the same) and its rows deflated at once
    (:func:`~sciviz_gbuf.writers.png.encode_png_rows`); the file takes the blocks in order.
    So mapping and deflating overlap, no array of the grid's size is made after the heights,
    and memory holds the heights and a few blocks.

    Maps below ``LARGE_IMAGE`` pixels, and those that need the whole grid at once (cast
    ``shadows``, texture and local-relief styles, labels) or are read in chunks, are made by
    :func:`topographic_map` and written by :func:`~sciviz_gbuf.writers.png.write_png`.

    Parameters
    ----------
    path : str or path-like
        The PNG to write (atomically: a failure leaves no file).
    dem, interval, major_interval, contours, width, major_width, dense_spacing, generalize,
    contour_color, bands, cmap, sea_level, vmin, vmax, relief, azimuth, altitude, z_factor,
    variant, shadows, sky_view, size, scale, dpi
        As :func:`topographic_map`; ``dpi`` is recorded in the PNG (and with ``scale``
        sizes the map, as there).
    geotiff : str or path-like, optional
        Also write the map as a georeferenced COG (``.tif``): the DEM's CRS, the map's pixel
        size, the layout of :func:`~sciviz_gbuf.writers.cog.write_cog` (512-pixel tiles,
        overviews), the same bytes as ``write_cog(topographic_map(...), dem=...)``. A
        streamed map's blocks are then whole rows of tiles, and each block's tiles are
        deflated where the block is mapped. Checked before any mapping; written atomically
        after the PNG.

    Returns
    -------
    (int, int)
        The map's height and width in pixels.

    Raises
    ------
    InputError
        As :func:`topographic_map`, or a path :func:`~sciviz_gbuf.writers.png.write_png`
        refuses.
    OutputError
        The file could not be written completely.
    """
    options = {k: v for k, v in locals().items() if k not in ("path", "dem", "geotiff")}
    return _write_map(dem, path, geotiff, options)


def write_topographic_cog(
    path: str | os.PathLike,
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    overview_png: str | os.PathLike | None = None,
    overview_size: int = 2048,
    **options: object,
) -> tuple[int, int]:
    """Write :func:`topographic_map` of a DEM as a Cloud-Optimised GeoTIFF, block of rows by
    block of rows as they are mapped, each block's tiles deflated where it is mapped (as
    :func:`write_topographic_png` streams a PNG): the bytes of
    ``write_cog(topographic_map(dem, **options), path, dem=...)``, the whole map never in
    memory.

    Parameters
    ----------
    path : str or path-like
        The ``.tif`` to write (atomically).
    dem : DEM, path or (H, W) array
        As :func:`topographic_map`; the COG takes its georeference (the map's pixel size).
    overview_png, overview_size
        As :func:`~sciviz_gbuf.writers.cog.write_cog`: a PNG preview read from the COG's
        overviews.
    **options
        The keyword options of :func:`write_topographic_png` but ``geotiff`` (those of
        :func:`topographic_map`, and ``dpi``).

    Returns
    -------
    (int, int)
        The map's height and width in pixels.

    Raises
    ------
    InputError
        An unknown option, or as :func:`topographic_map` and
        :func:`~sciviz_gbuf.writers.cog.write_cog`.
    OutputError
        The COG or its preview could not be written completely: neither is left.
    """
    defaults = _write_defaults()
    unknown = sorted(set(options) - set(defaults))
    if unknown:
        raise InputError(f"{unknown[0]}: not an option of write_topographic_cog "
                         f"(expected one of {', '.join(sorted(defaults))})")  # fmt: skip
    return _write_map(dem, None, path, {**defaults, **options}, overview_png, overview_size)


def _write_defaults() -> dict:
    """The map options of :func:`write_topographic_png` and their defaults."""
    import inspect

    params = inspect.signature(write_topographic_png).parameters
    return {k: p.default for k, p in params.items() if k not in ("path", "dem", "geotiff")}


#: The options of :func:`write_topographic_png` that size, scale and colour the map as a
#: whole; the others are its layers' (:func:`_map_dem`).
_FRAME_OPTIONS = ("contour_color", "z_factor", "size", "scale", "dpi")


def _write_map(
    dem: DEM | str | os.PathLike | np.ndarray, png: str | os.PathLike | None,
    cog: str | os.PathLike | None, o: dict, overview_png: str | os.PathLike | None = None,
    overview_size: int = 2048,
) -> tuple[int, int]:  # fmt: skip
    """:func:`write_topographic_png` (``png``, and a COG ``cog`` if given) and
    :func:`write_topographic_cog` (``png`` None) with their options ``o``."""
    opts = {k: v for k, v in o.items() if k not in _FRAME_OPTIONS}
    colour = _validate.rgb(o["contour_color"], "contour_color")
    dpi, size, scale = o["dpi"], o["size"], o["scale"]
    map_dpi = dpi if scale is not None else None  # with a scale it sizes the map too
    z_factor = _check_map_args(o["width"], o["major_width"], o["dense_spacing"], size, scale,
                               map_dpi, o["z_factor"])  # fmt: skip
    style = relief_style(o["relief"])
    d, options = _map_dem(dem, **opts, z_factor=z_factor, size=size, scale=scale, dpi=map_dpi)
    h, w = d.shape
    if cog is not None:
        check_cog_target(cog, d, overview_png, overview_size)  # before any mapping
    whole = o["shadows"] or style in ("texture", "local_relief") or _dask.is_dask(d.heights)
    if whole or h * w < LARGE_IMAGE:
        image = topographic_map(d, contour_color=o["contour_color"], **opts, z_factor=z_factor)
        if png is not None:
            write_png(png, image, dpi=dpi)
        if cog is not None:
            write_cog(image, cog, dem=d, overview_png=overview_png, overview_size=overview_size)
        return image.shape[0], image.shape[1]
    block, halo = _map_block(d, colour, options)
    rows = max(STREAM_ROWS, STREAM_HALOS * halo)
    if cog is not None:
        rows = -(-rows // BLOCK) * BLOCK  # whole rows of COG tiles in every block
    starts = range(0, h, rows)
    z = d.heights

    def mapped(r0: int) -> np.ndarray:
        r1 = min(r0 + rows, h)
        a0, a1 = max(0, r0 - halo), min(h, r1 + halo)
        with on_this_thread():  # the other cores map other blocks
            return block(z[a0:a1], (slice(r0 - a0, r1 - a0), slice(0, w)))

    chunks = (tuple(min(rows, h - r0) for r0 in starts), (w,))
    target = nullcontext() if cog is None else cog_target(
        cog, (h, w, 4), chunks, dem=d, overview_png=overview_png, overview_size=overview_size,
    )  # fmt: skip
    with target as sink:

        def encode(r0: int) -> tuple[bytes, int, int] | None:
            rgba = mapped(r0)
            if sink is not None:
                sink.encode(rgba, r0, 0)  # the COG's tiles, deflated here
            return None if png is None else encode_png_rows(rgba, last=r0 + rows >= h)

        encoded = _in_order(encode, starts, threads())
        if png is None:
            for _ in encoded:
                pass
        else:
            write_png_blocks(png, (h, w, 4), encoded, dpi=dpi)
    return h, w


def _map_block(d: DEM, colour: np.ndarray, options: dict) -> tuple[Callable, int]:
    """:func:`~.terrain_chunked.window_map` of an in-memory DEM with the checked options of
    :func:`_map_dem`: the whole-grid numbers as :func:`~._map.map_layers` takes them (the same
    functions on the same heights), every option checked before a block is mapped."""
    o = options
    z = d.heights
    dx, dy = d.pixel_size
    style = relief_style(o["relief"])
    lo, hi, interval, major = contour_intervals(z, o["interval"], o["major_interval"])
    vmin, vmax = o["vmin"], o["vmax"]
    tables = map_band_tables(o["bands"], interval, major, o["cmap"], lo if vmin is None else vmin,
                             hi if vmax is None else vmax, o["sea_level"])  # fmt: skip
    z_factor = None if style is None else grid_z_factor(z, o["z_factor"], dx, dy)
    ink, light, flat, bands = map_parts(
        style, tables, dx, dy, interval=interval, major_interval=major, width=o["width"],
        major_width=o["major_width"], dense_spacing=o["dense_spacing"],
        generalize=o["generalize"], bands=o["bands"], azimuth=o["azimuth"],
        altitude=o["altitude"], z_factor=z_factor, variant=o["variant"],
    )  # fmt: skip
    halo = RELIEF_HALO + (relief_reach(style, dx, dy) if style is not None else 0)
    return window_map(colour, tables, ink if o["contours"] else None, light,
                      bool(o["sky_view"]) and light is not None, dx, dy, flat, bands,
                      halo)  # fmt: skip


def _in_order(fn: Callable[[int], object], items: Iterable[int], workers: int) -> Iterator[object]:
    """``fn`` of each item, in order, computed on ``workers`` threads at most two items
    ahead each (memory for a few blocks); the rest cancelled if the consumer stops."""
    it = iter(items)
    pool = ThreadPoolExecutor(max_workers=max(1, workers), thread_name_prefix="sciviz_gbuf_map")
    try:
        pending = deque(pool.submit(fn, k) for k in itertools.islice(it, 2 * max(1, workers)))
        while pending:
            result = pending.popleft().result()
            nxt = next(it, None)
            if nxt is not None:
                pending.append(pool.submit(fn, nxt))
            yield result
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
