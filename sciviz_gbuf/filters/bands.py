"""Colour bands of a height (or any scalar) image: discrete hypsometric tints, continuous ramps
and topo-bathymetry with a sea level (1990 §4.3: "to present absolute height, several discrete
colour bands are used; continuous colour change is also available")."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from . import _band_kernels as _bk

__all__ = ["BATHYMETRIC", "HYPSOMETRIC", "band_tables", "color_bands", "composite_map"]

# Land tints from lowland green through yellow and brown to rock grey and snow.
_LAND = (
    (0.34, 0.62, 0.38),
    (0.58, 0.76, 0.47),
    (0.85, 0.88, 0.58),
    (0.96, 0.87, 0.62),
    (0.86, 0.70, 0.50),
    (0.72, 0.56, 0.46),
    (0.72, 0.70, 0.68),
    (0.97, 0.97, 0.97),
)
# Sea tints from the deep (dark blue) to the shore (pale blue).
_SEA = ((0.08, 0.20, 0.45), (0.25, 0.48, 0.72), (0.62, 0.80, 0.92))
# Entries of the look-up table of continuous ramps (0.1% steps: below any visible step).
_LUT = 1024


def _colormap(name: str, colours) -> object:
    from matplotlib.colors import LinearSegmentedColormap

    return LinearSegmentedColormap.from_list(name, colours, N=_LUT)


#: The default colour maps, made on first use (matplotlib is imported then, not with the
#: module): ``HYPSOMETRIC``, the default land colour map of :func:`color_bands` (a matplotlib
#: ``Colormap``, green - yellow - brown - grey - white), and ``BATHYMETRIC``, its default sea
#: colour map, deep to shallow.
_DEFAULT_MAPS = {
    "HYPSOMETRIC": ("sciviz_hypsometric", _LAND),
    "BATHYMETRIC": ("sciviz_bathymetric", _SEA),
}


HYPSOMETRIC: object  # made by __getattr__ on first use
BATHYMETRIC: object


def __getattr__(name: str) -> object:
    if name in _DEFAULT_MAPS:
        cm = _colormap(*_DEFAULT_MAPS[name])
        globals()[name] = cm  # made once
        return cm
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _default_map(name: str) -> object:
    return globals()[name] if name in globals() else __getattr__(name)


def _lut(cm) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(cm(np.linspace(0.0, 1.0, _LUT)), np.float32)[:, :3])


def _scale(lo: float, hi: float) -> tuple[float, float]:
    """``(lo, (n - 1) / (hi - lo))`` of a ramp; scale 0 (the middle colour) when hi == lo."""
    return lo, ((_LUT - 1) / (hi - lo) if hi > lo else 0.0)


def band_tables(
    data: np.ndarray,
    *,
    interval: float | None,
    levels,
    base: float,
    cmap,
    vmin: float | None,
    vmax: float | None,
    sea_level: float | None,
    sea_cmap,
) -> tuple:
    """Checked parameters of :func:`color_bands` as the arguments ``(mode, base, q, levels,
    mids, land, sea, tab)`` of the band kernels; ``data`` are the valid heights (for the default
    ``vmin``/``vmax``; may be empty when both are given)."""
    if interval is not None and levels is not None:
        raise InputError("color_bands: give interval= or levels=, not both")
    base = _validate.finite(base, "base")
    land = _lut(_default_map("HYPSOMETRIC") if cmap is None else _validate.colormap(cmap, "cmap"))
    sea = _lut(
        _default_map("BATHYMETRIC")
        if sea_cmap is None
        else _validate.colormap(sea_cmap, "sea_cmap")
    )
    lo = float(data.min()) if vmin is None else _validate.finite(vmin, "vmin")
    hi = float(data.max()) if vmax is None else _validate.finite(vmax, "vmax")
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
        raise InputError(f"vmin, vmax: expected finite numbers with vmin <= vmax, got {lo}, {hi}")
    lv = mids = np.zeros(1)
    q = 1.0
    if interval is not None:
        mode, q = _bk.INTERVAL, _validate.positive(interval, "interval")
    elif levels is not None:
        mode, lv = _bk.LEVELS, _validate.levels(levels, "levels", limit="bands")
        # Band k lies between edges[k] and edges[k + 1]; the outer bands are as wide as their
        # neighbours (or 1 when there is a single level).
        gap_lo = lv[1] - lv[0] if lv.size > 1 else 1.0
        gap_hi = lv[-1] - lv[-2] if lv.size > 1 else 1.0
        edges = np.concatenate([[lv[0] - gap_lo], lv, [lv[-1] + gap_hi]])
        mids = (edges[:-1] + edges[1:]) / 2
    else:
        mode = _bk.CONTINUOUS
    if sea_level is None:
        tab = (*_scale(lo, hi), 0.0, 0.0, np.nan)
    else:
        s = _validate.finite(sea_level, "sea_level")
        # Heights below the sea level take the sea colours, by the height itself: a band
        # never puts land under the sea.
        tab = (*_scale(s, max(hi, s)), *_scale(min(lo, s), s), s)
    return (
        mode,
        np.float32(base),
        np.float32(q),
        lv.astype(np.float64),
        mids.astype(np.float64),
        land,
        sea,
        _float32(tab),
    )


def _float32(values) -> np.ndarray:
    """float32 copy; a ramp scale beyond float32 (a range below 1e-35) becomes inf, which the
    kernel handles like the end of the map."""
    with np.errstate(over="ignore"):
        return np.asarray(values, dtype=np.float32)


def color_bands(
    heights: np.ndarray,
    *,
    interval: float | None = None,
    levels: Sequence[float] | np.ndarray | None = None,
    base: float = 0.0,
    cmap: str | object | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    sea_level: float | None = None,
    sea_cmap: str | object | None = None,
    mask: np.ndarray | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Colour an image by height: discrete bands, a continuous ramp, or topo-bathymetry.

    Parameters
    ----------
    heights : (H, W) array
        Heights (or any scalar); NaN/inf are nodata.
    interval : float > 0, optional
        Discrete bands ``[base + n q, base + (n + 1) q)``, each one colour (that of its
        middle). Default: a continuous ramp. (Not bounded: the band of a pixel is computed
        from its height, so the work does not grow with the number of bands.)
    levels : sequence of float, optional
        Band edges instead of a regular ``interval``; at most ``LIMITS["bands"]`` = 4096.
    base : float, default: 0
        Offset of the regular bands.
    cmap : str or matplotlib Colormap, optional
        Colours of the land (or of everything without ``sea_level``); default
        :data:`HYPSOMETRIC` (green - yellow - brown - grey - white). Any matplotlib map works.
    vmin, vmax : float, optional
        Heights at the two ends of the colour map(s). Default: the range of the valid heights;
        give them explicitly to colour tiles of one map alike.
    sea_level : float, optional
        Topo-bathymetry: heights below it take ``sea_cmap`` over ``[vmin, sea_level]``, the rest
        ``cmap`` over ``[sea_level, vmax]``.
    sea_cmap : str or matplotlib Colormap, optional
        Default :data:`BATHYMETRIC` (deep blue to pale blue).
    mask : (H, W) bool, optional
        False marks nodata.
    out : (H, W, 4) float32 array, optional
        C-contiguous, writeable and apart from ``heights``: written and returned instead of a
        new array (an (H, W) image's colours are 16 bytes a cell: fresh memory costs more to
        touch than the kernel takes to fill it). Not with dask input.

    Returns
    -------
    (H, W, 4) float32 RGBA in [0, 1]: alpha 1 on data, 0 (and black) at nodata.
    """
    if _chunks.any_dask(heights, mask):
        if out is not None:
            raise InputError("out: not supported with dask input (the result is lazy)")
        return _chunked_bands(heights, mask, vmin, vmax, **{
            "interval": interval, "levels": levels, "base": base, "cmap": cmap,
            "sea_level": sea_level, "sea_cmap": sea_cmap})  # fmt: skip
    v = _validate.image(heights, "heights")
    m = _validate.mask(mask, v.shape)
    valid = np.isfinite(v) if m is None else np.isfinite(v) & m
    any_valid = bool(valid.any())
    extremes = np.zeros(1, np.float32)
    if any_valid and (vmin is None or vmax is None):
        # the tables need the valid heights' range only: no copy of the valid heights
        extremes = np.array(
            [np.min(v, where=valid, initial=np.inf), np.max(v, where=valid, initial=-np.inf)]
        )
    tables = band_tables(
        extremes,
        interval=interval,
        levels=levels,
        base=base,
        cmap=cmap,
        vmin=vmin,
        vmax=vmax,
        sea_level=sea_level,
        sea_cmap=sea_cmap,
    )
    if out is None:
        out = np.empty((*v.shape, 4), dtype=np.float32)
    else:
        out = _validate.out_array(out, (*v.shape, 4), heights)
    if not any_valid:
        out[:] = 0.0
        return out
    _bk.band_image(v, valid, *tables, out)
    return out


def _check_tables(tables: object) -> tuple:
    """``tables`` as :func:`band_tables` makes them, checked so the kernel cannot read past
    an array: a mode, two scalars, levels and band middles (one more than the levels), two
    (n, 3) colour tables and the 5 ramp numbers."""
    what = "tables: expected None or band_tables(...) of the map's options"
    try:
        mode, base, q, lv, mids, land, sea, tab = tables  # type: ignore[misc]
        ok = isinstance(mode, (int, np.integer)) and not isinstance(mode, (bool, np.bool_))
        ok = ok and int(mode) in (_bk.CONTINUOUS, _bk.INTERVAL, _bk.LEVELS)
        lv = np.ascontiguousarray(lv, dtype=np.float64)
        mids = np.ascontiguousarray(mids, dtype=np.float64)
        land = np.ascontiguousarray(land, dtype=np.float32)
        sea = np.ascontiguousarray(sea, dtype=np.float32)
        tab = np.ascontiguousarray(tab, dtype=np.float32)
        base, q = np.float32(_validate.finite(base, "base")), np.float32(q)
    except (TypeError, ValueError, InputError, OverflowError):
        raise InputError(f"{what}, got {_validate.brief(tables)}") from None
    ok = ok and lv.ndim == 1 and lv.size >= 1 and mids.ndim == 1
    ok = ok and mids.size >= (lv.size + 1 if int(mode) == _bk.LEVELS else 1)
    ok = ok and all(t.ndim == 2 and t.shape[0] >= 1 and t.shape[1] == 3 for t in (land, sea))
    ok = ok and tab.shape == (5,) and bool(np.isfinite(q) and q > 0)
    if not ok:
        raise InputError(f"{what}, got {_validate.brief(tables)}")
    return (int(mode), base, q, lv, mids, land, sea, tab)


def _chunked_bands(heights, mask, vmin, vmax, **params):
    """:func:`color_bands` chunk by chunk (each cell's colour is its own): the default
    ``vmin``/``vmax`` come first from one reduction pass over the valid heights."""
    import dask.array as da

    z = _chunks.as_dask("heights", heights, None)
    valid = da.isfinite(z)
    if mask is not None:
        valid &= _chunks.as_dask("mask", mask, z).astype(bool)
    if vmin is None or vmax is None:
        kept = da.where(valid, z, np.nan).astype(np.float32)
        lo, hi, n = _chunks.reduce(da.nanmin(kept), da.nanmax(kept), valid.sum())
        if n == 0:  # no valid cell: any range does (every cell is transparent)
            lo = hi = 0.0
        vmin = float(lo) if vmin is None else vmin
        vmax = float(hi) if vmax is None else vmax

    def block(heights, mask):
        return color_bands(heights, mask=mask, vmin=vmin, vmax=vmax, **params)

    color_bands(np.zeros((3, 3), np.float32), vmin=vmin, vmax=vmax, **params)  # checks now
    return da.map_blocks(
        block,
        z,
        valid,
        new_axis=2,
        chunks=(*z.chunks, (4,)),
        dtype=np.float32,
        meta=np.empty((0, 0, 0), np.float32),
    )


def composite_map(
    heights: np.ndarray,
    *,
    tables: tuple | None,
    relief: np.ndarray | None = None,
    flat: float = 1.0,
    shadow: np.ndarray | None = None,
    sky: np.ndarray | None = None,
    ink: np.ndarray | None = None,
    ink_color: Sequence[float] = (0.0, 0.0, 0.0),
) -> np.ndarray:
    """A topographic map's pixels in one fused pass (1990 §4.3, Fig. 11): band colours, lit by
    the relief, overdrawn with contour ink, as uint8 RGBA (no float image of the map is made).

    Parameters
    ----------
    heights : (H, W) array
        The heights; NaN cells come out transparent black.
    tables : tuple or None
        The band colours, :func:`band_tables` of the map's options; None: white paper.
    relief : (H, W) array, optional
        Hillshade in [0, 1]. The light is ``1/3 sky + 2/3 relief * shadow / flat``, 1 on open
        flat ground; below 1 it multiplies the colour, above 1 it lifts it up to halfway to
        white. None: no relief (``flat``, ``shadow`` and ``sky`` unused).
    flat : float
        The hillshade of open flat ground (the relief's normalisation).
    shadow, sky : (H, W) arrays, optional
        Cast-shadow light (0 in shadow) and sky-view factor; None: fully lit, open sky.
    ink, ink_color : (H, W) array and RGB, optional
        Contour ink in [0, 1] and its colour.

    Returns
    -------
    (H, W, 4) uint8 RGBA
    """
    z = _validate.image(heights, "heights")
    # The fused kernel indexes every layer and table without bounds checks: all are checked.
    colours = None if tables is None else _check_tables(tables)
    flat = _validate.positive(flat, "flat")
    for name, a in (("relief", relief), ("shadow", shadow), ("sky", sky), ("ink", ink)):
        if a is not None and np.shape(a) != z.shape:
            raise InputError(f"{name}: expected shape {z.shape} (like heights), got {np.shape(a)}")
    if colours is None:  # no bands: white paper (the kernel ignores the tables)
        colours = band_tables(
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

    def layer(a: np.ndarray | None, name: str) -> np.ndarray:
        # contiguous float32 always: one compiled signature of the kernel, not one per layout
        return empty if a is None else _validate.image(a, name)

    out = np.empty((*z.shape, 4), dtype=np.uint8)
    _bk.map_image_fast(
        z,
        tables is not None,
        *colours,
        relief is not None,
        layer(relief, "relief"),
        np.float32(flat),
        layer(shadow, "shadow"),
        layer(sky, "sky"),
        layer(ink, "ink"),
        _validate.rgb(ink_color, "ink_color"),
        out,
    )
    return out
