"""Turn G-buffer channels into images: colour maps, normal and id colouring, PNG, montages.

All functions are vectorised, return new arrays and never modify their inputs. RGB images are
``(H, W, 3)`` float32 in ``[0, 1]`` unless said otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from . import _validate
from .errors import InputError
from .writers.geotiff import write_geotiff
from .writers.png import check_image, to_uint8, write_png

__all__ = [
    "colorize",
    "ids_to_rgb",
    "layered",
    "montage",
    "normals_to_rgb",
    "to_uint8",
    "with_colorbar",
    "write_geotiff",
    "write_png",
]

_Colour = Sequence[float]
_M24 = np.uint64(0xFFFFFF)


# ---------------------------------------------------------------------------- checks
def _array(values: object, name: str, ndim: int, trailing: tuple[int, ...] = ()) -> np.ndarray:
    a = np.asarray(values)
    if a.ndim != ndim or a.shape[2:] != trailing or a.size == 0:
        shape = "(H, W" + "".join(f", {t}" for t in trailing) + ")"
        raise InputError(f"{name}: expected a non-empty array of shape {shape}, got {a.shape}")
    return a


def _mask(mask: object, shape: tuple[int, ...]) -> np.ndarray | None:
    if mask is None:
        return None
    m = np.asarray(mask)
    if m.dtype != np.bool_ or m.shape != shape:
        raise InputError(f"mask: expected a bool array of shape {shape}, got {m.dtype} {m.shape}")
    return m


# ---------------------------------------------------------------------------- channels
def colorize(
    values: np.ndarray,
    *,
    mask: np.ndarray | None = None,
    cmap: str | object = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    background: _Colour = (1.0, 1.0, 1.0),
) -> np.ndarray:
    """Map a scalar image through a Matplotlib colour map.

    Parameters
    ----------
    values : (H, W) array_like of real numbers
        The channel, e.g. ``GBuffer.depth``; NaN marks background.
    mask : (H, W) bool array, optional
        Pixels to colour; the rest (and NaN) get ``background``.
    cmap : str or matplotlib.colors.Colormap, default: "viridis"
        Colour map or its registered name.
    vmin, vmax : float, optional
        Values mapped to ``cmap(0)`` and ``cmap(1)``; values outside are clipped. Default the
        range of the finite, masked values. A constant image maps to ``cmap(0.5)``.
    background : RGB triple in [0, 1], default: white

    Returns
    -------
    (H, W, 3) float32 ndarray in [0, 1]
    """

    v = _array(values, "values", 2)
    if not (np.issubdtype(v.dtype, np.number) or v.dtype == np.bool_) or np.iscomplexobj(v):
        raise InputError(f"values: expected real numbers, got dtype {v.dtype}")
    m = _mask(mask, v.shape)
    bg = _validate.rgb(background, "background")
    cm = _validate.colormap(cmap)
    v = v.astype(np.float64)
    valid = np.isfinite(v) if m is None else np.isfinite(v) & m
    lo, hi = _value_range(v, valid, vmin, vmax)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip((v - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.full(v.shape, 0.5)
    rgb = np.asarray(cm(np.where(valid, t, 0.0)), dtype=np.float32)[..., :3]
    rgb[~valid] = bg
    return rgb


def _value_range(
    v: np.ndarray, valid: np.ndarray, vmin: float | None, vmax: float | None
) -> tuple[float, float]:
    for name, x in (("vmin", vmin), ("vmax", vmax)):
        if x is not None and not np.isfinite(x):
            raise InputError(f"{name}: expected a finite number, got {x!r}")
    any_valid = bool(valid.any())
    lo = float(vmin) if vmin is not None else (float(v[valid].min()) if any_valid else 0.0)
    hi = float(vmax) if vmax is not None else (float(v[valid].max()) if any_valid else 1.0)
    if vmin is not None and vmax is not None and lo > hi:
        raise InputError(f"vmin, vmax: expected vmin <= vmax, got {lo} > {hi}")
    # A given limit beyond the data's range wins over the default other end.
    return (lo, max(lo, hi)) if vmin is not None else (min(lo, hi), hi)


def normals_to_rgb(
    normal: np.ndarray,
    *,
    mask: np.ndarray | None = None,
    background: _Colour = (1.0, 1.0, 1.0),
) -> np.ndarray:
    """The usual normal-map colouring: components in ``[-1, 1]`` map linearly to ``[0, 1]``.

    Parameters
    ----------
    normal : (H, W, 3) array_like
        Unit normals, e.g. ``GBuffer.normal`` (eye space: a normal facing the viewer,
        ``(0, 0, 1)``, is ``(0.5, 0.5, 1)``); pixels with a NaN component are background.
    mask : (H, W) bool array, optional
        Pixels to colour; the rest get ``background``.
    background : RGB triple in [0, 1], default: white

    Returns
    -------
    (H, W, 3) float32 ndarray in [0, 1]
    """
    n = _array(normal, "normal", 3, (3,))
    if not np.issubdtype(n.dtype, np.floating):
        raise InputError(f"normal: expected floating-point components, got dtype {n.dtype}")
    m = _mask(mask, n.shape[:2])
    bg = _validate.rgb(background, "background")
    valid = np.isfinite(n).all(axis=-1)
    if m is not None:
        valid &= m
    with np.errstate(invalid="ignore"):
        rgb = np.clip((n.astype(np.float32) + 1.0) * 0.5, 0.0, 1.0)
    rgb[~valid] = bg
    return rgb


def _mix24(x: np.ndarray) -> np.ndarray:
    """A bijection of 24-bit integers with good avalanche (multiply by odd, xor-shift)."""
    for mult, shift in ((0x9E3779, 12), (0x85EBCB, 11), (0xC2B2AF, 13)):
        x = (x * np.uint64(mult)) & _M24
        x ^= x >> np.uint64(shift)
    return x


def ids_to_rgb(ids: np.ndarray, *, background: _Colour = (1.0, 1.0, 1.0)) -> np.ndarray:
    """Colour integer labels (object or cell ids) so that neighbouring ids look different.

    Parameters
    ----------
    ids : (H, W) integer array_like
        Labels; negative values (``-1`` in a G-buffer) are background.
    background : RGB triple in [0, 1], default: white

    Returns
    -------
    (H, W, 3) float32 ndarray in [0, 1]
        The colour of an id is a hash of it: equal ids get equal colours in every image, and
        ids that differ modulo ``2**24`` get different 8-bit colours (the hash is a bijection
        of 24-bit integers).
    """
    a = _array(ids, "ids", 2)
    if not np.issubdtype(a.dtype, np.integer):
        raise InputError(f"ids: expected an integer array, got dtype {a.dtype}")
    bg = _validate.rgb(background, "background")
    valid = a >= 0
    x = np.where(valid, a, 0).astype(np.uint64)
    # Fold high bits in (a no-op below 2**24, so the bijection holds there); the offset keeps
    # id 0, the only object of most scenes, from hashing to black.
    x = (x ^ (x >> np.uint64(24)) ^ (x >> np.uint64(48))) + np.uint64(0x6A09E6)
    h = _mix24(x & _M24)
    channels = [(h >> np.uint64(s)) & np.uint64(0xFF) for s in (16, 8, 0)]
    rgb = np.stack(channels, axis=-1).astype(np.float32) / np.float32(255.0)
    rgb[~valid] = bg
    return rgb


def _as_rgb(image: object, name: str) -> np.ndarray:
    """Any accepted image as (H, W, 3) uint8 (alpha dropped, grey repeated)."""
    a = to_uint8(check_image(image, name))
    if a.ndim == 2:
        return np.repeat(a[..., None], 3, axis=2)
    return a[..., :3]


def _fit_text(draw, text: str, font, width: int) -> str:
    """``text``, shortened with an ellipsis until it fits ``width`` pixels."""
    if draw.textlength(text, font=font) <= width:
        return text
    while text and draw.textlength(text + "…", font=font) > width:
        text = text[:-1]
    return text + "…"


def montage(
    images: Sequence[tuple[str, np.ndarray]],
    *,
    columns: int | None = None,
    background: _Colour = (1.0, 1.0, 1.0),
    padding: int = 4,
) -> np.ndarray:
    """Tile titled images into one image, row by row.

    Parameters
    ----------
    images : sequence of (str, image)
        Title and image (any form :func:`write_png` accepts); sizes may differ: every tile is
        as large as the largest image, which is centred in it.
    columns : int, optional
        Tiles per row; default ``ceil(sqrt(len(images)))``.
    background : RGB triple in [0, 1], default: white
    padding : int, default: 4
        Pixels between tiles and around the titles.

    Returns
    -------
    (H, W, 3) float32 ndarray in [0, 1]
        Titles are drawn above each tile in black with Pillow's default font.
    """
    from PIL import Image, ImageDraw, ImageFont

    if isinstance(images, (str, bytes)) or not isinstance(images, Sequence) or not images:
        raise InputError("images: expected a non-empty list of (title, image) pairs")
    tiles = []
    for i, item in enumerate(images):
        if not (isinstance(item, Sequence) and len(item) == 2 and isinstance(item[0], str)):
            raise InputError(f"images[{i}]: expected a (title, image) pair, got {type(item)}")
        tiles.append((item[0], _as_rgb(item[1], f"images[{i}]")))
    n = len(tiles)
    if columns is None:
        columns = math.ceil(math.sqrt(n))
    if isinstance(columns, bool) or not isinstance(columns, (int, np.integer)) or columns < 1:
        raise InputError(f"columns: expected a positive integer, got {columns!r}")
    if isinstance(padding, bool) or not isinstance(padding, (int, np.integer)) or padding < 0:
        raise InputError(f"padding: expected a non-negative integer, got {padding!r}")
    bg = tuple(int(c) for c in to_uint8(_validate.rgb(background, "background")[None, None])[0, 0])

    tile_h = max(t.shape[0] for _, t in tiles)
    tile_w = max(t.shape[1] for _, t in tiles)
    try:  # Pillow >= 10.1 scales its default (FreeType) font
        font = ImageFont.load_default(size=max(10, tile_h // 30))
    except (TypeError, ImportError):
        font = ImageFont.load_default()
    canvas_probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    text_h = canvas_probe.textbbox((0, 0), "Ag", font=font)[3]
    cell_w, cell_h = tile_w + padding, tile_h + text_h + 2 * padding
    rows = math.ceil(n / columns)
    cols = min(columns, n)
    canvas = Image.new("RGB", (cols * cell_w + padding, rows * cell_h + padding), bg)
    draw = ImageDraw.Draw(canvas)
    for k, (title, tile) in enumerate(tiles):
        x0 = padding + (k % columns) * cell_w
        y0 = padding + (k // columns) * cell_h
        label = _fit_text(draw, title, font, tile_w)
        tx = x0 + (tile_w - draw.textlength(label, font=font)) / 2
        draw.text((tx, y0), label, fill=(0, 0, 0), font=font)
        oy = y0 + text_h + padding + (tile_h - tile.shape[0]) // 2
        ox = x0 + (tile_w - tile.shape[1]) // 2
        canvas.paste(Image.fromarray(tile), (ox, oy))
    return np.asarray(canvas, dtype=np.float32) / np.float32(255.0)


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About ``n`` round tick values within [lo, hi] (1, 2, 5 times a power of ten apart)."""
    if not hi > lo:
        return [lo]
    raw = (hi - lo) / max(1, n - 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1.0, 2.0, 5.0, 10.0) if m * power >= raw)
    first = math.ceil(lo / step - 1e-9) * step
    out = []
    k = 0
    while first + k * step <= hi + 1e-9 * step and k < 50:
        out.append(first + k * step)
        k += 1
    return out


def _tick_text(v: float, step: float) -> str:
    if v == 0.0:
        return "0"
    if abs(v) >= 1e5 or abs(v) < 1e-3:
        return f"{v:.2g}"
    digits = max(0, -math.floor(math.log10(step))) if step > 0 else 0
    return f"{v:.{digits}f}"


def with_colorbar(
    image: np.ndarray,
    *,
    cmap: str | object = "viridis",
    vmin: float,
    vmax: float,
    label: str,
    background: _Colour = (1.0, 1.0, 1.0),
) -> np.ndarray:
    """``image`` with a horizontal colour bar below it: the colour map from ``vmin`` to
    ``vmax`` with round tick values and ``label`` (what the colours measure, with its unit).

    Parameters
    ----------
    image : (H, W, 3) or (H, W) image
        Any form :func:`write_png` accepts: e.g. the output of :func:`colorize` made with the
        same ``cmap``, ``vmin`` and ``vmax``.
    cmap : str or matplotlib.colors.Colormap, default: "viridis"
    vmin, vmax : float
        The values at the two ends of the colour map (``vmin < vmax``; equal values draw one
        tick).
    label : str
        E.g. ``"depth (scene units)"``, ``"elevation (m)"``.
    background : RGB triple in [0, 1], default: white

    Returns
    -------
    (H + bar, W, 3) float32 ndarray in [0, 1]
        The image unchanged on top; the bar (about a twelfth of the height, at least 34 px)
        below, its ticks and label in black with Pillow's default font.
    """
    from PIL import Image, ImageDraw, ImageFont

    rgb = _as_rgb(image, "image")
    lo, hi = (_validate.finite(v, n) for v, n in ((vmin, "vmin"), (vmax, "vmax")))
    if lo > hi:
        raise InputError(f"vmin, vmax: expected vmin <= vmax, got {lo} > {hi}")
    if not isinstance(label, str):
        raise InputError(f"label: expected a string, got {type(label).__name__}")
    cm = _validate.colormap(cmap)
    bg = tuple(int(c) for c in to_uint8(_validate.rgb(background, "background")[None, None])[0, 0])
    h, w = rgb.shape[:2]
    try:
        font = ImageFont.load_default(size=max(10, min(18, h // 28)))
    except (TypeError, ImportError):
        font = ImageFont.load_default()
    probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    text_h = probe.textbbox((0, 0), "Ag", font=font)[3]
    margin = max(6, w // 40)
    bar_h = max(6, text_h // 2 + 2)
    strip_h = 3 + bar_h + 2 + text_h + 2 + text_h + 3
    canvas = Image.new("RGB", (w, h + strip_h), bg)
    canvas.paste(Image.fromarray(rgb), (0, 0))
    x0, x1 = margin, max(margin + 2, w - margin)
    t = np.linspace(0.0, 1.0, x1 - x0)
    colours = to_uint8(np.asarray(cm(t), np.float32)[None, :, :3])
    bar = np.repeat(colours, bar_h, axis=0)
    y0 = h + 3
    canvas.paste(Image.fromarray(bar), (x0, y0))
    draw = ImageDraw.Draw(canvas)
    draw.rectangle((x0 - 1, y0 - 1, x1, y0 + bar_h), outline=(0, 0, 0))
    ticks = _ticks(lo, hi)
    step = ticks[1] - ticks[0] if len(ticks) > 1 else 0.0
    last_end = -1e9
    for v in ticks:
        x = x0 + (0.5 if hi == lo else (v - lo) / (hi - lo)) * (x1 - x0 - 1)
        draw.line((x, y0 + bar_h, x, y0 + bar_h + 2), fill=(0, 0, 0))
        text = _tick_text(v, step)
        tw = draw.textlength(text, font=font)
        tx = min(max(0.0, x - tw / 2), w - tw)
        if tx > last_end + 4:  # never overprint a neighbour's label
            draw.text((tx, y0 + bar_h + 2), text, fill=(0, 0, 0), font=font)
            last_end = tx + tw
    text = _fit_text(draw, label, font, w - 2 * margin)
    tw = draw.textlength(text, font=font)
    draw.text(((w - tw) / 2, y0 + bar_h + 4 + text_h), text, fill=(0, 0, 0), font=font)
    return np.asarray(canvas, dtype=np.float32) / np.float32(255.0)


# ---------------------------------------------------------------------------- layers
#: :func:`layered` defaults: the light (eye space, as the styles'), the ink of the outlines.
LAYERED_LIGHT = (-0.4, 0.5, 0.77)
LAYERED_INK = (0.12, 0.1, 0.1)


def _per_object(value: object, n: int, name: str, check) -> list:
    """One value per object id: a single value for all, or a sequence of ``n``."""
    if (
        isinstance(value, (list, tuple))
        and len(value) == n
        and (name != "colors" or (n and np.ndim(value[0]) == 1))
    ):
        return [check(v) for v in value]
    return [check(value)] * n


def layered(
    gb,
    *,
    opacity: float | Sequence[float] = 0.35,
    colors: _Colour | Sequence[_Colour] = (0.85, 0.85, 0.85),
    light: _Colour = LAYERED_LIGHT,
    ambient: float = 0.3,
    profile_width: float = 1.5,
    edge_color: _Colour = LAYERED_INK,
    background: _Colour | None = None,
) -> np.ndarray:
    """Surfaces and the ones behind them, composed with opacity: a translucent picture from a
    multi-layer G-buffer (``capture(..., layers=k)``; 1990 §5.1's extended G-buffer).

    Each object's first surface along each ray is gathered from the layers (a translucent
    skin is one film: its far side does not dim what lies inside twice), and along each ray
    these are taken front to back down to the first opaque one (``opacity`` 1). Each is
    shaded (Lambert,
    ``ambient + (1 - ambient) max(0, N.L)``, times its object's colour) and outlined by its
    own profile and crease lines (:func:`~sciviz_gbuf.filters.profile_and_crease_edges` of
    that object's surface alone: no line where two objects meet at one depth), and they are
    laid over each other from the deepest to the front, each surface with its
    object's ``opacity`` and its lines at full ink: a line behind a translucent surface shows
    through it attenuated as the surface's colour is, and lines of different layers cross
    correctly.

    Parameters
    ----------
    gb : GBuffer
        Its first layer and ``gb.layers``.
    opacity : float or one per object, default: 0.35
        In [0, 1]; 1 hides what lies behind.
    colors : RGB or one per object, default: light grey
    light, ambient
        Eye-space direction towards the light; ambient term in [0, 1].
    profile_width : float in [1, 64], default: 1.5
        Width of the outlines, output pixels; their ink is ``edge_color``.
    background : RGB, optional
        Opaque background; default transparent (alpha = coverage).

    Returns
    -------
    (H, W, 4) float32 RGBA in [0, 1] at the output size.
    """
    from .core.gbuffer import check_gbuffer
    from .filters import lambert, profile_and_crease_edges

    gb = check_gbuffer(gb)
    n_obj = max(1, len(gb.object_names), int(gb.object_id.max()) + 1)
    alphas = _per_object(opacity, n_obj, "opacity",
                         lambda v: _validate.unit_interval(v, "opacity"))  # fmt: skip
    rgbs = _per_object(colors, n_obj, "colors", lambda v: _validate.rgb(v, "colors"))
    amb = _validate.unit_interval(ambient, "ambient")
    ink_rgb = _validate.rgb(edge_color, "edge_color").astype(np.float32)
    width = _validate.size(profile_width, "profile_width", "line_width")
    alpha_of = np.asarray(alphas, np.float32)
    rgb_of = np.asarray(rgbs, np.float32).reshape(n_obj, 3)
    from scipy import ndimage

    from .core.gbuffer import GBuffer

    h, w = gb.output_shape
    stack = [gb, *gb.layers]
    # Each object's own first surface along every ray, gathered from the layers: what it
    # shows were it alone (a translucent skin is one film, its far side is not seen again;
    # a bone behind it is seen whole). Its lines are found on it alone, so where two objects
    # meet at nearly one depth (a thin skin on a skull) no line is drawn between them.
    ids = [np.where(layer.mask, layer.object_id, -1) for layer in stack]
    present = sorted({int(o) for i in ids for o in np.unique(i) if o >= 0})
    surfaces = {}
    for o in present:
        pick = np.full(gb.shape, -1, np.int64)
        for k in range(len(stack) - 1, -1, -1):
            pick[ids[k] == o] = k
        found = pick >= 0
        k_safe = np.where(found, pick, 0)

        def gather(name: str, k_safe=k_safe, found=found):
            arrs = np.stack([getattr(layer, name) for layer in stack])
            out = np.take_along_axis(arrs, k_safe[None, ..., None] if arrs.ndim == 4
                                     else k_safe[None], axis=0)[0]  # fmt: skip
            return out

        depth = np.where(found, gather("depth"), np.float32(np.nan)).astype(np.float32)
        surfaces[o] = GBuffer(
            depth=depth, sz=np.where(found, gather("sz"), np.float32(np.nan)),
            normal=np.where(found[..., None], gather("normal"), np.float32(np.nan)),
            world=np.where(found[..., None], gather("world"), np.float32(np.nan)),
            object_id=np.where(found, o, -1).astype(np.int32),
            cell_id=np.where(found, gather("cell_id"), -1).astype(np.int64),
            mask=found, camera=gb.camera, supersample=gb.supersample,
            object_names=list(gb.object_names),
        )  # fmt: skip
    # per pixel, the objects front to back down to the first opaque one
    depths = np.stack([np.where(surfaces[o].mask, surfaces[o].depth, np.inf) for o in present])
    order = np.argsort(depths, axis=0, kind="stable")
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.arange(len(present))[:, None, None], axis=0)
    opaque_depth = np.full(gb.shape, np.inf)
    for i, o in enumerate(present):
        if alpha_of[o] >= 1.0:
            opaque_depth = np.minimum(opaque_depth, depths[i])
    img = np.zeros((h, w, 3), np.float32)
    cover = np.zeros((h, w), np.float32)
    for r in range(len(present) - 1, -1, -1):
        for i, o in enumerate(present):
            surf = surfaces[o]
            inc = surf.mask & (rank[i] == r) & (depths[i] <= opaque_depth)
            if not inc.any():
                continue
            shade = amb + (1.0 - amb) * np.nan_to_num(
                lambert(surf.normal, light=light, mask=surf.mask)
            )
            a = alpha_of[o] * inc
            a_out = surf.downsample(a.astype(np.float32))
            c_out = surf.downsample(
                (rgb_of[o] * shade[..., None] * a[..., None]).astype(np.float32)
            )
            img = c_out + (1.0 - a_out[..., None]) * img
            cover = a_out + (1.0 - a_out) * cover
            # its lines where it is shown (and a pixel beyond: a profile lies on the nearer
            # side of its step)
            prof, crease = profile_and_crease_edges(surf, width=width, signed=False)
            shown = ndimage.grey_dilation(surf.downsample(inc.astype(np.float32)), size=3)
            ink = (np.maximum(prof, crease) * shown)[..., None]
            img = ink * ink_rgb + (1.0 - ink) * img
            cover = ink[..., 0] + (1.0 - ink[..., 0]) * cover
    out = np.empty((h, w, 4), np.float32)
    # premultiplied -> straight colour where something is drawn
    safe = np.where(cover > 0, cover, 1.0)[..., None]
    out[..., :3] = np.clip(img / safe, 0.0, 1.0)
    out[..., 3] = np.clip(cover, 0.0, 1.0)
    if background is not None:
        bg = _validate.rgb(background, "background").astype(np.float32)
        out[..., :3] = out[..., :3] * out[..., 3:] + bg * (1.0 - out[..., 3:])
        out[..., 3] = 1.0
    return out
