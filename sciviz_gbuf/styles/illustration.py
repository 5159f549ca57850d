"""Shaded + edge illustrations of a G-buffer: the styles of the ``sciviz-gbuf edges`` command.

Every image is at the G-buffer's output size (``gb.output_shape``); with ``supersample > 1`` the
shade and the lines are averaged from the larger buffer, so silhouettes and lines are
antialiased. Background pixels are white paper.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from ..filters import edge_map, enhance, profile_and_crease_edges, profile_edges
from ..filters.edges import INNER_COLOR
from ..filters.shading import unit_light
from . import _tone_kernels as _tk
from ._ink import clump_cut
from .registry import check_style, register, styles_for

__all__ = [
    "LIGHT",
    "PAPER",
    "SHADE_AMBIENT",
    "SHADE_HIGHLIGHT",
    "STYLES",
    "edges_to_map",
    "fig7_edge_map",
    "illustrate",
    "is_dark",
    "line_ink",
    "profile_ink",
    "shade_image",
    "signed_to_grey",
    "thin_edge_map",
]

#: Eye-space light from the upper left, as in hand-drawn illustrations (every style's default).
LIGHT = (-0.4, 0.5, 0.77)
#: White paper: the background of every style.
PAPER = (1.0, 1.0, 1.0)
#: :func:`shade_image`: ambient term and the highlight (the brightest shade, below white so
#: that white edges stay visible on it).
SHADE_AMBIENT = 0.2
SHADE_HIGHLIGHT = 0.85
#: Luminance below which a line colour is dark ink: lines drawn in it are kept from filling
#: an area (:func:`thin_edge_map`).
DARK_INK = 0.5


def shade_image(
    gb: GBuffer,
    *,
    light: Sequence[float] = LIGHT,
    ambient: float = SHADE_AMBIENT,
    highlight: float = SHADE_HIGHLIGHT,
) -> np.ndarray:
    """Lambert shade of the G-buffer's normals on white paper, at the output size.

    ``highlight * (ambient + (1 - ambient) max(0, N.L))``: the brightest surface stays below
    white (``highlight``) so that white edge highlights remain visible on it.

    Returns
    -------
    (H, W) float32 in [0, 1]; 1 (paper) on the background, blended at the silhouette.
    """
    gb = check_gbuffer(gb)
    if not 0.0 < _validate.finite(highlight, "highlight") <= 1.0:
        raise InputError(f"highlight: expected a value in (0, 1], got {_validate.brief(highlight)}")
    out = np.empty(gb.output_shape, dtype=np.float32)
    # lambert, the paper and the box filter per output pixel in one pass (same arithmetic)
    _tk.lambert_shade(
        np.ascontiguousarray(gb.normal, dtype=np.float32),
        np.ascontiguousarray(gb.mask, dtype=np.bool_),
        unit_light(light),
        float(_validate.unit_interval(ambient, "ambient")),
        float(highlight),
        _validate.count(gb.supersample, "gb.supersample", "supersample"),
        out,
    )
    return out


def signed_to_grey(values: np.ndarray, *, scale: float = 1.0) -> np.ndarray:
    """Diverging grey of a signed image: 0 mid grey, ``+scale`` and above white, ``-scale`` black.

    NaN (background) is mid grey too.
    """
    scale = _validate.positive(scale, "scale")
    v = np.nan_to_num(np.asarray(values, dtype=np.float32), nan=0.0)
    return (0.5 + 0.5 * np.clip(v / np.float32(scale), -1.0, 1.0)).astype(np.float32)


def is_dark(color: Sequence[float] | None, name: str = "color") -> bool:
    """Whether lines drawn in ``color`` (RGB in [0, 1]; None: not drawn) are dark ink: Rec. 709
    luminance below :data:`DARK_INK`. ``name``: the parameter named in an error."""
    if color is None:
        return False
    rgb = _validate.rgb(color, name)
    return float(rgb @ np.float32([0.2126, 0.7152, 0.0722])) < DARK_INK


def _line_core(width: float) -> float:
    """The width whose clumps :func:`~._ink.declump` thins, for lines ``width`` output pixels
    wide: one pixel more, since antialiased lines off the pixel grid (and the 2003 lines,
    which straddle the edge) have a half-ink core up to a pixel wider than their width."""
    return float(width) + 1.0


def thin_edge_map(
    emap: np.ndarray,
    width: float = 1.0,
    *,
    inner_color: Sequence[float] | None = INNER_COLOR,
) -> np.ndarray:
    """An RGBA edge map whose dark lines never fill an area.

    Where the lines drawn in dark ink (the profiles in A; the inner edges in RGB too if
    ``inner_color`` is dark, see :func:`is_dark`) crowd into a clump thicker than a line (a
    bolt hole smaller than its outline, a thin fin between two profiles, a junction of
    several lines) only the clump's skeleton keeps its ink, one pixel wide and connected to
    the lines that run into it (:func:`~._ink.declump`); elsewhere the map is unchanged.
    Drawn over a dark shade, such a clump would be one solid black area.

    Parameters
    ----------
    emap : (H, W, 4) float32
        An edge map (:func:`~sciviz_gbuf.filters.edge_map`, :func:`fig7_edge_map`):
        inner-edge intensity in RGB, profile intensity in A.
    width : float, default: 1
        Its line width in output pixels.
    inner_color : RGB or None, default: white
        The colour the inner edges are drawn in (None: not drawn).

    Returns
    -------
    (H, W, 4) float32: ``emap`` itself if nothing was thinned, else a thinned copy.
    """
    emap = np.asarray(emap, dtype=np.float32)
    if emap.ndim != 3 or emap.shape[2] != 4:
        raise InputError(f"emap: expected an (H, W, 4) RGBA edge map, got shape {emap.shape}")
    width = _validate.size(width, "width", "line_width", low=1.0, closed=True)
    dark_inner = is_dark(inner_color, "inner_color")
    core = _line_core(width)
    profile = np.clip(np.nan_to_num(emap[..., 3], nan=0.0), 0.0, 1.0)
    cut = clump_cut(profile, core)  # profiles crowding: a small hole, a thin fin
    shared = None
    if dark_inner:
        # both drawn dark, one over the other: together they leave (1 - R)(1 - A) of the shade
        inner = np.clip(np.nan_to_num(emap[..., 0], nan=0.0), 0.0, 1.0)
        shared = clump_cut(profile + inner - profile * inner, core)
    if cut is None and shared is None:
        return emap
    out = emap.copy()
    if cut is not None:
        out[cut, 3] = np.float32(0.0)
        if dark_inner:
            out[cut, :3] = np.float32(0.0)
    if shared is not None:
        # Where dark inner edges run into profiles, the inner edges give way (but for the
        # clump's skeleton) and the profiles keep their lines, so the silhouette stays
        # outlined; profile ink too weak to be a line by itself (half-inked lines over one
        # another) keeps only the skeleton.
        out[shared, :3] = np.float32(0.0)
        out[shared & ~(profile > 0.5), 3] = np.float32(0.0)
    return out


def _thinned(ink: np.ndarray, width: float) -> np.ndarray:
    cut = clump_cut(ink, _line_core(width))
    if cut is not None:
        ink[cut] = np.float32(0.0)
    return ink


def profile_ink(gb: GBuffer, *, depth_jump: float = 1.0, width: float = 1.0) -> np.ndarray:
    """Black profile lines (:func:`~sciviz_gbuf.filters.profile_edges`) that never fill an
    area: clumps thinned to their skeleton (see :func:`thin_edge_map`). (H, W) float32 ink."""
    return _thinned(profile_edges(gb, depth_jump=depth_jump, width=width), width)


def line_ink(
    gb: GBuffer, *, crease_angle: float = 30.0, depth_jump: float = 1.0, width: float = 1.0
) -> np.ndarray:
    """The ink of the ``lines`` style: profile and crease lines, clumps thinned to their
    skeleton (see :func:`thin_edge_map`). (H, W) float32 in [0, 1] at the output size."""
    ink = np.maximum(
        *profile_and_crease_edges(
            gb, crease_angle=crease_angle, depth_jump=depth_jump, width=width, signed=False
        )
    )
    return _thinned(ink, width)


def fig7_edge_map(
    gb: GBuffer,
    *,
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
    black_only: bool = False,
) -> np.ndarray:
    """The 1990 Fig. 7 edge image as an RGBA map for :func:`~sciviz_gbuf.filters.enhance`.

    RGB: convex internal edges (to be drawn white); A: concave internal edges and profiles (to
    be drawn black), clumps of them thinned to their skeleton (see :func:`thin_edge_map`).
    ``black_only``: all internal edges in A (Fig. 7 (c'), absolute values).
    """
    prof, inner = profile_and_crease_edges(
        gb, crease_angle=crease_angle, depth_jump=depth_jump, width=width
    )
    return edges_to_map(inner, prof, black_only=black_only, width=width)


def edges_to_map(
    inner: np.ndarray,
    profile: np.ndarray,
    *,
    black_only: bool = False,
    width: float | None = None,
) -> np.ndarray:
    """RGBA edge map of signed internal edges and profile ink (see :func:`fig7_edge_map`).

    ``width``: the lines' width in output pixels; given, clumps of the black lines (A) are
    thinned to their skeleton (:func:`thin_edge_map`); None leaves them as they are.
    """
    if black_only:
        white, black = np.zeros_like(inner), np.maximum(profile, np.abs(inner))
    else:
        white, black = np.maximum(inner, 0.0), np.maximum(profile, np.maximum(-inner, 0.0))
    emap = np.stack([white, white, white, black], axis=-1).astype(np.float32)
    if width is None:
        return emap
    return thin_edge_map(emap, width)


def illustrate(
    gb: GBuffer,
    *,
    style: str = "enhance",
    operator: str = "diagonal",
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
    light: Sequence[float] = LIGHT,
) -> np.ndarray:
    """One illustration of a G-buffer in one of the ``"illustrate"`` styles of the registry.

    Parameters
    ----------
    gb : GBuffer
    style : {"enhance", "lines", "fig7", "edgemap"}, default: "enhance"
        See :data:`STYLES` (``styles_for("illustrate")``).
    operator : {"diagonal", "c1"}, default: "diagonal"
        The 2003 edge-map operator (styles ``enhance`` and ``edgemap``; the other styles use
        the pair-wise profile and internal edges of :mod:`sciviz_gbuf.filters`).
    crease_angle, depth_jump, width
        As in :func:`sciviz_gbuf.filters.internal_edges` (degrees, pixel footprints, output
        pixels; ``width`` in [1, 64]: at most ``LIMITS["line_width"]``).
    light : 3 floats
        Eye-space direction towards the light of the shade.

    Returns
    -------
    (H, W, 3) float32 RGB in [0, 1]; ``edgemap``: (H, W, 4) RGBA.
    """
    style = check_style(style, "illustrate")
    gb = check_gbuffer(gb)
    # before any image is made (the edge filters check the rest)
    _validate.size(width, "width", "line_width", low=1.0, closed=True)
    opts = {"crease_angle": crease_angle, "depth_jump": depth_jump, "width": width}
    if style in ("enhance", "edgemap"):
        emap = edge_map(gb, operator=operator, **opts)
        if style == "edgemap":
            return emap  # the map itself, as the filter makes it
        # black profiles never fill an area, even around a hole smaller than its outline
        return enhance(shade_image(gb, light=light), thin_edge_map(emap, width))
    if style == "lines":
        ink = line_ink(gb, **opts)
        return np.repeat((1.0 - ink)[..., None], 3, axis=2).astype(np.float32)
    return enhance(shade_image(gb, light=light), fig7_edge_map(gb, **opts))


def _illustration(style: str):
    def draw(gb: GBuffer, **options) -> np.ndarray:
        return illustrate(gb, style=style, **options)

    draw.__name__ = draw.__qualname__ = f"illustrate_{style}"
    return draw


_EDGE_FRONTS = ("illustrate", "explore", "live")
register(
    "enhance",
    "shaded, white inner edges, black profiles (2003 edge map)",
    fronts=_EDGE_FRONTS,
    draw=_illustration("enhance"),
)
register(
    "lines",
    "black profile and crease lines on white paper",
    fronts=_EDGE_FRONTS,
    draw=_illustration("lines"),
)
register(
    "fig7",
    "shaded, convex edges white, concave edges and profiles black (1990 Fig. 7)",
    fronts=_EDGE_FRONTS,
    draw=_illustration("fig7"),
)
register(
    "edgemap",
    "the RGBA edge map itself: RGB inner-edge intensity, alpha profile (2003)",
    fronts=("illustrate",),
    draw=_illustration("edgemap"),
)
register(
    "profile",
    "profiles (silhouettes, borders, occlusions) only, over the rendering",
    fronts=("live",),
)
#: The styles of :func:`illustrate` (``{name: description}``, from the registry).
STYLES = styles_for("illustrate")
