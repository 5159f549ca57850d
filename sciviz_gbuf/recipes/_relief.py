"""The relief styles of a plan-view map: the shade that lights its colour bands.

Every style is a grey shade in [0, 1] built on the map's hillshade and blended the way RVT's
blender does (Kokalj & Somrak 2019: each layer normalised to [0, 1] by a fixed range, then
laid over the result of the layers below it with a blend mode and an opacity), and divided by
its own value on open flat ground, so that flat ground keeps the bands' colours whatever the
style (:func:`~._map.relief_light`).

======================  ==================================================================
style                   layers, from the bottom (blend mode, opacity)
======================  ==================================================================
``hillshade``           GDAL's hillshade ``H`` (the default)
``vat``                 RVT's "VAT - Archaeological": ``H`` (normal, 100 %); slope
                        0-50 deg, inverted (luminosity, 50 %); positive openness 68-93 deg
                        (overlay, 50 %); sky-view factor 0.7-1 (multiply, 25 %). Openness
                        and sky view over 16 directions and 10 cells, RVT's defaults.
``openness``            ``H``; positive openness 68-93 deg, VAT's range (normal, 50 %):
                        valleys and hollows dark, ridges light, whatever the sun
``texture``             ``H``; Brown's texture shading, alpha 0.5, ``-q..q`` to [0, 1]
                        (normal, 50 %): the drainage network of every scale
``local_relief``        ``H``; the simple local relief model, 20 cells, ``-q..q`` to [0, 1]
                        (normal, 50 %): the landforms smaller than 20 cells
======================  ==================================================================

``q`` is the 99th percentile of the absolute values over the map (its contrast; the value 0
is mid grey). Normal at opacity ``o`` is ``o a + (1 - o) b`` for the layer ``a`` laid over
``b``; overlay is RVT's ``2 b a`` where ``b <= 0.5``, else ``1 - 2 (1 - b)(1 - a)``; the
luminosity of a grey layer is the layer.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..filters import fill_nodata_ring, hillshade, local_relief, openness, texture_shade
from ..filters import sky_view as sky_view_factor
from ..filters.terrain_light import sky_view_reach
from .map_options import RELIEFS

__all__ = [
    "RELIEFS",
    "VAT_CELLS",
    "relief_contrast",
    "relief_flat",
    "relief_reach",
    "relief_shade",
    "relief_style",
]

#: Ray length of VAT's openness and sky view, in cells (RVT's default radius).
VAT_CELLS = 10
_DIRECTIONS = 16
#: Fixed layer ranges of RVT's VAT: slope (deg), openness (deg), sky-view factor.
_SLOPE_RANGE = (0.0, 50.0)
_OPENNESS_RANGE = (68.0, 93.0)
_SKY_RANGE = (0.7, 1.0)
_TEXTURE_DETAIL = 0.5
_LOCAL_RELIEF_CELLS = 20


def relief_style(relief: object) -> str | None:
    """The style of ``relief=``: True is ``'hillshade'``, False or None no relief, a name one
    of :data:`RELIEFS` (``-`` and ``_`` alike)."""
    if relief is None or relief is False:
        return None
    if relief is True:
        return "hillshade"
    if isinstance(relief, str) and relief.replace("-", "_") in RELIEFS:
        return relief.replace("-", "_")
    raise InputError(f"relief: expected True, False or one of {', '.join(RELIEFS)}, got {relief!r}")


def _radius(dx: float, dy: float) -> float:
    return VAT_CELLS * max(float(dx), float(dy))


def relief_reach(style: str, dx: float, dy: float) -> int:
    """How many cells beyond the hillshade's 3x3 window a style reads (for chunks' halos);
    the styles with a contrast of the whole map are refused."""
    if style in ("vat", "openness"):
        return sky_view_reach(_radius(dx, dy), dx, dy)
    if style in ("texture", "local_relief"):
        raise InputError(
            f"relief: {style!r} takes its contrast from the whole map, so a map read in "
            "chunks cannot be lit by it; use relief='vat', 'openness' or 'hillshade', or a DEM "
            "in memory (filters.texture_shade and local_relief themselves take dask arrays)"
        )
    return 0


def _norm(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return np.clip((values - np.float32(lo)) / np.float32(hi - lo), 0.0, 1.0).astype(np.float32)


def _overlay(top: np.ndarray, bottom: np.ndarray, opacity: float) -> np.ndarray:
    """RVT's overlay of ``top`` on ``bottom`` at ``opacity``."""
    blended = np.where(bottom > 0.5, 1 - 2 * (1 - bottom) * (1 - top), 2 * bottom * top)
    return (opacity * blended + (1 - opacity) * bottom).astype(np.float32)


def _blend(style: str, h, slope=None, opened=None, sky=None, detail=None) -> np.ndarray:
    """The style's blend of its normalised layers over the hillshade ``h``."""
    h = np.asarray(h, np.float32)
    if style == "vat":
        # luminosity of a grey layer over a grey one is the layer itself
        inverted = 1.0 - _norm(slope, *_SLOPE_RANGE)
        base = (0.5 * inverted + 0.5 * h).astype(np.float32)
        base = _overlay(_norm(opened, *_OPENNESS_RANGE), base, 0.5)
        return (base * (0.75 + 0.25 * _norm(sky, *_SKY_RANGE))).astype(np.float32)
    # the other styles: their layer laid over the hillshade (normal, 50 %)
    layer = _norm(opened, *_OPENNESS_RANGE) if style == "openness" else detail
    return (0.5 * np.asarray(layer, np.float32) + 0.5 * h).astype(np.float32)


def relief_contrast(values: np.ndarray) -> float:
    """``q`` of the texture and local relief styles: the 99th percentile of ``|values|`` over
    the finite ones (1 when there are none or all are 0)."""
    finite = np.abs(values[np.isfinite(values)])
    q = float(np.percentile(finite, 99)) if finite.size else 0.0
    return q if q > 0 else 1.0


def relief_flat(style: str, dx: float, dy: float, **light) -> float:
    """The style's shade on open flat ground: hillshade ``sin(altitude)``, no slope, openness
    90 deg, the whole sky, no texture or local relief."""
    h = float(hillshade(np.zeros((3, 3), np.float32), dx=dx, dy=dy, **light)[1, 1])
    one = np.ones(1, np.float32)
    if style == "hillshade":
        value = h
    else:
        value = float(_blend(style, h * one, 0 * one, 90 * one, one, 0.5 * one)[0])
    return max(value, 1e-3)


def relief_shade(
    z: np.ndarray, style: str, *, dx: float, dy: float, contrast: float | None = None, **light
) -> np.ndarray:
    """The shade of ``style`` on the heights ``z`` (NaN nodata), in [0, 1]: GDAL's hillshade
    with ``light`` (azimuth, altitude, z_factor, variant) and the style's layers, at the
    same ``z_factor``. ``contrast`` is ``q`` of texture and local relief (default: that of
    ``z``, :func:`relief_contrast`)."""
    h = hillshade(fill_nodata_ring(z), dx=dx, dy=dy, **light)
    if style == "hillshade":
        return h
    zf = light.get("z_factor", 1.0)
    zf = 1.0 if zf is None else float(zf)
    ray = {"dx": dx, "dy": dy, "directions": _DIRECTIONS, "radius": _radius(dx, dy),
           "z_factor": zf}  # fmt: skip
    if style in ("vat", "openness"):
        opened = openness(z, kind="positive", **ray)
        if style == "openness":
            return _blend(style, h, opened=opened)
        # GDAL's slope from the same 3x3 window: the hillshade of a sun at the zenith is
        # cos(slope)
        zenith = hillshade(fill_nodata_ring(z), dx=dx, dy=dy, altitude=90.0, z_factor=zf)
        slope = np.degrees(np.arccos(np.clip(zenith, 0.0, 1.0)))
        return _blend(style, h, slope=slope, opened=opened, sky=sky_view_factor(z, **ray))
    if style == "texture":
        detail = texture_shade(z, detail=_TEXTURE_DETAIL, dx=dx, dy=dy, z_factor=zf)
    else:
        detail = local_relief(z, dx=dx, dy=dy, z_factor=zf)  # 20 cells, RVT's default
    q = relief_contrast(detail) if contrast is None else float(contrast)
    # rounding noise of flat ground is no relief: a floor of a millionth of the height range
    finite = z[np.isfinite(z)]
    span = float(finite.max() - finite.min()) if finite.size else 0.0
    q = max(q, 1e-6 * (span + 1.0))
    scaled = np.clip(0.5 + 0.5 * detail / np.float32(q), 0.0, 1.0)
    return _blend(style, h, detail=scaled)
