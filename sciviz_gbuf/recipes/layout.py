"""Print layouts of topographic maps: the map at a stated scale on a page, with its legend,
scale bar, north arrow, title and credit line (PNG or PDF).

The map is drawn by :func:`~sciviz_gbuf.recipes.terrain.topographic_map` at the page's
resolution and a round map scale (1:N with N 1, 2, 2.5 or 5 times a power of ten, the
smallest at which the DEM's extent fits the map frame, or the scale asked for), so one map
pixel is one page pixel: it is placed unresampled (PNG) or embedded at that resolution (PDF).
The furniture below the frame is drawn with matplotlib as vector graphics (text in DejaVu
Sans): the hypsometric legend (:func:`~.furniture.legend_classes`, with the contour
interval), the scale bar (:func:`~.furniture.scale_bar`), the north arrow and the scale.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import _validate
from .._atomic import atomic_output
from ..errors import InputError
from ..filters import Stroke, contour_polylines, simplify
from ..filters.contours import MIN_RING_WIDTHS, generalized_field
from ..readers import DEM
from ._intervals import contour_intervals
from ._map import CONTOUR_COLOR, as_dem
from ._resample import map_grid
from .furniture import legend_classes, scale_bar
from .labels import PAD_FONTS, ContourLabel, label_boxes, label_options, labels_of_grid
from .map_options import PAGES
from .terrain import topographic_map

__all__ = [
    "PAGES",
    "map_lines",
    "map_page",
    "map_strokes",
    "page_scale",
    "write_map_page",
]

#: Page margin, mm.
MARGIN_MM = 12.0
#: Height of the furniture strip below the map frame, mm.
STRIP_MM = 34.0
#: Height of the title line, mm (when there is a title).
TITLE_MM = 12.0
_MM = 0.001  # metres per millimetre


#: Where the furniture goes: below the map frame, or on a panel inside its lower edge.
FURNITURE = ("outside", "inside")
#: Coordinate ticks on the frame, or ticks and grid lines across the map.
GRATICULES = ("ticks", "grid")
#: Height of the furniture panel inside the frame, mm.
PANEL_MM = 27.0


def _frame_mm(
    page: str, landscape: bool, title: bool, inside: bool = False
) -> tuple[float, float, float, float]:
    """``(page_w, page_h, frame_w, frame_h)`` in mm (the frame takes the furniture's strip
    too when the furniture is inside it)."""
    pw, ph = PAGES[page]
    if landscape:
        pw, ph = ph, pw
    fw = pw - 2 * MARGIN_MM
    fh = ph - 2 * MARGIN_MM - (0.0 if inside else STRIP_MM) - (TITLE_MM if title else 0.0)
    return pw, ph, fw, fh


def _round_scale(n: float) -> int:
    """The smallest of 1, 2, 2.5, 5 times a power of ten that is >= ``n``."""
    e = math.floor(math.log10(n))
    for k in (e, e + 1):
        for m in (1.0, 2.0, 2.5, 5.0, 10.0):
            if m * 10.0**k >= n * (1 - 1e-12):
                return round(m * 10.0**k)
    return round(10.0 ** (e + 1))  # pragma: no cover - the loop always returns


def page_scale(
    dem: DEM,
    page: str = "A4",
    *,
    landscape: bool = False,
    title: bool = False,
    furniture: str = "outside",
) -> int:
    """The map scale denominator N of :func:`map_page`: the smallest round 1:N at which the
    DEM's extent (its cells times their size in metres) fits the page's map frame."""
    _, _, fw, fh = _frame_mm(page, landscape, title, furniture == "inside")
    h, w = dem.shape
    ground_w, ground_h = w * dem.pixel_size[0], h * dem.pixel_size[1]
    return _round_scale(max(ground_w / (fw * _MM), ground_h / (fh * _MM)))


def _parse_scale(scale: object) -> int | None:
    if scale is None:
        return None
    text = str(scale).strip()
    value = text.partition(":")[2] if ":" in text else text
    try:
        n = float(value)
    except ValueError:
        n = float("nan")
    if not (math.isfinite(n) and n >= 1 and (":" not in text or text.startswith("1:"))):
        raise InputError(f"scale: expected a map scale 1:N such as 1:25000, got {scale!r}")
    return round(n)


def _north_note(d: DEM) -> tuple[float, str]:
    """The direction of true north on the map (degrees from the page's up, clockwise) and a
    note: on geographic grids north is up; on projected grids the arrow shows grid north and
    the note gives the convergence at the centre when the CRS can be transformed (rasterio)."""
    if d.geographic:
        return 0.0, "True north"
    if not d.crs:
        return 0.0, "Grid north"
    try:
        from rasterio.crs import CRS
        from rasterio.warp import transform
    except ImportError:
        return 0.0, "Grid north"
    h, w = d.shape
    x0, dx, rx, y0, ry, dy = d.transform
    cx, cy = x0 + w / 2 * dx + h / 2 * rx, y0 + w / 2 * ry + h / 2 * dy
    try:
        src = CRS.from_user_input(d.crs)
        lon, lat = transform(src, "EPSG:4326", [cx], [cy])
        step = 0.01
        xs, ys = transform("EPSG:4326", src, [lon[0]], [min(lat[0] + step, 89.99)])
    except Exception:
        return 0.0, "Grid north"
    gamma = math.degrees(math.atan2(xs[0] - cx, ys[0] - cy))
    side = "E" if gamma >= 0 else "W"
    return gamma, f"Grid north; true north {abs(gamma):.1f}\u00b0 {side}"


#: Vertex spacing of vector contour lines along their length, in map pixels (the knock-out
#: of a label and the crowding of minors are decided per vertex).
_VERTEX_PX = 0.5


def _densify(points: np.ndarray, step: float) -> np.ndarray:
    """``points`` (N, 2) resampled along their length at most ``step`` apart (the original
    vertices kept)."""
    seg = np.hypot(*np.diff(points, axis=0).T)
    n = np.maximum(np.ceil(seg / step).astype(int), 1)
    # t = j / n_k for j = 0 .. n_k - 1 of every segment k, without a loop over segments
    # (a list of aranges cost seconds on a page's 10^6 vertices): the same divisions
    start = np.repeat(np.arange(len(seg)), n)
    first = np.cumsum(n) - n  # each segment's first sample
    j = np.arange(int(n.sum())) - first[start]
    t = np.append(j / n[start], 0.0)
    start = np.append(start, len(seg) - 1)
    t[-1] = 1.0
    a, b = points[start], points[start + 1]
    return a + (b - a) * t[:, None]


def _runs(keep: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of the runs of True in ``keep`` with at least two entries."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(np.int8), [0]])))
    return [(a, b) for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a >= 2]


#: Along-line window (vertices) over which a minor's spacing is averaged (16 px at 0.5 px a
#: vertex), the shortest gap of a minor kept open (6 px) and its shortest piece (40 px): a
#: printed minor runs on or stops, it is not strewn in crumbs where the ground steepens.
_CROWD_WINDOW = 33
_CROWD_PIECE = 12
_MINOR_PIECE = 80


def _flip_short(keep: np.ndarray, value: bool, shortest: int) -> np.ndarray:
    """``keep`` with its runs of ``value`` shorter than ``shortest`` flipped (not a run that
    is the whole line)."""
    keep = keep.copy()
    n = len(keep)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (keep == value).astype(np.int8), [0]])))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a < shortest and (a > 0 or b < n):
            keep[a:b] = not value
    return keep


def _uncrowded(spacing: np.ndarray, crowd: float) -> np.ndarray:
    """Which vertices of a minor line stay: where its spacing to the next line, averaged
    over 16 px along it, is at least ``crowd``; gaps shorter than 6 px close, then pieces
    shorter than 40 px go (a hard threshold on a noisy spacing would draw dashes and crumbs
    where the raster ink fades)."""
    n = len(spacing)
    k = min(_CROWD_WINDOW, n)
    finite = np.where(np.isfinite(spacing), spacing, 1e30)
    smooth = np.convolve(np.pad(finite, k // 2, mode="edge"), np.ones(k) / k, mode="valid")[:n]
    keep = _flip_short(smooth >= crowd, False, _CROWD_PIECE)
    return _flip_short(keep, True, _MINOR_PIECE)


def _sample(grid: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Nearest-cell values of ``grid`` at the (x, y) pixel positions ``pts``."""
    h, w = grid.shape
    c = np.clip(np.rint(pts[:, 0]).astype(int), 0, w - 1)
    r = np.clip(np.rint(pts[:, 1]).astype(int), 0, h - 1)
    return grid[r, c]


def map_lines(
    grid: DEM,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    generalize: bool = True,
    labels: Sequence[ContourLabel] = (),
) -> list[tuple[np.ndarray, bool]]:
    """The contour lines of a map on the map's own grid as vector polylines: the lines
    :func:`~sciviz_gbuf.recipes.terrain.topographic_map` draws as ink, for a PDF.

    The levels are the map's (default intervals alike); with ``generalize`` the lines are
    traced on the smoothed field of the generalised ink
    (:func:`~sciviz_gbuf.filters.contours.generalized_field`) and rings that fit in 3 widths
    of the widest line are left out, as there. Minor lines are cut where they crowd closer
    than ``dense_spacing - width / 2`` px (the middle of the ink's fade, Eq. 15; majors never
    thin out), and every line is cut under the boxes of ``labels``.

    Returns
    -------
    list of ((N, 2) float64 points, major)
        ``(x, y)`` in map pixels (column, row; pixel centres at integers, row 0 north).
    """
    pieces = _map_pieces(grid, interval, major_interval, width, major_width, dense_spacing,
                         generalize, labels)  # fmt: skip
    return [(pts, major) for pts, major, _level in pieces]


def map_strokes(
    grid: DEM,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    generalize: bool = True,
    labels: Sequence[ContourLabel] = (),
    color: Sequence[float] = CONTOUR_COLOR,
    tolerance: float = 0.25,
) -> list[Stroke]:
    """The lines of :func:`map_lines` as :class:`~sciviz_gbuf.filters.Stroke` (kinds
    ``"contour"`` and ``"contour-major"``, each with its level) for SVG and PDF, simplified
    within ``tolerance`` px: every vertex kept is a vertex of the traced line (Eq. 13's
    contour of the, possibly generalised, heights)."""
    colour = tuple(float(c) for c in _validate.rgb(color, "contour_color"))
    tol = _validate.size(tolerance, "tolerance", "line_width", closed=True)
    out = []
    for pts, major, level in _map_pieces(grid, interval, major_interval, width, major_width,
                                         dense_spacing, generalize, labels):  # fmt: skip
        out.append(Stroke(simplify(pts, tol), float(major_width if major else width),
                          "contour-major" if major else "contour", colour, level))  # fmt: skip
    return out


def _map_pieces(
    grid: DEM,
    interval: float | None,
    major_interval: float | None,
    width: float,
    major_width: float,
    dense_spacing: float,
    generalize: bool,
    labels: Sequence[ContourLabel],
) -> list[tuple[np.ndarray, bool, float]]:
    """:func:`map_lines` with each piece's level."""
    heights = np.where(grid.mask, grid.heights, np.nan).astype(np.float32)
    _lo, _hi, minor, major = contour_intervals(heights, interval, major_interval)
    if generalize:
        field, grad = generalized_field(heights, interval=minor)
    else:
        field = heights
        gy, gx = np.gradient(heights.astype(np.float64))
        grad = np.hypot(gx, gy).astype(np.float32)
    lines = contour_polylines(field, interval=minor, major_interval=major)
    widest = max(width, major_width) if major is not None else width
    ring = MIN_RING_WIDTHS * widest if generalize else 0.0
    cover = label_boxes(labels, heights.shape) if labels else None
    crowd = dense_spacing - width / 2
    out: list[tuple[np.ndarray, bool, float]] = []
    for line in lines:
        pts = line.points
        if len(pts) < 2:
            continue
        if line.closed and float((pts.max(axis=0) - pts.min(axis=0)).max()) <= ring:
            continue
        pts = _densify(pts, _VERTEX_PX)
        keep = np.ones(len(pts), bool)
        if not line.major:
            keep = _uncrowded(minor / np.maximum(_sample(grad, pts), 1e-30), crowd)
        if cover is not None:
            keep &= _sample(cover, pts) <= 0.0
        # a stub left between a label's box and a crowded stretch or another box goes
        pieces = [(a, b) for a, b in _runs(keep) if b - a >= _CROWD_PIECE or b - a == len(pts)]
        out.extend((pts[a:b], bool(line.major), float(line.level)) for a, b in pieces)
    return out


def _draw_vectors(fig, lines, labels, *, origin, dpi, map_options, font_px) -> None:
    """The contour lines and label text of a map as vector artists over its image, whose
    upper-left page pixel is ``origin`` (x from the left, y from the bottom of the page)."""
    from matplotlib.collections import LineCollection

    x0, top = origin
    inch = 1.0 / dpi

    def page(xy: np.ndarray) -> np.ndarray:
        # pixel centre (c, r) at page pixel (x0 + c + 0.5, top - r - 0.5), in inches
        return np.column_stack([(x0 + xy[:, 0] + 0.5) * inch, (top - xy[:, 1] - 0.5) * inch])

    colour = _validate.rgb(map_options.get("contour_color", CONTOUR_COLOR), "contour_color")
    pt = 72.0 / dpi  # points per map pixel
    widths = {False: float(map_options.get("width", 1.0)) * pt,
              True: float(map_options.get("major_width", 2.0)) * pt}  # fmt: skip
    for major in (False, True):
        segs = [page(p) for p, m in lines if m == major]
        if segs:
            fig.add_artist(LineCollection(
                segs, transform=fig.dpi_scale_trans, colors=[tuple(colour)],
                linewidths=widths[major], capstyle="butt", joinstyle="round", zorder=2,
            ))  # fmt: skip
    text_colour = map_options.get("label_color")
    text_colour = colour if text_colour is None else _validate.rgb(text_colour, "label_color")
    for lab in labels:
        ((x, y),) = page(np.array([[lab.x, lab.y]]))
        # the label's (x, y) is the centre of its ink; numerals stand on the baseline, which
        # lies half the ink's height (the box's less its margins) below it, at the text's foot
        a = math.radians(lab.angle)
        ink = lab.height - 2 * PAD_FONTS * font_px
        x += 0.5 * ink * inch * math.sin(a)
        y -= 0.5 * ink * inch * math.cos(a)
        fig.text(x, y, lab.text, transform=fig.dpi_scale_trans, rotation=lab.angle,
                 rotation_mode="anchor", ha="center", va="baseline",
                 fontsize=font_px * pt, family="DejaVu Sans", color=tuple(text_colour),
                 zorder=2)  # fmt: skip


#: Graticule spacings of geographic grids, in arc seconds (1", 2", 5", ... 30 deg).
_ARC_STEPS = (1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 18000, 36000,
              54000, 108000)  # fmt: skip
#: About this many graticule intervals across the map's wider side.
_TICKS = 5


def _tick_step(span: float, geographic: bool) -> float:
    """A round spacing giving about :data:`_TICKS` intervals over ``span`` (CRS units):
    1, 2 or 5 times a power of ten (metres), or a round angle (degrees)."""
    raw = span / _TICKS
    if geographic:
        arcsec = raw * 3600.0
        return min(_ARC_STEPS, key=lambda a: abs(math.log(a / arcsec))) / 3600.0
    e = math.floor(math.log10(raw))
    return min((m * 10.0**e for m in (1, 2, 5, 10)), key=lambda v: abs(math.log(v / raw)))


def tick_text(value: float, step: float, geographic: bool, axis: str) -> str:
    """A graticule value as printed on a map edge: metres with thin-space thousands
    (``485 000``), or degrees, minutes and seconds with the hemisphere (``105°25′W``), only
    as fine as the spacing ``step``; ``axis`` is ``'x'`` (east) or ``'y'`` (north)."""
    if not geographic:
        return f"{value:,.0f}".replace(",", "\u2009").replace("-", "\u2212")
    hemi = ("E", "W") if axis == "x" else ("N", "S")
    letter = hemi[0] if value >= 0 else hemi[1]
    total = round(abs(value) * 3600.0)
    deg, rest = divmod(total, 3600)
    minutes, seconds = divmod(rest, 60)
    step_s = round(step * 3600.0)
    text = f"{deg}\u00b0"
    if step_s % 3600 or minutes or seconds:
        text += f"{minutes:02d}\u2032" if deg or step_s < 3600 else f"{minutes}\u2032"
    if step_s % 60 or seconds:
        text += f"{seconds:02d}\u2033"
    return text + letter


def _graticule(fig, grid: DEM, corner: tuple[int, int], size: tuple[int, int], *, dpi: float,
               mode: str) -> None:  # fmt: skip
    """Coordinate ticks (and with ``mode='grid'`` grid lines) of the map's CRS on its frame:
    the map image's lower-left page pixel is ``corner``, its size ``(w, h)`` pixels."""
    from matplotlib.collections import LineCollection

    gx0, gdx, rx, gy0, ry, gdy = grid.transform
    if rx or ry:
        raise InputError("graticule: the grid is rotated (its transform has rotation terms)")
    x0, y0 = corner
    w, h = size
    inch = 1.0 / dpi
    mm = dpi / 25.4  # page pixels per mm
    west, east = sorted((gx0, gx0 + w * gdx))
    south, north = sorted((gy0, gy0 + h * gdy))
    step = _tick_step(max(east - west, north - south), grid.geographic)
    tick = 1.5 * mm
    segs, lines, texts = [], [], []
    for axis, lo, hi in (("x", west, east), ("y", south, north)):
        first = math.ceil(lo / step - 1e-9)
        for k in range(first, math.floor(hi / step + 1e-9) + 1):
            v = k * step
            if axis == "x":
                c = x0 + (v - gx0) / gdx  # page pixel column of the value
                if not x0 + 0.5 * mm <= c <= x0 + w - 0.5 * mm:
                    continue
                segs += [[(c, y0), (c, y0 - tick)], [(c, y0 + h), (c, y0 + h + tick)]]
                lines.append([(c, y0), (c, y0 + h)])
                texts.append((c, y0 - tick - 0.5 * mm, 0.0, "center", "top", v))
                texts.append((c, y0 + h + tick + 0.5 * mm, 0.0, "center", "bottom", v))
            else:
                r = y0 + h - (v - gy0) / gdy  # page pixel row from the bottom
                if not y0 + 0.5 * mm <= r <= y0 + h - 0.5 * mm:
                    continue
                segs += [[(x0, r), (x0 - tick, r)], [(x0 + w, r), (x0 + w + tick, r)]]
                lines.append([(x0, r), (x0 + w, r)])
                texts.append((x0 - tick - 0.5 * mm, r, 90.0, "right", "center", v))
                texts.append((x0 + w + tick + 0.5 * mm, r, 90.0, "left", "center", v))
    if not segs:
        return

    def inches(xy):
        return np.asarray(xy, float) * inch

    fig.add_artist(LineCollection([inches(sg) for sg in segs], transform=fig.dpi_scale_trans,
                                  colors="black", linewidths=0.5, zorder=3,
                                  gid="graticule-ticks"))  # fmt: skip
    if mode == "grid":
        fig.add_artist(LineCollection([inches(ln) for ln in lines],
                                      transform=fig.dpi_scale_trans, colors=[(0, 0, 0, 0.45)],
                                      linewidths=0.35, zorder=2, gid="graticule-grid"))  # fmt: skip
    for x, y, rot, ha, va, v in texts:
        axis = "x" if rot == 0.0 else "y"
        fig.text(x * inch, y * inch, tick_text(v, step, grid.geographic, axis),
                 transform=fig.dpi_scale_trans, rotation=rot, rotation_mode="anchor",
                 ha=ha if rot == 0.0 else "center", va=va if rot == 0.0 else
                 ("bottom" if ha == "right" else "top"), fontsize=5.5, zorder=3,
                 gid="graticule")  # fmt: skip


def map_page(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    page: str = "A4",
    landscape: bool = False,
    dpi: float = 300.0,
    scale: str | int | None = None,
    title: str | None = None,
    credit: str | None = None,
    labels: bool = True,
    legend: bool = True,
    vector: bool = False,
    graticule: str | bool = False,
    furniture: str = "outside",
    **map_options,
):
    """A matplotlib Figure of a print layout: the map at a round scale inside a frame, the
    furniture below it (legend, scale bar, north arrow, scale, credit), the title above.

    Parameters
    ----------
    dem : DEM, path, array or xarray.DataArray
    page : {'A4', 'A3', 'letter'}
    landscape : bool
    dpi : float, default: 300
        The page's resolution (and the map's: one map pixel per page pixel), at most
        ``LIMITS["dpi"]``; the page must stay within ``LIMITS["image_side"]`` pixels a side.
    scale : '1:N' or N, optional
        The map scale; default the smallest round scale at which the map fits the frame.
        A scale at which it does not fit is refused.
    title, credit : str, optional
    labels, legend : bool
        Contour labels (7 pt) and the hypsometric legend.
    vector : bool, default: False
        Contour lines and label text as vector artists over the map's image (which is then
        drawn without them): sharp at any zoom in a PDF, text selectable. The lines are
        :func:`map_lines`, the labels placed as in the raster map. ``write_map_page`` turns it
        on for a PDF.
    graticule : {False, 'ticks', 'grid'}, default: False
        Coordinates of the map's CRS on its frame: ticks with their values on all four
        edges (metres, or degrees-minutes-seconds on geographic grids; about five round
        intervals across), and with ``'grid'`` also thin grid lines across the map.
    furniture : {'outside', 'inside'}, default: 'outside'
        The legend, scale bar, north arrow and credit below the map frame, or on a white
        panel inside its lower edge (the map then takes the whole frame: a larger scale fits).
    **map_options
        Of :func:`~sciviz_gbuf.recipes.terrain.topographic_map` (intervals, bands, cmap,
        relief, ...), but not ``size``/``scale``/``dpi``.

    Returns
    -------
    matplotlib.figure.Figure
        With ``fig.sciviz_map = (image, (x0, y0), N)``: the map image, its lower-left corner
        in page pixels and the scale denominator.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon, Rectangle

    page = _validate.choice(page, "page", tuple(PAGES))
    landscape = _validate.boolean(landscape, "landscape")
    labels = _validate.boolean(labels, "labels")
    legend = _validate.boolean(legend, "legend")
    vector = _validate.boolean(vector, "vector")
    if graticule is not False:
        graticule = _validate.choice(graticule, "graticule", GRATICULES)
    furniture = _validate.choice(furniture, "furniture", FURNITURE)
    inside = furniture == "inside"
    dpi = _validate.size(dpi, "dpi", "dpi")
    for key in ("size", "scale", "dpi", "progress_bar"):
        if key in map_options:
            raise InputError(f"{key}: a page's map is sized by its scale and dpi, not by {key}=")
    for name, text in (("title", title), ("credit", credit)):
        if text is not None and (not isinstance(text, str) or len(text) > 500):
            raise InputError(f"{name}: expected a string of at most 500 characters")
    pw, ph, fw, fh = _frame_mm(page, landscape, bool(title), inside)
    side = max(pw, ph) / 25.4 * dpi
    if side > _validate.LIMITS["image_side"]:
        raise InputError(
            f"dpi: a {page} page at {dpi:g} dpi is {side:.0f} px long; expected at most "
            f"{int(_validate.LIMITS['image_side'])} (LIMITS['image_side'])"
        )
    d = as_dem(dem)
    n = _parse_scale(scale) or page_scale(
        d, page, landscape=landscape, title=bool(title), furniture=furniture
    )
    h, w = d.shape
    map_w_mm = w * d.pixel_size[0] / n / _MM
    map_h_mm = h * d.pixel_size[1] / n / _MM
    if map_w_mm > fw * 1.0001 or map_h_mm > fh * 1.0001:
        raise InputError(
            f"scale: at 1:{n} the map is {map_w_mm:.0f} x {map_h_mm:.0f} mm; the {page} "
            f"page's map frame is {fw:.0f} x {fh:.0f} mm (a smaller scale, 1:N with a larger N)"
        )
    scale_text = f"1:{n}"
    opts = {"scale": scale_text, "dpi": dpi}
    grid = map_grid(d, **opts)
    lines: list[tuple[np.ndarray, bool]] = []
    placed: list[ContourLabel] = []
    font_px = 0.0
    if vector:
        rest = {k: v for k, v in map_options.items() if k != "contours"}
        img = topographic_map(d, labels=False, contours=False, **opts, **rest)
        if map_options.get("contours", True):
            font_px, spacing_px = label_options(
                map_options.get("label_size"), map_options.get("label_spacing"), dpi
            )
            iv, mv = map_options.get("interval"), map_options.get("major_interval")
            if labels:
                placed = labels_of_grid(grid, iv, mv, font_px, spacing_px)
            keys = ("width", "major_width", "dense_spacing", "generalize")
            lines = map_lines(grid, interval=iv, major_interval=mv, labels=placed,
                              **{k: map_options[k] for k in keys if k in map_options})  # fmt: skip
    else:
        img = topographic_map(d, labels=labels, **opts, **map_options)
    ih, iw = img.shape[:2]
    fig = Figure(figsize=(pw / 25.4, ph / 25.4), dpi=dpi)
    fig.patch.set_facecolor("white")
    px = dpi / 25.4  # page pixels per mm
    # the map centred across its frame, at its top, at whole page pixels (placed as it is: no
    # resampling); the furniture follows right under it
    frame_x0 = MARGIN_MM + (fw - iw / px) / 2
    frame_y0 = MARGIN_MM + (0.0 if inside else STRIP_MM) + fh - ih / px
    x0, y0 = round(frame_x0 * px), round(frame_y0 * px)
    fig.figimage(img, xo=x0, yo=y0, origin="upper", resize=False, zorder=1)
    if vector:
        _draw_vectors(fig, lines, placed, origin=(x0, y0 + ih), dpi=dpi,
                      map_options=map_options, font_px=font_px)  # fmt: skip
    fx, fy = x0 / px / pw, y0 / px / ph  # figure fractions of the map's corner
    fwid, fhgt = iw / px / pw, ih / px / ph
    fig.add_artist(Rectangle((fx, fy), fwid, fhgt, transform=fig.transFigure, fill=False,
                             lw=0.8, ec="black", zorder=3))  # fmt: skip

    def at(x_mm: float, y_mm: float) -> tuple[float, float]:
        return x_mm / pw, y_mm / ph

    if title:
        # clear of the coordinates on the frame's top edge when there are any
        title_y = ph - MARGIN_MM - (TITLE_MM / 2 - (2.5 if graticule else 0.0))
        fig.text(*at(pw / 2, title_y), title, ha="center", va="center", fontsize=16,
                 family="DejaVu Sans")  # fmt: skip
    if graticule:
        _graticule(fig, grid, (x0, y0), (iw, ih), dpi=dpi, mode=graticule)
    # the furniture: below the frame across the page, or on a panel inside the frame's foot
    if inside:
        left, right, strip_top, z = x0 / px + 3.0, (x0 + iw) / px - 3.0, y0 / px + PANEL_MM - 3.0, 4
        fig.add_artist(Rectangle((fx, fy), fwid, PANEL_MM / ph, transform=fig.transFigure,
                                 fc=(1, 1, 1, 0.85), ec="black", lw=0.5, zorder=3.5))  # fmt: skip
    else:
        left, right, strip_top, z = MARGIN_MM, pw - MARGIN_MM, y0 / px - 6.0, 3
    # legend: swatches left to right with their edges
    _lo, _hi, minor, major = contour_intervals(
        grid.heights, map_options.get("interval"), map_options.get("major_interval")
    )
    if legend:
        keys = ("interval", "major_interval", "bands", "cmap", "sea_level", "vmin", "vmax")
        classes = legend_classes(grid, **{k: map_options[k] for k in keys if k in map_options})
        if classes:
            n_cls = len(classes)
            width = min(8.0, 0.55 * (right - left + 2 * MARGIN_MM) / n_cls)
            for i, c in enumerate(classes):
                fig.add_artist(
                    Rectangle(
                        at(left + i * width, strip_top - 8.0),
                        width / pw,
                        6.0 / ph,
                        transform=fig.transFigure,
                        fc=np.array(c.rgb) / 255.0,
                        ec="none",
                        zorder=z,
                    )
                )
            # the inner edges are the band edges (the outer ones the data's range)
            step = max(1, math.ceil(n_cls / 8))
            for i in range(1, n_cls, step):
                fig.text(*at(left + i * width, strip_top - 8.6), f"{classes[i].low:g}",
                         ha="center", va="top", fontsize=6, zorder=z)  # fmt: skip
            fig.text(*at(left, strip_top + 0.5), "Height (m)", ha="left", va="top",
                     fontsize=7, zorder=z)  # fmt: skip
    interval_text = f"Contour interval {minor:g} m" + (
        f", index contours every {major:g} m" if major is not None else ""
    )
    fig.text(*at(left, strip_top - 17.0), interval_text, ha="left", va="top", fontsize=7, zorder=z)
    # scale bar: two halves, black and white, at the map's scale
    bar = scale_bar(grid, fraction=0.3)
    bar_mm = bar.pixels / px
    bx = left + 0.62 * (right - left + 2 * MARGIN_MM) - MARGIN_MM
    for k in range(4):
        fig.add_artist(Rectangle(at(bx + k * bar_mm / 4, strip_top - 6.0), bar_mm / 4 / pw,
                                 1.6 / ph, transform=fig.transFigure,
                                 fc="black" if k % 2 == 0 else "white", ec="black",
                                 lw=0.5, zorder=z))  # fmt: skip
    for k, frac in enumerate((0.0, 0.5, 1.0)):
        v = bar.metres * frac
        text = bar.text if k == 2 else (f"{v / 1000:g}" if bar.metres >= 1000 else f"{v:g}")
        fig.text(*at(bx + frac * bar_mm, strip_top - 7.0), text, ha="center", va="top",
                 fontsize=6, zorder=z)  # fmt: skip
    fig.text(
        *at(bx + bar_mm / 2, strip_top - 1.5),
        f"Scale {n:,}".replace(",", "\u2009").replace("Scale ", "Scale 1:"),
        ha="center",
        va="top",
        fontsize=8,
        zorder=z,
    )
    # north arrow
    _gamma, note = _north_note(grid)
    ax_, ay_ = right - 5.0, strip_top - 9.0
    tri = np.array([[0.0, 7.0], [-2.2, 0.0], [0.0, 1.6], [2.2, 0.0]])
    fig.add_artist(
        Polygon(
            [at(ax_ + x, ay_ + y) for x, y in tri],
            closed=True,
            transform=fig.transFigure,
            fc="black",
            ec="black",
            zorder=z,
        )
    )
    fig.text(
        *at(ax_, ay_ + 8.0), "N", ha="center", va="bottom", fontsize=9, weight="bold", zorder=z
    )
    fig.text(*at(ax_ + 3.0, ay_ - 2.0), note, ha="right", va="top", fontsize=5.5, zorder=z)
    if credit:
        fig.text(*at(left, strip_top - 22.0), credit, ha="left", va="top", fontsize=6,
                 color="0.3", zorder=z)  # fmt: skip
    fig.sciviz_map = (img, (x0, y0), n)
    return fig


def write_map_page(path: str | os.PathLike, dem, **options) -> tuple[int, int]:
    """Write :func:`map_page` as PNG or PDF (by the suffix), all or nothing; returns the page
    size in pixels at its dpi. A PDF has vector contour lines and label text by default
    (``vector=True``), a PNG the map's own ink."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".png", ".pdf"):
        raise InputError(f"output: expected a .png or .pdf file for a page, got {str(path)!r}")
    import matplotlib

    options.setdefault("vector", suffix == ".pdf")
    fig = map_page(dem, **options)
    dpi = fig.dpi
    with atomic_output(path) as part:
        # TrueType fonts embedded (type 42): the PDF's text stays text (searchable, sharp)
        with open(part.path, "wb") as f, matplotlib.rc_context({"pdf.fonttype": 42}):
            meta = {"Creator": "sciviz-gbuf"} if suffix == ".pdf" else None
            fig.savefig(f, format=suffix[1:], dpi=dpi, facecolor="white", metadata=meta)
    w, h = fig.get_size_inches() * dpi
    return int(w), int(h)  # as Agg sizes the canvas (truncated)
