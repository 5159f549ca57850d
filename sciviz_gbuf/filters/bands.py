"""Colour bands of a height (or any scalar) image: discrete hypsometric tints, continuous ramps
and topo-bathymetry with a sea level (1990 §4.3: "to present absolute height, several discrete
colour bands are used; continuous colour change is also available")."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..compose import _colormap_of
from ..errors import InputError
from .operators import _finite, _image, _levels, _mask, _positive

__all__ = ["BATHYMETRIC", "HYPSOMETRIC", "color_bands"]

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


HYPSOMETRIC = _colormap("sciviz_hypsometric", _LAND)
"""Default land colour map of :func:`color_bands` (a matplotlib ``Colormap``)."""
BATHYMETRIC = _colormap("sciviz_bathymetric", _SEA)
"""Default sea colour map of :func:`color_bands`, deep to shallow."""


def _representative(v: np.ndarray, interval, levels, base: float) -> np.ndarray:
    """Each value replaced by the middle of its band (the value itself when continuous)."""
    if interval is not None:
        q = _positive(interval, "interval")
        with np.errstate(over="ignore", invalid="ignore"):  # huge heights: the end of the map
            return ((np.floor((v - base) / q) + 0.5) * q + base).astype(np.float32)
    if levels is None:
        return v
    lv = _levels(levels)
    # Band k lies between edges[k] and edges[k + 1]; the outer bands are as wide as their
    # neighbours (or 1 when there is a single level).
    gap_lo = lv[1] - lv[0] if lv.size > 1 else 1.0
    gap_hi = lv[-1] - lv[-2] if lv.size > 1 else 1.0
    edges = np.concatenate([[lv[0] - gap_lo], lv, [lv[-1] + gap_hi]])
    mids = (edges[:-1] + edges[1:]) / 2
    k = np.searchsorted(lv, v, side="right")
    return mids[k].astype(np.float32)


def _ramp(cm, v: np.ndarray, lo: float, hi: float) -> np.ndarray:
    lut = np.asarray(cm(np.linspace(0.0, 1.0, _LUT)), dtype=np.float32)[:, :3]
    if hi > lo:
        with np.errstate(over="ignore", invalid="ignore"):
            t = (v - np.float32(lo)) * np.float32((_LUT - 1) / (hi - lo))
    else:  # a constant image: the middle of the map
        t = np.full(v.shape, (_LUT - 1) / 2, dtype=np.float32)
    idx = np.clip(np.rint(np.nan_to_num(t, nan=0.0)), 0, _LUT - 1).astype(np.intp)
    return lut[idx]


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
) -> np.ndarray:
    """Colour an image by height: discrete bands, a continuous ramp, or topo-bathymetry.

    Parameters
    ----------
    heights : (H, W) array
        Heights (or any scalar); NaN/inf are nodata.
    interval : float > 0, optional
        Discrete bands ``[base + n q, base + (n + 1) q)``, each one colour (that of its
        middle). Default: a continuous ramp.
    levels : sequence of float, optional
        Band edges instead of a regular ``interval``.
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

    Returns
    -------
    (H, W, 4) float32 RGBA in [0, 1]: alpha 1 on data, 0 (and black) at nodata.
    """
    v = _image(heights, "heights")
    m = _mask(mask, v.shape)
    valid = np.isfinite(v) if m is None else np.isfinite(v) & m
    if interval is not None and levels is not None:
        raise InputError("color_bands: give interval= or levels=, not both")
    base = _finite(base, "base")
    land = HYPSOMETRIC if cmap is None else _colormap_of(cmap, "cmap")
    sea = BATHYMETRIC if sea_cmap is None else _colormap_of(sea_cmap, "sea_cmap")
    out = np.zeros((*v.shape, 4), dtype=np.float32)
    if not valid.any():
        return out
    data = v[valid]
    lo = float(data.min()) if vmin is None else float(vmin)
    hi = float(data.max()) if vmax is None else float(vmax)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
        raise InputError(f"vmin, vmax: expected finite numbers with vmin <= vmax, got {lo}, {hi}")
    rep = _representative(data, interval, levels, base)
    if sea_level is None:
        rgb = _ramp(land, rep, lo, hi)
    else:
        s = float(sea_level)
        if not np.isfinite(s):
            raise InputError(f"sea_level: expected a finite number, got {sea_level!r}")
        below = data < s  # by the height itself: a band never puts land under the sea
        rgb = np.empty((data.size, 3), dtype=np.float32)
        rgb[below] = _ramp(sea, rep[below], min(lo, s), s)
        rgb[~below] = _ramp(land, rep[~below], s, max(hi, s))
    out[valid, :3] = rgb
    out[valid, 3] = 1.0
    return out
