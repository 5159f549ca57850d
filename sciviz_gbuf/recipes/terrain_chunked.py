"""Plan-view topographic maps of DEMs too large for memory: the map of :mod:`.terrain`, chunk
by chunk on dask, with the same pixels.

Every layer is an operator with a bounded stencil (:mod:`sciviz_gbuf._dask`): contour lines
(1 cell; generalised, plus the smoothing's reach and the largest ring removed, see
:func:`~sciviz_gbuf.filters.contours.contour_halo`), the relief (GDAL's 3x3 window on a grid
whose nodata ring is extrapolated: 1 + 2 cells), the sky view (its ray length in cells), the
colour bands and the composite (the cell itself). What needs the whole grid comes first, in
one reduction pass over the heights: the height range (colour map ends, default contour
intervals) and the median slope on :func:`~.terrain.slope_lattice` (default contour
intervals; with ``z_factor=None`` also the median ground slope, the relief's automatic z
factor). Giving ``interval``/``major_interval``, ``vmin``/``vmax`` and a ``z_factor`` (or
``relief=False``) skips that pass.
Cast shadows reach across the whole grid and are refused.
"""

from __future__ import annotations

import numpy as np

from .. import _dask as _chunks
from ..errors import InputError
from ..filters import hillshade
from ..filters import sky_view as sky_view_factor
from ..filters.hillshade import FILL_RING_RADIUS
from ..filters.hillshade import RADIUS as HILLSHADE_RADIUS
from ..filters.terrain_light import default_sky_radius, sky_view_reach
from ..readers import DEM
from ._intervals import choose_intervals, median_ground_slope, median_slope, slope_lattice
from ._map import (
    composite,
    map_band_heights,
    map_band_tables,
    map_contour_halo,
    map_contours,
    relief_z_factor,
)
from ._relief import relief_flat, relief_reach, relief_shade, relief_style

__all__ = ["RELIEF_HALO", "lazy_topographic_map", "map_parts", "window_map"]

#: Stencil radius of a map's relief: GDAL's 3x3 window on the grid whose nodata ring is
#: extrapolated from up to 2 cells further.
RELIEF_HALO = HILLSHADE_RADIUS + FILL_RING_RADIUS


def _statistics(
    z, interval, major_interval, vmin, vmax, name: str = "heights", ground=None
) -> tuple[float, float, float, float | None, float]:
    """Height range, contour intervals and, with ``ground = (dx, dy)``, the median ground slope
    (NaN without), from one reduction pass when they are not given: the same lattice cells,
    and so the same numbers, as the in-memory map."""
    import dask.array as da

    need_range = vmin is None or vmax is None or (interval is None and major_interval is None)
    need_slope = interval is None and major_interval is None
    lo = hi = float("nan")
    slope = None
    ground_slope = float("nan")
    lattice = slope_lattice(z) if need_slope or ground is not None else None
    if need_range or lattice is not None:
        lo, hi, *cells = _chunks.reduce(
            da.nanmin(z), da.nanmax(z), *(lattice if lattice is not None else ())
        )
        lo, hi = float(lo), float(hi)
        if not np.isfinite(lo):
            raise InputError(f"{name}: every cell is nodata: nothing to map")
        if need_slope:
            slope = median_slope(*cells) if cells else float("nan")
        if ground is not None and cells:
            ground_slope = median_ground_slope(*cells, *ground)
    lo, hi, interval, major_interval = choose_intervals(lo, hi, slope, interval, major_interval)
    return lo, hi, interval, major_interval, ground_slope


def _relief_block(heights: np.ndarray, *, style: str = "hillshade", **opts) -> np.ndarray:
    return relief_shade(heights, style, **opts)


def lazy_topographic_map(
    d: DEM,
    colour: np.ndarray,
    *,
    interval,
    major_interval,
    contours: bool,
    width: float,
    major_width: float,
    dense_spacing: float,
    generalize: bool,
    bands,
    cmap,
    sea_level,
    vmin,
    vmax,
    relief: bool,
    azimuth: float,
    altitude: float,
    z_factor: float | None,
    variant: str,
    shadows: bool,
    sky_view: bool,
):
    """:func:`~.terrain.topographic_map` of a DEM whose heights are a dask array: a lazy
    (H, W, 4) uint8 dask array, chunked like the heights, bit-identical to the in-memory map.
    Parameters as there; ``shadows=True`` is refused (its reach is the whole grid)."""
    import dask.array as da

    if shadows:
        raise InputError(
            "shadows: cast shadows may come from anywhere along the sun's ray across the whole "
            "grid, so they cannot be drawn chunk by chunk; use sky_view=True (bounded reach) or "
            "an in-memory DEM"
        )
    z = d.heights
    dx, dy = d.pixel_size
    style = relief_style(relief)
    relief = style is not None
    # the stencil radius of the relief style (texture shading and local relief take their
    # contrast from the whole grid and are refused here)
    relief_halo = RELIEF_HALO + (relief_reach(style, dx, dy) if relief else 0)
    auto_z = relief and z_factor is None
    lo, hi, interval, major_interval, ground_slope = _statistics(
        z, interval, major_interval, vmin, vmax, d.source or "heights",
        ground=(dx, dy) if auto_z else None,
    )  # fmt: skip
    if relief:
        z_factor = relief_z_factor(z_factor, ground_slope)
    tables = map_band_tables(
        bands, interval, major_interval, cmap, lo if vmin is None else vmin,
        hi if vmax is None else vmax, sea_level,
    )  # fmt: skip
    ink_options, light, flat, band_options = map_parts(
        style, tables, dx, dy, interval=interval, major_interval=major_interval, width=width,
        major_width=major_width, dense_spacing=dense_spacing, generalize=generalize,
        bands=bands, azimuth=azimuth, altitude=altitude, z_factor=z_factor, variant=variant,
    )  # fmt: skip
    if _chunks.windows_of(z) is not None:
        return _windowed_map(
            z, colour, tables, ink_options if contours else None, light,
            sky_view and relief, dx, dy, flat, band_options, relief_halo,
        )  # fmt: skip
    layers: dict[str, object] = {}
    if band_options is not None:
        band_z = _band_z(z, band_options)
        if band_z is not None:
            layers["band_z"] = band_z
    if contours:
        layers["ink"] = map_contours(z, **ink_options)
    if relief:
        layers["sh"] = _chunks.map_stencil(
            _relief_block,
            {"heights": z},
            halo=relief_halo,
            dx=dx,
            dy=dy,
            **light,
        )
        if sky_view:
            layers["sky"] = sky_view_factor(z, dx=dx, dy=dy, z_factor=z_factor)
    # Layers whose halo was wider than a chunk come back coarser: back to the map's chunks.
    layers = {k: v if v.chunks == z.chunks else v.rechunk(z.chunks) for k, v in layers.items()}
    names = list(layers)
    has_tables = tables is not None

    def block(heights: np.ndarray, *parts: np.ndarray) -> np.ndarray:
        lay = dict(zip(names, parts, strict=True))
        lay.update(tables=tables if has_tables else None, relief=relief, flat=flat)
        lay.setdefault("ink", None)
        return composite(lay, heights, colour)

    return da.map_blocks(
        block,
        z,
        *(layers[k] for k in names),
        new_axis=2,
        chunks=(*z.chunks, (4,)),
        dtype=np.uint8,
        meta=np.empty((0, 0, 0), np.uint8),
    )


def map_parts(
    style: str | None, tables, dx: float, dy: float, *, interval, major_interval, width,
    major_width, dense_spacing, generalize, bands, azimuth, altitude, z_factor, variant,
) -> tuple[dict, dict | None, float, dict | None]:  # fmt: skip
    """``(ink options, light, flat, band options)`` of a map whose whole-grid numbers are
    known (``interval``/``major_interval`` chosen, ``tables`` made, ``z_factor`` a number):
    what the chunked and the streamed maps give :func:`window_map`. ``light`` (with the
    style) and the shade of flat ground only with a relief ``style`` (checked now: None and
    1 without); band options only for a generalised map with bands."""
    lines = {"interval": interval, "major_interval": major_interval, "width": width,
             "major_width": major_width}  # fmt: skip
    ink = {**lines, "dense_spacing": dense_spacing, "generalize": generalize}
    light = None
    flat = 1.0
    if style is not None:
        light = {"azimuth": azimuth, "altitude": altitude, "z_factor": z_factor,
                 "variant": variant}  # fmt: skip
        hillshade(np.zeros((3, 3), np.float32), dx=dx, dy=dy, **light)  # checks now
        flat = relief_flat(style, dx=dx, dy=dy, **light)
        light["style"] = style
    # generalised maps colour their bands by the heights their lines are drawn from
    band_options = {**lines, "bands": bands} if generalize and tables is not None else None
    return ink, light, flat, band_options


def _band_z(z, band_options: dict):
    """:func:`~._map.map_band_heights` of ``z`` (numpy or dask) with the map's options."""
    o = band_options
    return map_band_heights(
        z, o["bands"], interval=o["interval"], major_interval=o["major_interval"],
        width=o["width"], major_width=o["major_width"],
    )  # fmt: skip


def _windowed_map(z, *args, **kwargs):
    """The map of heights that can be read by window (:func:`~sciviz_gbuf._dask.map_windows`):
    one task per chunk reads the chunk with the widest halo any layer needs and computes every
    layer and the composite from it (:func:`window_map`, whose arguments follow ``z``); no
    task waits for another's data, so a worker's memory is that of the chunks it computes,
    whatever the DEM's size."""
    block, halo = window_map(*args, **kwargs)
    return _chunks.map_windows(block, z, halo=halo, dtype=np.uint8, bands=4)


def window_map(
    colour: np.ndarray,
    tables,
    ink_options: dict | None,
    light: dict | None,
    sky_view: bool,
    dx: float,
    dy: float,
    flat: float,
    band_options: dict | None = None,
    relief_halo: int = RELIEF_HALO,
):
    """``(block, halo)``: ``block(window, inner)`` computes every layer of the map and the
    composite from ``window``, heights read with up to ``halo`` cells around the cells
    ``inner`` (a (rows, cols) pair of slices) whose RGBA it returns. Each layer's cells see
    the same neighbourhood as in memory (a wider halo than a layer's own radius changes none
    of its cells), so the pixels are those of the in-memory map. ``ink_options``: the
    contours' options (None: no lines); ``light``: the relief's (with ``style``; None: no
    relief); ``band_options``: a generalised map's band heights' (None: the heights)."""
    halo = 0
    if ink_options is not None:
        # the contour stencil, plus with generalisation its smoothing and ring size
        halo = map_contour_halo(**ink_options)  # checks the options now
    if light is not None:
        halo = max(halo, relief_halo)
        if sky_view:
            halo = max(halo, sky_view_reach(default_sky_radius(dx, dy), dx, dy))
    if band_options is not None:
        # the lines' smoothing and ring size: the generalised lines' halo
        halo = max(halo, map_contour_halo(
            interval=band_options["interval"], major_interval=band_options["major_interval"],
            width=band_options["width"], major_width=band_options["major_width"],
            dense_spacing=1.0,
        ))  # fmt: skip

    def block(window: np.ndarray, inner: tuple[slice, slice]) -> np.ndarray:
        lay: dict = {"tables": tables, "relief": light is not None, "flat": flat, "ink": None}
        if ink_options is not None:
            lay["ink"] = map_contours(window, **ink_options)[inner]
        if light is not None:
            lay["sh"] = _relief_block(window, dx=dx, dy=dy, **light)[inner]
            if sky_view:
                zf = light["z_factor"]
                lay["sky"] = sky_view_factor(window, dx=dx, dy=dy, z_factor=zf)[inner]
        if band_options is not None:
            band_z = _band_z(window, band_options)
            if band_z is not None:
                lay["band_z"] = band_z[inner]
        return composite(lay, np.ascontiguousarray(window[inner]), colour)

    return block, halo
