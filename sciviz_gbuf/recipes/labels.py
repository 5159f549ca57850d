"""Contour labels of topographic maps: the index contours numbered along the line.

A map reader finds the height of a contour from its number, written into the line (Imhof,
*Cartographic Relief Presentation*, 1982, ch. 7): the line is broken under the number, the
number follows the line's direction and its top faces uphill, so that a reader can tell up
from down at a glance. This module places such labels on the index (major) contours of a
plan-view map (Saito & Takahashi 1990 Fig. 11) and draws them.

Placement works on the map's own grid, in output pixels:

1. the index contours are traced as polylines (:func:`~sciviz_gbuf.filters.contour_polylines`,
   marching squares on the heights the map is drawn from);
2. along each line, candidate centres every pixel are kept where the line
   is straight under the label (it stays within a fifth of the text height of the label's
   baseline, and its tangent at the centre is within 10 degrees of the baseline), the box lies
   inside the frame, over data, crossed by no other index contour and by no other branch of
   its own (the heights on its uphill half are above the level, on its downhill half below);
3. the baseline is the chord of the line under the label, turned so that the text's up vector
   points uphill (the height gradient); on a slope that faces the bottom of the map this makes
   the text upside down, as on Swiss and USGS maps, so positions where it would read upright
   are preferred, and taken wherever the line has one;
4. lines are labelled longest first, the best candidates first, at least ``spacing`` pixels
   apart along the line; a label's box, grown by half the font size, must not meet another's;
   closed lines shorter than four label lengths get none.

Drawing knocks the contour ink out under each label's box (a gap in every line there, as a
cartographer's mask does) and blends the text, rendered antialiased with DejaVu Sans (the
font matplotlib bundles) at four times the output resolution, rotated and averaged down.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from .. import _dask, _validate
from ..errors import InputError
from ..filters import contour_polylines
from ..readers import DEM
from ._intervals import contour_intervals
from ._map import as_dem
from ._resample import map_grid

__all__ = [
    "ContourLabel",
    "check_in_memory",
    "contour_labels",
    "draw_labels",
    "label_boxes",
    "label_ink",
    "label_levels",
    "label_options",
    "label_text",
    "labels_of_grid",
    "labels_to_geojson",
    "place_labels",
]

#: Supersampling of the rendered text (antialiasing of rotated glyphs).
TEXT_SUPERSAMPLE = 4
#: Cost of a place where the text reads uphill only upside down (the straightness cost of
#: a place is at most 0.3): upright places first, and on a line that has one, only those.
UPSIDE_DOWN_COST = 10.0
#: Default label size in output pixels (about 8 pt at 96 dpi).
DEFAULT_FONT_PX = 11.0
#: Default label size in points when the map has a print resolution (``dpi``).
DEFAULT_FONT_PT = 7.0
#: Default distance between labels along a line, in font sizes.
SPACING_FONTS = 25.0
#: Blank margin around the text inside the knocked-out box, in font sizes.
PAD_FONTS = 0.25
#: Least gap between two labels' boxes, in font sizes.
GAP_FONTS = 0.5
#: Closed lines shorter than this many label lengths get no label.
MIN_RING_LABELS = 4.0
#: Most expensive (box) checks per line, so that a line whose every candidate is blocked costs
#: a bounded time.
MAX_TRIES = 400


class ContourLabel(NamedTuple):
    """One contour label, in output pixels of the map (column ``x``, row ``y``; pixel centres at
    whole numbers, row 0 at the top, as :func:`~sciviz_gbuf.filters.contour_polylines`)."""

    text: str
    """The number written (a minus sign for heights below zero)."""
    level: float
    """The contour's height."""
    x: float
    """Column of the label's centre, which lies on the contour line."""
    y: float
    """Row of the label's centre."""
    angle: float
    """Direction of the baseline in degrees counter-clockwise from the map's +x (east) as seen
    on screen, in (-180, 180]: the text's up vector ``(-sin, cos)`` (y up) points uphill."""
    width: float
    """Length of the knocked-out box along the baseline, pixels (text plus margins)."""
    height: float
    """Height of the box across the line, pixels."""
    map_x: float
    """The centre in map (CRS) coordinates."""
    map_y: float
    """The centre in map (CRS) coordinates."""
    map_angle: float
    """The baseline direction in map coordinates (degrees counter-clockwise from +x), for a GIS
    (equal to ``angle`` on a north-up grid with square pixels)."""


def label_text(level: float, step: float) -> str:
    """A contour height as printed: as many decimals as the label ``step`` needs (none for
    whole steps), a true minus sign (U+2212) below zero.

    >>> label_text(1200.0, 100.0), label_text(-2.5, 2.5), label_text(0.0, 0.5)
    ('1200', '\u22122.5', '0.0')
    """
    decimals = 0
    while decimals < 6 and abs(step * 10**decimals - round(step * 10**decimals)) > 1e-6 * max(
        1.0, abs(step) * 10**decimals
    ):
        decimals += 1
    text = f"{abs(level):.{decimals}f}"
    negative = level < 0 and float(text) != 0.0
    return ("\u2212" if negative else "") + text


@functools.lru_cache(maxsize=8)
def _font(size: int):
    """DejaVu Sans (bundled with matplotlib) at ``size`` pixels (the supersampled size)."""
    import matplotlib
    from PIL import ImageFont

    path = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
    return ImageFont.truetype(str(path), size)


def _font_size(font_px: float) -> int:
    return max(1, round(font_px * TEXT_SUPERSAMPLE))


@functools.lru_cache(maxsize=4096)
def _extent(text: str, font_px: float) -> tuple[float, float]:
    """Width and height (output pixels) of the ink of ``text`` at ``font_px``."""
    left, top, right, bottom = _font(_font_size(font_px)).getbbox(text)
    return (right - left) / TEXT_SUPERSAMPLE, (bottom - top) / TEXT_SUPERSAMPLE


def label_options(
    font_size: float | None, spacing: float | None, dpi: float | None = None
) -> tuple[float, float]:
    """Checked ``(font_px, spacing_px)``: the label size in output pixels (default 11 px, or
    7 pt at ``dpi``) and the spacing along a line (default 25 font sizes), each bounded by
    ``LIMITS["font_size"]`` and ``LIMITS["label_spacing"]``."""
    if font_size is None:
        font_px = DEFAULT_FONT_PX if dpi is None else DEFAULT_FONT_PT * float(dpi) / 72.0
        font_px = min(font_px, _validate.LIMITS["font_size"])
    else:
        font_px = _validate.size(font_size, "label_size", "font_size")
    if font_px < 4.0:
        raise InputError(f"label_size: expected at least 4 pixels, got {font_size!r}")
    if spacing is None:
        spacing_px = min(SPACING_FONTS * font_px, _validate.LIMITS["label_spacing"])
    else:
        spacing_px = _validate.size(spacing, "label_spacing", "label_spacing")
    return font_px, spacing_px


def label_levels(lo: float, hi: float, step: float) -> np.ndarray:
    """The multiples of ``step`` in ``[lo, hi]`` (the index contours a map labels)."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return np.zeros(0)
    n0, n1 = math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9)
    if n1 - n0 + 1 > _validate.LIMITS["levels"]:
        raise InputError(
            f"major_interval: {step!r} gives {n1 - n0 + 1} labelled levels over [{lo:g}, "
            f"{hi:g}]; expected at most {int(_validate.LIMITS['levels'])}"
        )
    return np.arange(n0, n1 + 1, dtype=np.float64) * step


def _bilinear(a: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``a`` at fractional (column, row) positions inside the grid, bilinearly."""
    h, w = a.shape
    x = np.clip(x, 0.0, w - 1.0)
    y = np.clip(y, 0.0, h - 1.0)
    c0 = np.minimum(np.floor(x).astype(np.intp), max(w - 2, 0))
    r0 = np.minimum(np.floor(y).astype(np.intp), max(h - 2, 0))
    c1, r1 = np.minimum(c0 + 1, w - 1), np.minimum(r0 + 1, h - 1)
    fx, fy = x - c0, y - r0
    top = a[r0, c0] * (1 - fx) + a[r0, c1] * fx
    bottom = a[r1, c0] * (1 - fx) + a[r1, c1] * fx
    return top * (1 - fy) + bottom * fy


def _along(points: np.ndarray, cum: np.ndarray, s: np.ndarray, closed: bool) -> np.ndarray:
    """Points at arc lengths ``s`` of a polyline (``cum`` its cumulative lengths)."""
    if closed:
        s = np.mod(s, cum[-1])
    return np.stack([np.interp(s, cum, points[:, 0]), np.interp(s, cum, points[:, 1])], axis=-1)


def _transform_point(transform: Sequence[float], x: float, y: float) -> tuple[float, float]:
    x0, dx, rx, y0, ry, dy = transform
    c, r = x + 0.5, y + 0.5  # pixel centre -> corner coordinates of the geotransform
    return x0 + c * dx + r * rx, y0 + c * ry + r * dy


def _map_angle(transform: Sequence[float], angle: float) -> float:
    """The screen angle ``angle`` (degrees, y up) as a direction in map coordinates."""
    _, dx, rx, _, ry, dy = transform
    a = math.radians(angle)
    col, row = math.cos(a), -math.sin(a)
    return math.degrees(math.atan2(col * ry + row * dy, col * dx + row * rx))


def _normal_angle(deg: float) -> float:
    deg = math.fmod(deg, 360.0)
    if deg <= -180.0:
        deg += 360.0
    elif deg > 180.0:
        deg -= 360.0
    return deg


class _Line:
    """A traced contour line with its arc lengths."""

    def __init__(self, points: np.ndarray, closed: bool, level: float) -> None:
        self.points = points
        self.closed = closed
        self.level = level
        seg = np.hypot(*np.diff(points, axis=0).T)
        self.cum = np.concatenate(([0.0], np.cumsum(seg)))
        self.length = float(self.cum[-1])


def _candidates(
    line: _Line, half: float, hh: float, text_h: float, z: np.ndarray, step: float, strict: bool
):
    """The candidate centres of a line that pass the cheap tests (straight under the label,
    box in the frame, an uphill direction): ``(s, centre, direction, angle, cost)``, the
    direction in image coordinates (column, row) along the baseline, already turned uphill."""
    h, w = z.shape
    if line.closed:
        s = np.arange(0.0, line.length, step)
    else:
        s = np.arange(half + 1.0, line.length - half - 1.0, step)
    if s.size == 0:
        return None
    k = max(5, math.ceil(2 * half / 2.0) + 1)
    t = np.linspace(-half, half, k)
    pts = _along(line.points, line.cum, s[:, None] + t[None, :], line.closed)  # (n, k, 2)
    centre = _along(line.points, line.cum, s, line.closed)
    chord = pts[:, -1] - pts[:, 0]
    clen = np.hypot(chord[:, 0], chord[:, 1])
    ok = clen > 1.8 * half  # not folded back on itself
    d = chord / np.maximum(clen, 1e-12)[:, None]
    rel = pts - centre[:, None, :]
    dev = np.abs(rel[..., 0] * d[:, None, 1] - rel[..., 1] * d[:, None, 0]).max(axis=1)
    ok &= dev <= (0.2 if strict else 0.3) * text_h
    tang = _along(line.points, line.cum, s + 1.5, line.closed) - _along(
        line.points, line.cum, s - 1.5, line.closed
    )
    tlen = np.hypot(tang[:, 0], tang[:, 1])
    cos_t = np.abs(tang[:, 0] * d[:, 0] + tang[:, 1] * d[:, 1]) / np.maximum(tlen, 1e-12)
    ok &= cos_t >= math.cos(math.radians(10.0))
    # the box's corners inside the frame (1 px clear of the edge)
    nrm = np.stack([-d[:, 1], d[:, 0]], axis=-1)
    for su in (-1.0, 1.0):
        for sv in (-1.0, 1.0):
            corner = centre + su * half * d + sv * hh * nrm
            ok &= (corner[:, 0] >= 1.0) & (corner[:, 0] <= w - 2.0)
            ok &= (corner[:, 1] >= 1.0) & (corner[:, 1] <= h - 2.0)
    # the slope of the (bilinear) height surface at the centre, differences 1 px apart: the
    # baseline must also be within 10 degrees of the level line it defines
    cx, cy = centre[:, 0], centre[:, 1]
    gx = _bilinear(z, cx + 0.5, cy) - _bilinear(z, cx - 0.5, cy)
    gy = _bilinear(z, cx, cy + 0.5) - _bilinear(z, cx, cy - 0.5)
    glen = np.hypot(gx, gy)
    ok &= np.isfinite(glen) & (glen > 0)
    with np.errstate(invalid="ignore"):
        cos_g = np.abs(d[:, 0] * gy - d[:, 1] * gx) / glen
    ok &= cos_g >= math.cos(math.radians(10.0))
    if not ok.any():
        return None
    s, centre, d, dev, gx, gy = s[ok], centre[ok], d[ok], dev[ok], gx[ok], gy[ok]
    # up vector of the text in image coordinates: the baseline turned 90 degrees anticlockwise
    # on screen, (dc, dr) -> (dr, -dc); flip the baseline where that points downhill
    up_dot = d[:, 1] * gx - d[:, 0] * gy
    d = np.where((up_dot < 0)[:, None], -d, d)
    angle = np.degrees(np.arctan2(-d[:, 1], d[:, 0]))
    upside_down = np.abs(angle) > 90.0
    cost = dev / text_h + upside_down * UPSIDE_DOWN_COST
    return s, centre, d, angle, cost


def _box_samples(centre: np.ndarray, d: np.ndarray, half: float, hh: float):
    """Sample points (image coordinates) covering a label's box, about one per pixel, and each
    one's signed offset across the line (positive uphill)."""
    u = np.linspace(-half, half, max(3, math.ceil(2 * half) + 1))
    v = np.linspace(-hh, hh, max(3, math.ceil(2 * hh) + 1))
    uu, vv = np.meshgrid(u, v)
    nrm = np.array([d[1], -d[0]])  # the text's up vector in image coordinates
    x = centre[0] + uu * d[0] + vv * nrm[0]
    y = centre[1] + uu * d[1] + vv * nrm[1]
    return x.ravel(), y.ravel(), vv.ravel()


def _box_uv(shape: Sequence[int], x: float, y: float, d: Sequence[float], reach: float):
    """The window of a grid around a box centred at ``(x, y)`` with baseline ``d`` (image
    coordinates), ``reach`` pixels each way: ``(rows, cols, u, v)``, the window's slices and
    each pixel centre's offset along and across the baseline; None outside the grid."""
    h, w = int(shape[0]), int(shape[1])
    c0, c1 = max(0, int(x - reach)), min(w, int(x + reach) + 2)
    r0, r1 = max(0, int(y - reach)), min(h, int(y + reach) + 2)
    if c0 >= c1 or r0 >= r1:
        return None
    yy, xx = np.mgrid[r0:r1, c0:c1]
    px, py = xx - x, yy - y
    return slice(r0, r1), slice(c0, c1), px * d[0] + py * d[1], px * d[1] - py * d[0]


def _stamp(grid: np.ndarray, centre: np.ndarray, d: np.ndarray, half: float, hh: float) -> None:
    """Mark the pixels whose centres lie in a box on a boolean grid."""
    box = _box_uv(grid.shape, centre[0], centre[1], d, math.hypot(half, hh) + 1.0)
    if box is not None:
        rows, cols, u, v = box
        grid[rows, cols] |= (np.abs(u) <= half) & (np.abs(v) <= hh)


def place_labels(
    heights: np.ndarray,
    *,
    step: float,
    band: float,
    font_px: float,
    spacing_px: float,
    transform: Sequence[float] = (0.0, 1.0, 0.0, 0.0, 0.0, -1.0),
    levels: np.ndarray | None = None,
) -> list[ContourLabel]:
    """Place labels on the contours of ``heights`` at the multiples of ``step`` (or the given
    ``levels``); ``band`` is the distance to the next labelled level, whose lines a label box
    may not cross. See the module's docstring for the rules; :func:`contour_labels` is the
    public entry on DEMs."""
    z = np.asarray(heights, dtype=np.float64)
    h, w = z.shape
    valid = np.isfinite(z)
    if not valid.any() or min(h, w) < 3:
        return []
    if levels is None:
        levels = label_levels(float(z[valid].min()), float(z[valid].max()), step)
    if len(levels) == 0:
        return []
    lines = [
        _Line(p.points, p.closed, p.level)
        for p in contour_polylines(z, levels=levels)
        if len(p.points) >= 2
    ]
    lines.sort(key=lambda line: -line.length)
    taken = np.zeros((h, w), bool)  # boxes placed, grown by the gap
    out: list[ContourLabel] = []
    # Where index contours crowd closer than a label's height, no box is clear of the
    # neighbouring lines: a long line left without a label after the first pass gets one in a
    # second pass that lets the box cross the other lines (they are knocked out with it, the
    # "ladder" of labels on steep slopes).
    bare = []
    for line in lines:
        if not _label_line(line, z, taken, out, step, band, font_px, spacing_px,
                           transform, strict=True):  # fmt: skip
            bare.append(line)
    for line in bare:
        if line.length > 3 * spacing_px:
            _label_line(line, z, taken, out, step, band, font_px, spacing_px, transform,
                        strict=False)  # fmt: skip
    return out


def _label_line(
    line: _Line,
    z: np.ndarray,
    taken: np.ndarray,
    out: list[ContourLabel],
    step: float,
    band: float,
    font_px: float,
    spacing_px: float,
    transform: Sequence[float],
    *,
    strict: bool,
) -> bool:
    """Place the labels of one line (appended to ``out``, their boxes marked in ``taken``);
    True if it got one. ``strict``: the box must be clear of the other labelled levels and of
    the line's other branches."""
    h, w = z.shape
    text = label_text(line.level, step)
    tw, th = _extent(text, font_px)
    pad, gap = PAD_FONTS * font_px, GAP_FONTS * font_px
    half, hh = tw / 2 + pad, th / 2 + pad
    if line.closed and line.length < MIN_RING_LABELS * 2 * half:
        return False
    found = _candidates(line, half, hh, th, z, 1.0, strict)
    if found is None:
        return False
    s, centre, d, angle, cost = found
    placed: list[float] = []
    tries = 0
    for i in np.argsort(cost, kind="stable"):
        if cost[i] >= UPSIDE_DOWN_COST and placed:
            # the line reads upright somewhere: no label on it is turned upside down (one
            # that reads uphill only upside down is for a line that has no other)
            break
        if placed:
            gaps = np.abs(np.asarray(placed) - s[i])
            if line.closed:
                gaps = np.minimum(gaps, line.length - gaps)
            if gaps.min() < spacing_px:
                continue
        tries += 1
        if tries > MAX_TRIES:
            break
        x, y, v = _box_samples(centre[i], d[i], half, hh)
        ci = np.clip(np.rint(x).astype(np.intp), 0, w - 1)
        ri = np.clip(np.rint(y).astype(np.intp), 0, h - 1)
        zs = _bilinear(z, x, y)
        if not np.isfinite(zs).all() or taken[ri, ci].any():
            continue
        if strict:
            # no other labelled level in the box, and no other branch of this one: the
            # heights away from the line are above it on the uphill side, below downhill
            if (np.abs(zs - line.level) >= band).any():
                continue
            far = np.abs(v) > 0.5 * hh
            if ((zs - line.level) * v <= 0)[far].any():
                continue
        placed.append(float(s[i]))
        _stamp(taken, centre[i], d[i], half + gap, hh + gap)
        cx, cy = float(centre[i][0]), float(centre[i][1])
        mx, my = _transform_point(transform, cx, cy)
        out.append(
            ContourLabel(
                text,
                float(line.level),
                cx,
                cy,
                float(_normal_angle(float(angle[i]))),
                float(2 * half),
                float(2 * hh),
                float(mx),
                float(my),
                float(_map_angle(transform, float(angle[i]))),
            )
        )
    return bool(placed)


def contour_labels(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    size: int | Sequence[int] | None = None,
    scale: float | str | None = None,
    dpi: float | None = None,
    label_size: float | None = None,
    label_spacing: float | None = None,
) -> list[ContourLabel]:
    """Where :func:`~sciviz_gbuf.recipes.terrain.topographic_map` ``labels=True`` writes the
    heights of the index contours, in the map's output pixels and in map coordinates.

    Parameters
    ----------
    dem : DEM, path, array or xarray.DataArray
        Anything :func:`~sciviz_gbuf.readers.read_dem` reads (arrays: 1 m pixels).
    interval, major_interval : float, optional
        The map's contour intervals (the same defaults as the map); the index contours, those
        labelled, are the multiples of ``major_interval`` (of ``interval`` when the map has
        one family of lines).
    size, scale, dpi : optional
        The map's output grid, as in ``topographic_map``.
    label_size : float, optional
        Height of the font (its em) in output pixels, at most ``LIMITS["font_size"]`` = 512;
        default 11 px, or 7 pt at ``dpi`` (``7 * dpi / 72`` px).
    label_spacing : float, optional
        Least distance between two labels along a line, output pixels (default 25 font
        sizes), at most ``LIMITS["label_spacing"]`` = 16384.

    Returns
    -------
    list of ContourLabel
        Longest lines first; on each line the best place first. Every label's centre lies on
        its contour, its baseline follows the line (within 10 degrees of the tangent), its top
        faces uphill, its box is inside the frame, over data, clear of the other index
        contours and of the other labels.

    Notes
    -----
    Labels are placed on the lines of the heights the map is drawn from; the map's drawn lines,
    generalised, lie within 0.6 px of those. Out-of-core (dask) DEMs are not labelled: the
    lines are traced on the whole grid in memory.
    """
    font_px, spacing_px = label_options(label_size, label_spacing, dpi if scale else None)
    d = check_in_memory(as_dem(dem))
    d = map_grid(d, size=size, scale=scale, dpi=dpi)
    return labels_of_grid(d, interval, major_interval, font_px, spacing_px)


def check_in_memory(d: DEM) -> DEM:
    """``d`` itself if its heights are in memory; an InputError for a DEM read in chunks
    (labels are placed on the whole grid's contour lines)."""
    if _dask.is_dask(d.heights):
        raise InputError(
            f"labels: {d.source or 'the DEM'} is read in chunks (out of core); contour labels "
            "are placed on a DEM in memory (read it without chunks=)"
        )
    return d


def labels_of_grid(
    d: DEM, interval: float | None, major_interval: float | None, font_px: float, spacing: float
) -> list[ContourLabel]:
    """:func:`contour_labels` on a DEM already on the map's grid."""
    _, _, minor, major = contour_intervals(d.heights, interval, major_interval)
    step = float(major if major is not None else minor)
    return place_labels(
        d.heights, step=step, band=step, font_px=font_px, spacing_px=spacing,
        transform=d.transform,
    )  # fmt: skip


def label_boxes(labels: Sequence[ContourLabel], shape: Sequence[int]) -> np.ndarray:
    """(H, W) float32 coverage in [0, 1] of the labels' boxes (antialiased edges, exactly 1
    inside): what :func:`draw_labels` knocks out of the contour ink."""
    cover = np.zeros((int(shape[0]), int(shape[1])), np.float32)
    for lab in labels:
        a = math.radians(lab.angle)
        d = (math.cos(a), -math.sin(a))  # baseline in image coordinates
        half, hh = lab.width / 2, lab.height / 2
        box = _box_uv(cover.shape, lab.x, lab.y, d, math.hypot(half, hh) + 2.0)
        if box is None:
            continue
        rows, cols, u, v = box
        c = np.clip(half + 0.5 - np.abs(u), 0, 1) * np.clip(hh + 0.5 - np.abs(v), 0, 1)
        np.maximum(cover[rows, cols], c.astype(np.float32), out=cover[rows, cols])
    return cover


def label_ink(labels: Sequence[ContourLabel], shape: Sequence[int], font_px: float) -> np.ndarray:
    """(H, W) float32 coverage in [0, 1] of the labels' text: DejaVu Sans at ``font_px``,
    drawn at :data:`TEXT_SUPERSAMPLE` times the resolution, rotated to each label's angle and
    box-averaged down (antialiased, centred on the label within 1/8 px)."""
    from PIL import Image, ImageDraw

    h, w = int(shape[0]), int(shape[1])
    ss = TEXT_SUPERSAMPLE
    ink = np.zeros((h, w), np.float32)
    font = _font(_font_size(font_px))
    for lab in labels:
        left, top, right, bottom = font.getbbox(lab.text)
        m = ss * 2
        img = Image.new("L", (right - left + 2 * m, bottom - top + 2 * m), 0)
        ImageDraw.Draw(img).text((m - left, m - top), lab.text, fill=255, font=font)
        # PIL turns anticlockwise as displayed: the baseline ends at the label's screen angle
        rot = img.rotate(lab.angle, resample=Image.BICUBIC, expand=True)
        rw, rh = rot.size
        # output pixel i spans supersampled cells ss*(i - i0) .. +ss; its centre (x = i) lies at
        # the cells' coordinate ss*(i - i0 + 0.5)
        i0 = math.floor(lab.x - rw / (2 * ss)) - 1
        j0 = math.floor(lab.y - rh / (2 * ss)) - 1
        ox = round(ss * (lab.x - i0 + 0.5) - rw / 2)
        oy = round(ss * (lab.y - j0 + 0.5) - rh / 2)
        nw = (ox + rw) // ss + 2
        nh = (oy + rh) // ss + 2
        patch = np.zeros((nh * ss, nw * ss), np.float32)
        patch[oy : oy + rh, ox : ox + rw] = np.asarray(rot, np.float32) / 255.0
        small = patch.reshape(nh, ss, nw, ss).mean(axis=(1, 3))
        # clip to the image
        a0, b0 = max(0, -j0), max(0, -i0)
        a1, b1 = min(nh, h - j0), min(nw, w - i0)
        if a0 >= a1 or b0 >= b1:
            continue
        view = ink[j0 + a0 : j0 + a1, i0 + b0 : i0 + b1]
        np.maximum(view, small[a0:a1, b0:b1], out=view)
    return ink


def draw_labels(
    rgba: np.ndarray, labels: Sequence[ContourLabel], font_px: float, color: Sequence[float]
) -> np.ndarray:
    """The map ``rgba`` (uint8, H x W x 4) with the labels' text blended in ``color`` (RGB in
    [0, 1]); a new array. The contour ink under the boxes is knocked out before the map is
    composed (:func:`label_boxes`), not here."""
    ink = label_ink(labels, rgba.shape[:2], font_px)[..., None]
    col = np.asarray(color, np.float32) * 255.0
    out = rgba.copy()
    rgb = out[..., :3].astype(np.float32)
    out[..., :3] = np.rint(rgb * (1.0 - ink) + col * ink).astype(np.uint8)
    alpha = out[..., 3:4].astype(np.float32)
    out[..., 3:4] = np.rint(np.maximum(alpha, ink * 255.0)).astype(np.uint8)
    return out


def labels_to_geojson(
    labels: Sequence[ContourLabel], *, crs: str | None = None, font_px: float | None = None
) -> dict[str, Any]:
    """A GeoJSON FeatureCollection of Points at the labels' centres (map coordinates) with
    ``text``, ``level``, ``angle`` (degrees anticlockwise from +x in map coordinates) and
    ``rotation`` (degrees clockwise, the convention of QGIS's and Mapnik's label rotation)
    properties, and the box ``width``/``height`` in map pixels; ``crs`` as in
    :func:`~sciviz_gbuf.filters.polylines_to_geojson`."""
    features = []
    for lab in labels:
        props: dict[str, Any] = {
            "text": lab.text,
            "level": lab.level,
            "angle": round(lab.map_angle, 3),
            "rotation": round(-lab.map_angle, 3),
            "width_px": round(lab.width, 2),
            "height_px": round(lab.height, 2),
        }
        if font_px is not None:
            props["size_px"] = round(float(font_px), 2)
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": [lab.map_x, lab.map_y]},
                "properties": props,
            }
        )
    fc: dict[str, Any] = {"type": "FeatureCollection", "features": features}
    if crs is not None:
        fc["crs"] = {"type": "name", "properties": {"name": str(crs)}}
    return fc
