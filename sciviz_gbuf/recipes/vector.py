"""Vector pictures: the line art of G-buffers, surfaces and maps as strokes over an optional
raster background, for SVG and PDF.

Each recipe returns a :class:`VectorPicture`: its lines as :class:`~sciviz_gbuf.filters.Stroke`
(vector, so they stay sharp at any zoom and can be restyled in an editor by their kind), the
rest of the picture (shading, colour bands, relief) as one raster background of the picture's
size, and its text (contour labels) as text. :func:`write_vector` writes it as SVG or PDF by
the file's suffix. Where the raster recipes draw the lines as ink (1990 §3-4), these draw the
same lines (same detectors, same levels) traced into strokes
(:func:`~sciviz_gbuf.filters.vectorize`) or, for contours, from the traced lines themselves.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from ..filters import Stroke, bridge, edge_strokes, hidden_edges, paint_strokes, vectorize
from ..filters.edges import HIDDEN_CLEARANCE
from ..styles.illustration import shade_image
from ..writers.vector import SvgText, write_strokes
from ._map import CONTOUR_COLOR, as_dem
from ._resample import map_grid
from .labels import label_options, labels_of_grid
from .layout import map_strokes
from .surface import LINE_COLOR, MODES, surface_layers
from .terrain import topographic_map

__all__ = [
    "BACKGROUNDS",
    "HIDDEN",
    "HIDDEN_GREY",
    "VectorPicture",
    "drawing_picture",
    "edge_picture",
    "surface_picture",
    "technical_drawing",
    "technical_drawing_image",
    "topographic_picture",
    "write_vector",
]

#: Backgrounds of :func:`edge_picture`: paper only, or the Lambert shade under the lines.
BACKGROUNDS = ("none", "shade")
#: How :func:`technical_drawing` draws hidden lines: dashed (ISO 128's type of line for
#: hidden edges, dashes 6 and gaps 3 line widths long, at least 4 and 2 px) or thin and grey.
HIDDEN = ("dashed", "thin")
#: Colour of thin hidden lines.
HIDDEN_GREY = (0.45, 0.45, 0.45)


class VectorPicture(NamedTuple):
    """Strokes, text and an optional raster background of one picture."""

    strokes: list[Stroke]
    """The lines, in the picture's pixels (x the column, y the row, pixel centres at
    integers)."""
    size: tuple[int, int]
    """(width, height) in pixels."""
    background: np.ndarray | None = None
    """(H, W), (H, W, 3) or (H, W, 4) image under the lines, or None (white paper)."""
    texts: tuple[SvgText, ...] = ()
    """Text over the lines (contour labels)."""


def write_vector(
    path: str | os.PathLike, picture: VectorPicture, *, title: str | None = None
) -> Path:
    """Write ``picture`` as SVG or PDF (by the suffix of ``path``), all or nothing
    (:func:`~sciviz_gbuf.writers.write_strokes`)."""
    if not isinstance(picture, VectorPicture):
        raise InputError(f"picture: expected a VectorPicture, got {type(picture).__name__}")
    return write_strokes(
        path, picture.strokes, size=picture.size, background=picture.background,
        texts=picture.texts, title=title,
    )  # fmt: skip


def _size(gb: GBuffer) -> tuple[int, int]:
    h, w = gb.output_shape
    return int(w), int(h)


def edge_picture(
    gb: GBuffer,
    *,
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
    min_length: float = 5.0,
    background: str = "none",
) -> VectorPicture:
    """Profile and crease lines of a G-buffer as strokes (1990 §3.2; kinds ``"profile"`` and
    ``"crease"``, :func:`~sciviz_gbuf.filters.edge_strokes`), on white paper or over the
    Lambert shade of the normals (``background="shade"``, the 2003 §5 shaded image)."""
    gb = check_gbuffer(gb)
    bg = _validate.choice(background, "background", BACKGROUNDS)
    strokes = edge_strokes(gb, crease_angle=crease_angle, depth_jump=depth_jump, width=width,
                           min_length=min_length)  # fmt: skip
    image = shade_image(gb) if bg == "shade" else None
    return VectorPicture(strokes, _size(gb), image)


def technical_drawing(
    gb: GBuffer,
    *,
    hidden: str | None = "dashed",
    width: float = 1.0,
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    min_length: float = 5.0,
    background: str = "none",
) -> VectorPicture:
    """A technical line drawing: the visible profile and crease lines solid (kinds
    ``"profile"``, ``"crease"``) and the hidden ones (kind ``"hidden"``: the edges of the
    surfaces behind, :func:`~sciviz_gbuf.filters.hidden_edges`) dashed, thin and grey, or
    left out (``hidden=None``).

    ``gb`` needs its layers behind (``capture(..., layers=k)``, k >= 2) unless ``hidden`` is
    None. A dashed stroke's pattern runs on along the whole stroke, through its vertices.
    """
    gb = check_gbuffer(gb)
    if hidden is not None:
        hidden = _validate.choice(hidden, "hidden", HIDDEN)
    pic = edge_picture(gb, crease_angle=crease_angle, depth_jump=depth_jump, width=width,
                       min_length=min_length, background=background)  # fmt: skip
    if hidden is None:
        return pic
    w = _validate.size(width, "width", "line_width")
    ink = hidden_edges(gb, crease_angle=crease_angle, depth_jump=depth_jump,
                       min_length=min_length)  # fmt: skip
    if hidden == "dashed":
        style = {"width": w, "dash": (max(4.0, 6.0 * w), max(2.0, 3.0 * w))}
    else:
        style = {"width": max(0.5, 0.5 * w), "color": HIDDEN_GREY}
    traced = vectorize(ink, kind="hidden", width=style["width"], min_length=3.0)
    # a hidden line is cut where a visible one crosses it (hidden_edges' clearance): one
    # stroke again, so its dashes run on across
    traced = bridge(traced, gap=2.0 * HIDDEN_CLEARANCE + 6.0)
    if "dash" in style:
        traced = [s._replace(dash=style["dash"]) for s in traced]
    else:
        traced = [s._replace(color=style["color"]) for s in traced]
    # hidden lines under the visible ones
    return pic._replace(strokes=traced + list(pic.strokes))


def technical_drawing_image(gb: GBuffer, **options) -> np.ndarray:
    """:func:`technical_drawing` as a raster image (H, W, 3) float32: its strokes drawn as
    an SVG viewer draws them (:func:`~sciviz_gbuf.filters.draw_strokes`: the same dashes)
    over its background (white paper or the shade)."""
    pic = technical_drawing(gb, **options)
    w, h = pic.size
    bg = np.ones((h, w), np.float32) if pic.background is None else pic.background
    return paint_strokes(pic.strokes, bg)


def drawing_picture(gb: GBuffer, **style_options) -> VectorPicture:
    """The line drawing of 1990 Fig. 9 (:func:`~sciviz_gbuf.styles.drawing`: profiles and
    curved hatching) traced into strokes of kind ``"drawing"``, each as wide as its ink.
    ``style_options`` as the drawing style's (``combo``, ``spacing``, ``width``, ...)."""
    from .npr import npr_image

    gb = check_gbuffer(gb)
    rgb = npr_image(gb, style="drawing", **style_options)
    ink = 1.0 - rgb.astype(np.float32).mean(axis=2) / 255.0
    return VectorPicture(vectorize(ink, kind="drawing", threshold=0.15, taper=True), _size(gb))


def surface_picture(
    gb: GBuffer,
    *,
    mode: str = "reflection",
    axis: Sequence[float] = (0.0, 0.0, 1.0),
    stripes: float = 16,
    width: float = 1.5,
    curvature: str = "gaussian",
    curvature_limit: float | None = None,
    interval: float | None = None,
    line_color: Sequence[float] = LINE_COLOR,
    profile_width: float = 1.5,
) -> VectorPicture:
    """A surface-analysis picture (1990 §4.5, Fig. 15; the modes of
    :func:`~sciviz_gbuf.recipes.surface.surface_analysis`) with its lines as strokes: the
    reflection, highlight, isophote or contour lines (kind = the mode) and the profiles
    (kind ``"profile"``) over the shaded surface; zebra stripes and curvature maps are areas,
    so they stay in the raster background and only their profiles are strokes."""
    gb = check_gbuffer(gb)
    if mode not in MODES:
        raise InputError(f"mode: expected one of {MODES}, got {mode!r}")
    lay = surface_layers(gb, mode=mode, axis=axis, stripes=stripes, width=width,
                         curvature=curvature, curvature_limit=curvature_limit,
                         interval=interval, profile_width=1.0)  # fmt: skip
    colour = tuple(float(c) for c in _validate.rgb(line_color, "line_color"))
    shade = (0.35 + 0.65 * lay["sh"])[..., None]
    if mode == "stripes":
        img = (1.0 - lay["ink"][..., None]) * np.clip(shade + 0.15, 0.0, 1.0)
        img = np.repeat(img, 3, axis=2)
    else:
        img = lay["rgb"] * shade
    alpha = lay["alpha"][..., None]
    background = np.clip(img * alpha + (1.0 - alpha), 0.0, 1.0).astype(np.float32)
    strokes: list[Stroke] = []
    if mode not in ("stripes", "curvature"):
        strokes += vectorize(lay["ink"], kind=mode, width=width, color=colour)
    pw = _validate.size(profile_width, "profile_width", "line_width")
    strokes += vectorize(lay["pr"], kind="profile", width=pw)
    return VectorPicture(strokes, _size(gb), background)


def topographic_picture(dem, **map_options) -> VectorPicture:
    """A topographic map (:func:`~sciviz_gbuf.recipes.terrain.topographic_map`, 1990 Fig. 11)
    with its contour lines as strokes (kinds ``"contour"`` and ``"contour-major"``, each with
    its level: :func:`~sciviz_gbuf.recipes.layout.map_strokes`) and, with ``labels=True``, its
    labels as text, over the map's colour bands and relief as the raster background.

    ``map_options`` are :func:`~sciviz_gbuf.recipes.terrain.topographic_map`'s (``size``,
    ``scale``, ``dpi``, ``interval``, ``labels``, ``width``, ``contour_color``, ...); the
    lines are the ones it draws as ink (same levels, the same generalisation, minors cut
    where they crowd, lines cut under the labels)."""
    d = as_dem(dem)
    opts = {k: map_options[k] for k in ("size", "scale", "dpi") if map_options.get(k) is not None}
    grid = map_grid(d, **opts)
    contours = map_options.get("contours", True)
    labels = bool(map_options.get("labels", False)) and contours
    rest = {k: v for k, v in map_options.items() if k not in ("contours", "labels")}
    image = topographic_map(d, labels=False, contours=False, **rest)
    strokes: list[Stroke] = []
    texts: list[SvgText] = []
    if contours:
        iv, mv = map_options.get("interval"), map_options.get("major_interval")
        placed = []
        colour = map_options.get("contour_color", CONTOUR_COLOR)
        if labels:
            font_px, spacing_px = label_options(
                map_options.get("label_size"), map_options.get("label_spacing"), opts.get("dpi")
            )
            placed = labels_of_grid(grid, iv, mv, font_px, spacing_px)
            text_colour = map_options.get("label_color")
            text_colour = colour if text_colour is None else text_colour
            rgb = tuple(float(c) for c in _validate.rgb(text_colour, "label_color"))
            texts = [SvgText(p.text, p.x, p.y, p.angle, font_px, rgb) for p in placed]
        keys = ("width", "major_width", "dense_spacing", "generalize")
        strokes = map_strokes(grid, interval=iv, major_interval=mv, labels=placed, color=colour,
                              **{k: map_options[k] for k in keys if k in map_options})  # fmt: skip
    h, w = image.shape[:2]
    return VectorPicture(strokes, (int(w), int(h)), image, tuple(texts))
