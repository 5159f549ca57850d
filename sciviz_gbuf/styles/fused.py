"""Every explorer style in one fused pass per pixel: the shade of ``N.L`` in the style, then the
edge map, colour-band tint and contour ink, straight to uint8 (no float image in between).

A deliberate second implementation of :func:`~sciviz_gbuf.styles.illustrate` (``enhance``,
``fig7``, ``lines``), :func:`~sciviz_gbuf.styles.gooch`, :func:`~sciviz_gbuf.styles.toon` and
:func:`~sciviz_gbuf.styles.hatch` at their default colours, kept for interactivity (a light or
style change in the explorer re-runs only this pass). It takes its constants from those
styles' own named constants (:data:`FUSED_CONSTANTS`), and a test holds it within one grey
level of them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..filters.edges import INNER_COLOR, PROFILE_COLOR
from . import _fused_kernels as _fk
from .hatch import HALO_CORE, HATCH_ANGLES, HATCH_MAX_INK, HATCH_SPACING, family_thresholds
from .illustration import PAPER, SHADE_AMBIENT, SHADE_HIGHLIGHT
from .registry import check_style
from .tone import (
    GOOCH_ALPHA,
    GOOCH_BASE,
    GOOCH_BETA,
    GOOCH_COOL,
    GOOCH_INNER_COLOR,
    GOOCH_PROFILE_COLOR,
    GOOCH_WARM,
    TOON_BASE,
    TOON_INNER_COLOR,
    TOON_LEVELS,
    TOON_PROFILE_COLOR,
    toon_shades,
)

__all__ = ["FUSED_CONSTANTS", "FUSED_MODES", "fused_constants", "fused_style", "rgba_on_paper"]

#: Base colour of each explorer style in the kernel: 0 Lambert shade below white
#: (``shade_image``), 1 gooch, 2 toon, 3 hatch, 4 ink lines on paper.
FUSED_MODES = {"enhance": 0, "fig7": 0, "gooch": 1, "toon": 2, "hatch": 3, "lines": 4}


def fused_constants() -> dict:
    """The styles' default colours and shade tables as the kernel's arguments."""
    f32 = np.float32
    base = np.asarray(GOOCH_BASE, f32)
    k_cool = np.asarray(GOOCH_COOL, f32) + f32(GOOCH_ALPHA) * base
    k_warm = np.asarray(GOOCH_WARM, f32) + f32(GOOCH_BETA) * base
    table = toon_shades(TOON_LEVELS)[:, None] * np.asarray(TOON_BASE, np.float64)[None, :]
    angles = np.radians(np.asarray(HATCH_ANGLES, np.float64))
    tau, left, _ = family_thresholds(len(HATCH_ANGLES), HATCH_MAX_INK)

    def pair(inner: Sequence[float], profile: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(inner, f32), np.asarray(profile, f32)

    edges = pair(INNER_COLOR, PROFILE_COLOR)
    return {
        "edge_colors": {
            "enhance": edges,
            "fig7": edges,
            "gooch": pair(GOOCH_INNER_COLOR, GOOCH_PROFILE_COLOR),
            "toon": pair(TOON_INNER_COLOR, TOON_PROFILE_COLOR),
        },
        "gooch": np.stack([k_cool, k_warm, np.asarray(PAPER, f32)]).astype(f32),
        "toon": table.astype(f32),
        "toon_bg": np.asarray(PAPER, f32),
        "hatch": np.stack([np.sin(angles), np.cos(angles)]).astype(np.float64),
        "hatch_spacing": np.float64(HATCH_SPACING),
        "hatch_tau": tau,
        "hatch_left": left,
        "hatch_ink": np.float32(HATCH_MAX_INK),
        "halo_core": np.float32(HALO_CORE),
        "shade": np.asarray([SHADE_AMBIENT, SHADE_HIGHLIGHT], f32),
    }


#: :func:`fused_constants`, computed once.
FUSED_CONSTANTS = fused_constants()

_EMPTY2 = np.zeros((0, 0), np.float32)
_EMPTY3 = np.zeros((0, 0, 0), np.float32)


def _f32(a: np.ndarray | None, empty: np.ndarray) -> np.ndarray:
    return empty if a is None else np.ascontiguousarray(a, np.float32)


def fused_style(
    style: str,
    normal: np.ndarray,
    mask: np.ndarray,
    light: Sequence[float],
    *,
    layer: np.ndarray | None = None,
    emap: np.ndarray | None = None,
    tint: np.ndarray | None = None,
    ink: np.ndarray | None = None,
    ink_color: Sequence[float] = (0.0, 0.0, 0.0),
    out: np.ndarray | None = None,
) -> np.ndarray:
    """One explorer picture in one pass (G-buffer without supersampling: output size).

    Parameters
    ----------
    style : str
        An ``"explore"`` style of the registry (a key of :data:`FUSED_MODES`).
    normal, mask : (H, W, 3) float32, (H, W) bool
        The G-buffer's eye-space normals and coverage.
    light : 3 floats
        Unit eye-space direction towards the light.
    layer : (H, W) float32, optional
        ``lines``: the ink of profiles and creases; ``hatch``: the profile ink.
    emap : (H, W, 4) float32, optional
        The edge map (RGB inner edges, alpha profiles) for ``enhance``, ``fig7``, ``gooch``,
        ``toon``; drawn in that style's edge colours.
    tint, ink : (H, W, 3) and (H, W) float32, optional
        Colour-band tint (multiplied on the surface) and contour ink (blended to ``ink_color``).
    out : (H, W, 3) uint8, optional
        Written in place.

    Returns
    -------
    (H, W, 3) uint8 RGB
    """
    style = check_style(style, "explore")
    if style in ("lines", "hatch") and layer is None:
        # The kernel reads the layer at every pixel of these styles: without one it would
        # read past an empty array.
        raise InputError(f"layer: style {style!r} needs its (H, W) ink layer, got None")
    h, w = np.shape(mask)[:2]
    # (name, array, channels: 0 for an (H, W) image, else at least that many)
    for name, a, ch in (
        ("normal", normal, 3), ("layer", layer, 0), ("emap", emap, 4), ("tint", tint, 3),
        ("ink", ink, 0), ("out", out, 3),
    ):  # fmt: skip
        if a is None:
            continue
        shape = tuple(np.shape(a))
        ok = shape == (h, w) if ch == 0 else len(shape) == 3 and shape[:2] == (h, w)
        if not ok or (ch and shape[2] < ch):
            want = f"({h}, {w})" if ch == 0 else f"({h}, {w}, >={ch})"
            raise InputError(f"{name}: expected shape {want} (the mask's), got {shape}")
    if out is not None and np.asarray(out).dtype != np.uint8:
        raise InputError(f"out: expected a uint8 RGB array, got dtype {np.asarray(out).dtype}")
    c = FUSED_CONSTANTS
    zero3 = np.zeros(3, np.float32)
    inner, prof = c["edge_colors"].get(style, (zero3, zero3)) if emap is not None else (zero3,) * 2
    if out is None:
        out = np.empty((*mask.shape, 3), dtype=np.uint8)
    _fk.compose_kernel(
        FUSED_MODES[style],
        normal,
        mask,
        np.asarray(light, np.float32),
        c["gooch"],
        c["toon"],
        c["toon_bg"],
        c["hatch"],
        c["hatch_spacing"],
        c["hatch_tau"],
        c["hatch_left"],
        c["hatch_ink"],
        c["halo_core"],
        c["shade"],
        _f32(layer, _EMPTY2),
        _f32(emap, _EMPTY3),
        inner,
        prof,
        _f32(tint, _EMPTY3),
        _f32(ink, _EMPTY2),
        np.asarray(ink_color, np.float32),
        out,
    )
    return out


def rgba_on_paper(rgba: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """The RGB of a uint8 RGBA image, white paper where it is fully transparent."""
    if out is None:
        out = np.empty((*rgba.shape[:2], 3), dtype=np.uint8)
    _fk.rgb_on_paper(rgba, out)
    return out
