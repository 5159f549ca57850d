"""SVG and PDF files of vector strokes, optionally over a raster picture (line art that scales).

One picture, two formats: :func:`write_svg` writes the strokes as SVG polylines,
:func:`write_pdf` the same strokes as PDF paths (one pixel = one point, so a 1 px line is
1 pt wide), :func:`write_strokes` picks by the file's suffix. Either embeds an optional
raster background (e.g. the shaded picture under the lines) at the picture's size.
"""

from __future__ import annotations

import base64
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from .. import _validate
from .._atomic import atomic_output
from ..errors import InputError
from ..filters.strokes import Stroke
from ._png_encoder import encode_png
from .png import check_image, to_uint8

__all__ = ["SvgText", "write_pdf", "write_strokes", "write_svg"]

#: Suffixes :func:`write_strokes` writes.
SUFFIXES = (".svg", ".pdf")


class SvgText(NamedTuple):
    """A text of an SVG, centred on ``(x, y)`` (pixels, as stroke vertices)."""

    text: str
    x: float
    y: float
    angle: float
    """Baseline direction, degrees anticlockwise as seen."""
    size: float
    """The em, pixels."""
    color: tuple[float, float, float] = (0.0, 0.0, 0.0)


def _rgb(color: Sequence[float]) -> str:
    r, g, b = (round(255 * min(max(float(c), 0.0), 1.0)) for c in color)
    return f"#{r:02x}{g:02x}{b:02x}"


def _num(v: float) -> str:
    text = f"{v:.3f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _check_path(path: str | os.PathLike, suffix: str) -> Path:
    p = Path(path)
    if p.suffix.lower() != suffix:
        raise InputError(f"path: expected a file name ending in {suffix}, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"path: no such directory {str(p.parent)!r}")
    return p


def _check_size(size: Sequence[int]) -> tuple[int, int]:
    if np.ndim(size) != 1 or len(size) != 2:
        raise InputError(f"size: expected (width, height) in pixels, got {_validate.brief(size)}")
    w, h = (_validate.size(v, "size", "image_side") for v in size)
    if w != int(w) or h != int(h):
        raise InputError(f"size: expected whole pixels, got {_validate.brief(size)}")
    return int(w), int(h)


def _check_background(background: np.ndarray, w: int, h: int) -> np.ndarray:
    img = to_uint8(check_image(background, "background"))
    if img.shape[:2] != (h, w):
        raise InputError(
            f"background: expected an image of {w} x {h} pixels, got {img.shape[1]} x "
            f"{img.shape[0]}"
        )
    return img


def _check_stroke(s: Stroke) -> tuple[np.ndarray, float]:
    pts = np.asarray(s.points, np.float64)
    width = float(s.width)
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.isfinite(pts).all():
        raise InputError(f"strokes: expected finite (N, 2) points, got shape {pts.shape}")
    if not (math.isfinite(width) and 0 < width <= _validate.LIMITS["line_width"]):
        raise InputError(
            f"strokes: expected a width in (0, {_validate.LIMITS['line_width']:g}] px, "
            f"got {_validate.brief(s.width)}"
        )
    return pts, width


def _dash(s: Stroke) -> tuple[float, float] | None:
    dash = getattr(s, "dash", None)
    if dash is None:
        return None
    if np.ndim(dash) != 1 or len(dash) != 2:
        raise InputError(
            f"strokes: dash: expected (on, off) in pixels, got {_validate.brief(dash)}"
        )
    on, off = (_validate.size(v, "strokes: dash", "spacing") for v in dash)
    return on, off


def write_svg(
    path: str | os.PathLike,
    strokes: Sequence[Stroke],
    *,
    size: tuple[int, int],
    background: np.ndarray | None = None,
    texts: Sequence[SvgText] = (),
    title: str | None = None,
) -> Path:
    """Write ``strokes`` (and ``texts``) as an SVG of ``size = (width, height)`` pixels, all or
    nothing, over the raster ``background`` (an image of that size, embedded as PNG) if given.

    Each stroke is a ``<polyline>`` (``<polygon>`` when closed) with round joins and butt caps,
    its width in pixels, its kind as its ``class`` and a contour's level as ``data-level``;
    coordinates are the pixel positions plus 0.5 (SVG's pixel ``i`` spans ``[i, i + 1]``), to
    a thousandth of a pixel. Strokes of one kind are grouped. Text is DejaVu Sans (the family
    named; a viewer without it substitutes).

    Raises
    ------
    InputError
        A name not ending in ``.svg``, a missing folder, a bad size, a background of another
        size, a stroke with non-finite points or width.
    OutputError
        The file could not be written completely (nothing is left under its name).
    """
    p = _check_path(path, ".svg")
    w, h = _check_size(size)
    parts = [
        '<?xml version="1.0" encoding="UTF-8"?>\n',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
        f'viewBox="0 0 {w} {h}">\n',
    ]
    if title:
        parts.append(f"<title>{escape(str(title))}</title>\n")
    if background is not None:
        img = _check_background(background, w, h)
        data = base64.b64encode(encode_png(img)).decode("ascii")
        href = f"data:image/png;base64,{data}"
        parts.append(f'<image x="0" y="0" width="{w}" height="{h}" '
                     f'preserveAspectRatio="none" href="{href}"/>\n')  # fmt: skip
    groups: dict[str, list[Stroke]] = {}
    for s in strokes:
        groups.setdefault(str(s.kind), []).append(s)
    for kind, group in groups.items():
        parts.append(f'<g class={quoteattr(kind)} fill="none" stroke-linejoin="round" '
                     'stroke-linecap="butt">\n')  # fmt: skip
        for s in group:
            pts, width = _check_stroke(s)
            if len(pts) < 2:
                continue
            coords = " ".join(f"{_num(x + 0.5)},{_num(y + 0.5)}" for x, y in pts)
            tag = "polygon" if s.closed else "polyline"
            level = "" if s.level is None else f' data-level="{float(s.level)!r}"'
            dash = _dash(s)
            dash = "" if dash is None else f' stroke-dasharray="{_num(dash[0])} {_num(dash[1])}"'
            parts.append(f'<{tag} points="{coords}" stroke="{_rgb(s.color)}" '
                         f'stroke-width="{_num(width)}"{level}{dash}/>\n')  # fmt: skip
        parts.append("</g>\n")
    if texts:
        parts.append('<g class="labels" font-family="DejaVu Sans" text-anchor="middle" '
                     'dominant-baseline="central">\n')  # fmt: skip
        for text, x, y, angle, em, color in texts:
            cx, cy = _num(x + 0.5), _num(y + 0.5)
            parts.append(f'<text x="{cx}" y="{cy}" font-size="{_num(em)}" fill="{_rgb(color)}" '
                         f'transform="rotate({_num(-angle)} {cx} {cy})">'
                         f"{escape(str(text))}</text>\n")  # fmt: skip
        parts.append("</g>\n")
    parts.append("</svg>\n")
    data = "".join(parts).encode("utf-8")
    with atomic_output(p) as part:
        part.path.write_bytes(data)
        part.expected_size = len(data)
    return p


def _pdf_figure(w: int, h: int, img, checked, texts):
    """The matplotlib figure of :func:`write_pdf` (made inside its rc context)."""
    from matplotlib.backends.backend_pdf import FigureCanvasPdf
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    fig = Figure(figsize=(w / 72.0, h / 72.0), dpi=72)
    FigureCanvasPdf(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)  # row 0 at the top, as the pixels
    if img is not None:
        ax.imshow(img, extent=(0, w, h, 0), interpolation="nearest", zorder=0)
    for s, pts, width in checked:
        if len(pts) < 2:
            continue
        xy = pts + 0.5  # pixel i spans [i, i + 1]
        style = {"linewidth": width, "capstyle": "butt", "joinstyle": "round", "zorder": 1}
        dash = _dash(s)
        if dash is not None:  # in points = pixels (rc lines.scale_dashes off, below)
            style["linestyle"] = (0, dash)
        if s.closed:
            ax.add_patch(Polygon(xy, closed=True, fill=False, edgecolor=tuple(s.color), **style))
        else:
            ax.add_collection(LineCollection([xy], colors=[tuple(s.color)], **style))
    for text, x, y, angle, em, color in texts:
        ax.text(x + 0.5, y + 0.5, str(text), rotation=angle, rotation_mode="anchor",
                ha="center", va="center", fontsize=em, family="DejaVu Sans",
                color=tuple(color), zorder=2)  # fmt: skip
    return fig


def write_pdf(
    path: str | os.PathLike,
    strokes: Sequence[Stroke],
    *,
    size: tuple[int, int],
    background: np.ndarray | None = None,
    texts: Sequence[SvgText] = (),
    title: str | None = None,
) -> Path:
    """Write the picture of :func:`write_svg` as a one-page PDF, all or nothing: a page of
    ``size`` points (one pixel = one point), the background an embedded image, each stroke a
    vector path (butt caps, round joins) and each text real text in embedded DejaVu Sans
    (TrueType, searchable). Raises as :func:`write_svg` (for a name ending in ``.pdf``)."""
    p = _check_path(path, ".pdf")
    w, h = _check_size(size)
    img = None if background is None else _check_background(background, w, h)
    checked = [(s, *_check_stroke(s)) for s in strokes]
    import matplotlib

    # dash lengths in points as given (not scaled by the width), fonts embedded as TrueType
    with matplotlib.rc_context({"pdf.fonttype": 42, "lines.scale_dashes": False}):
        fig = _pdf_figure(w, h, img, checked, texts)
    meta = {"Creator": "sciviz-gbuf"}
    if title:
        meta["Title"] = str(title)
    with atomic_output(p) as part:
        with (
            open(part.path, "wb") as f,
            matplotlib.rc_context({"pdf.fonttype": 42, "lines.scale_dashes": False}),
        ):
            fig.savefig(f, format="pdf", dpi=72, facecolor="white", metadata=meta)
    return p


def write_strokes(path: str | os.PathLike, strokes: Sequence[Stroke], **options) -> Path:
    """:func:`write_svg` or :func:`write_pdf` by the suffix of ``path`` (``options`` as
    theirs)."""
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise InputError(f"path: expected a file name ending in .svg or .pdf, got {str(path)!r}")
    return (write_svg if suffix == ".svg" else write_pdf)(path, strokes, **options)
