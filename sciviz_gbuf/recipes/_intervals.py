"""Contour intervals of height data: round numbers, chosen from the range and the typical slope
(shared by the terrain, bird's-eye, medical and surface recipes and the explorer)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import InputError

__all__ = [
    "MIN_MAJOR_SPACING",
    "choose_intervals",
    "contour_intervals",
    "median_ground_slope",
    "median_slope",
    "nice_intervals",
    "round_up",
    "slope_lattice",
    "typical_slope",
]


def round_up(value: float) -> float:
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
        major = max(major, round_up(slope * spacing))
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


def median_ground_slope(
    base: np.ndarray, east: np.ndarray, south: np.ndarray, dx: float, dy: float
) -> float:
    """The median ground slope, rise over run (dimensionless), of the lattice cells of
    :func:`slope_lattice` on cells ``dx`` by ``dy`` in the heights' units (metres: a DEM's
    ``pixel_size``), where not flat (like :func:`median_slope`); NaN without such a cell."""
    g = np.hypot((east - base) / np.float64(dx), (south - base) / np.float64(dy))
    g = g[np.isfinite(g) & (g > 0)]
    return float(np.median(g)) if g.size else float("nan")


def contour_intervals(
    z: np.ndarray,
    interval: float | None,
    major_interval: float | None,
    *,
    pixels_per_sample: float = 1.0,
    check_spacing: bool = False,
) -> tuple[float, float, float, float | None]:
    """``(lo, hi, interval, major_interval)`` of a height image: its valid range (0, 1 if
    none) and the contour intervals, the given ones or :func:`nice_intervals` on its slope;
    ``major_interval`` alone implies minors at a fifth of it. ``pixels_per_sample``: output
    pixels per sample of ``z`` (1 / supersampling), for the slope in output pixels.

    ``check_spacing``: given intervals whose major lines (the minors without majors) would be
    closer than :data:`MIN_MAJOR_SPACING` pixels on the median slope raise an InputError
    naming the useful range: such lines never thin out (Eq. 15 fades minors only) and would
    ink the whole map."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: no range
        lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
    slope = None
    given = not (interval is None and major_interval is None)
    if not given or check_spacing:
        slope = typical_slope(z) / pixels_per_sample
    out = choose_intervals(lo, hi, None if given else slope, interval, major_interval)
    if given and check_spacing and slope is not None and math.isfinite(slope) and slope > 0:
        _check_spacing(out[2], out[3], slope, lo, hi)
    return out


#: Closest spacing (output pixels on the median slope) of the lines that never thin out:
#: closer than half a pixel they alias into solid ink or noise, whatever their width (a
#: busy map of 1-2 px spacing on steep ground is still a map someone may want).
MIN_MAJOR_SPACING = 0.5


def _check_spacing(
    interval: float, major_interval: float | None, slope: float, lo: float, hi: float
) -> None:
    name, q = ("major_interval", major_interval) if major_interval else ("interval", interval)
    spacing = float(q) / slope
    if spacing >= MIN_MAJOR_SPACING:
        return
    _, suggested = nice_intervals(lo, hi, slope=slope)
    least = round_up(slope * MIN_MAJOR_SPACING)
    raise InputError(
        f"{name}: lines every {float(q):g} are {spacing:.2g} px apart on the median slope "
        f"({slope:.3g} a pixel), so they would fill the map with ink; expected at least "
        f"{least:g} (the automatic choice here: major {suggested:g}, minor {suggested / 5:g})"
    )


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
