"""Line drawing illustrations and their photocopies (Saito & Takahashi 1990 §4.2, Figs. 9-10).

Fig. 9 composes an illustration from G-buffers: the shaded image ``sh`` from the normals, the
profile image ``pr`` from ``sz``, and curved hatching ``cu`` / ``cv`` (§3.4, Eq. 17-21) of the
``u`` and ``v`` G-buffers; "enhancing the hatching images with the sh image and composing with
the pr image" gives ``shu``, ``shv`` and ``shuv``.

Fig. 10 makes the case for line drawings: copied five times on an inexpensive copy machine, the
``sh`` image is ruined while ``cv`` keeps almost its original quality. :func:`photocopy` is a
model of such a machine, so that the claim can be tested.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from scipy import ndimage

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from ..filters import hatching, lambert, modulated_hatching, profile_edges
from ..filters.shading import unit_light
from ._ink import declump
from ._tone_kernels import modulation_image
from .illustration import LIGHT
from .registry import register

__all__ = [
    "COMBOS",
    "TONE_FULL",
    "TONE_NONE",
    "drawing",
    "line_drawing",
    "modulation",
    "photocopy",
    "with_section_uv",
]

#: The images of 1990 Fig. 9 that :func:`line_drawing` makes, with what each one holds.
COMBOS = {
    "sh": "Lambert shade of the normals (the shaded image)",
    "pr": "profile lines from sz",
    "cu": "curved hatching of the u buffer",
    "cv": "curved hatching of the v buffer",
    "shu": "u hatching enhanced with sh, composed with pr",
    "shv": "v hatching enhanced with sh, composed with pr",
    "shuv": "u and v hatching enhanced with sh, composed with pr",
}
#: Tone ``1 - sh`` below which the enhanced hatching has no ink (highlights stay paper) ...
TONE_NONE = 0.1
#: ... and above which its lines are drawn in full.
TONE_FULL = 0.7


def modulation(shade: np.ndarray) -> np.ndarray:
    """How strongly the hatching is drawn at a shade: the "enhancing with sh" of Fig. 9.

    A smoothstep of the tone ``1 - sh`` from :data:`TONE_NONE` (0: lit, no lines) to
    :data:`TONE_FULL` (1: full lines); NaN shade (background) gives 0.
    """
    t = np.float32(1.0) - np.nan_to_num(np.asarray(shade, dtype=np.float32), nan=1.0)
    x = np.clip((t - np.float32(TONE_NONE)) / np.float32(TONE_FULL - TONE_NONE), 0.0, 1.0)
    return (x * x * (np.float32(3.0) - np.float32(2.0) * x)).astype(np.float32)


def _field(gb: GBuffer, index: int) -> np.ndarray:
    """``gb.uv[..., index]`` as the hatching kernels read it (the mask goes with it)."""
    return np.ascontiguousarray(gb.uv[..., index], dtype=np.float32)


def _hatch(gb: GBuffer, index: int, spacing: float, width: float) -> np.ndarray:
    """Curved hatching (Eq. 17-21) of ``gb.uv[..., index]`` at the buffer resolution."""
    k = gb.supersample
    return hatching(_field(gb, index), spacing=spacing * k, width=width * k, mask=gb.mask)


def _modulation(gb: GBuffer, light: Sequence[float]) -> np.ndarray:
    """:func:`modulation` of the Lambert shade of ``gb`` at the buffer resolution, in one pass
    (the same values as ``modulation(lambert(gb.normal, light=light, mask=gb.mask))``)."""
    out = np.empty(gb.shape, dtype=np.float32)
    modulation_image(
        np.ascontiguousarray(gb.normal, dtype=np.float32),
        np.ascontiguousarray(gb.mask, dtype=np.bool_),
        unit_light(light),
        TONE_NONE,
        TONE_FULL,
        out,
    )
    return out


def _enhanced(gb: GBuffer, index: int, spacing: float, width: float, m: np.ndarray):
    """Hatching whose lines thin out and fade with the light, at the buffer resolution.

    Where ``m`` (see :func:`modulation`) is 1 the lines are ``width`` wide; down to ``m = 0.5``
    they narrow to half that width (a blend of the two antialiased line images, which moves
    the line's edges); below, the thin line fades out. Narrowing first keeps the lines crisp
    (black), which is what survives copying (Fig. 10); only the lightest tones get faint ink.
    Both widths and the blend are one stencil pass (:func:`~sciviz_gbuf.filters.
    modulated_hatching`).
    """
    k = gb.supersample
    return modulated_hatching(
        _field(gb, index), m, spacing=spacing * k, width=width * k, mask=gb.mask
    )


def line_drawing(
    gb: GBuffer,
    *,
    combo: str = "shuv",
    spacing: float = 6.0,
    width: float = 1.0,
    light: Sequence[float] = LIGHT,
    profile_width: float = 1.5,
) -> np.ndarray:
    """One image of the 1990 Fig. 9 line drawing illustration (§4.2, hatching §3.4).

    Parameters
    ----------
    gb : GBuffer
        Needs ``gb.uv`` (the paper's ``ou``, ``ov`` buffers) for every combo with u or v.
    combo : {"sh", "pr", "cu", "cv", "shu", "shv", "shuv"}, default: "shuv"
        ``sh``: the Lambert shade of the normals (the shaded image, not a line drawing);
        ``pr``: black profile lines (:func:`~sciviz_gbuf.filters.profile_edges`);
        ``cu`` / ``cv``: curved hatching (:func:`~sciviz_gbuf.filters.hatching`, Eq. 17-21)
        of ``u`` / ``v`` at the buffer resolution, alone as in Fig. 9;
        ``shu`` / ``shv`` / ``shuv``: that hatching "enhanced with sh" — full lines where the
        tone ``1 - sh`` exceeds :data:`TONE_FULL`, thinner lines in half-tones, fading to no
        ink below :data:`TONE_NONE` (see :func:`modulation`) — composed with ``pr``.
        Ink of overlapping lines is combined with ``max``. Where lines converge into a clump
        thicker than a line, only its skeleton keeps ink: no combo but ``sh`` fills an area.
    spacing : float in (0, 1024], default: 6
        ``d_i`` of Eq. 18-20: on-screen hatch spacing in output pixels; at most
        ``LIMITS["spacing"]`` = 1024.
    width : float in (0, 64], default: 1
        Hatch line width in output pixels; at most ``LIMITS["line_width"]`` = 64.
    light : 3 floats, default: ``LIGHT`` (upper left)
        Eye-space direction towards the light of ``sh``.
    profile_width : float in [1, 64], default: 1.5
        Width of the profile lines in output pixels; at most ``LIMITS["line_width"]`` = 64.

    Returns
    -------
    (H, W) float32 grey in [0, 1] at ``gb.output_shape``; 1 is paper (also the background).
    """
    check_gbuffer(gb)
    combo = _validate.choice(combo, "combo", sorted(COMBOS))
    _validate.count(gb.supersample, "gb.supersample", "supersample")
    sp = _validate.size(spacing, "spacing", "spacing")
    wd = _validate.size(width, "width", "line_width")
    pw = _validate.size(profile_width, "profile_width", "line_width", low=1.0, closed=True)
    needs_uv = "u" in combo or "v" in combo
    if needs_uv and gb.uv is None:
        raise InputError(f"combo: {combo!r} needs texture coordinates (u, v), but gb.uv is None")
    unit_light(light)  # validates light
    if combo == "sh":
        shade = lambert(gb.normal, light=light, mask=gb.mask)  # NaN off the mask
        return np.clip(gb.downsample(np.where(gb.mask, shade, 1.0)), 0, 1).astype(np.float32)
    # A line drawing never fills an area: where lines converge into a solid clump (the inner
    # rim of a torus meeting its silhouette, profiles crowding at grazing angles) only the
    # clump's centre lines keep their ink (see ``declump``).
    thickest = max(pw, wd)
    if combo == "pr":
        return np.clip(1.0 - declump(profile_edges(gb, width=pw), pw), 0, 1).astype(np.float32)
    if combo in ("cu", "cv"):
        ink = gb.downsample(_hatch(gb, "uv".index(combo[1]), sp, wd))
        return np.clip(1.0 - declump(ink, wd), 0.0, 1.0).astype(np.float32)
    m = _modulation(gb, light)
    ink = profile_edges(gb, width=pw)
    for name in combo[2:]:
        ink = np.maximum(ink, gb.downsample(_enhanced(gb, "uv".index(name), sp, wd, m)))
    return np.clip(1.0 - declump(ink, thickest), 0.0, 1.0).astype(np.float32)


def _tone_curve(x: np.ndarray, pivot: float, contrast: float) -> np.ndarray:
    """Normalised logistic: 0 -> 0, 1 -> 1, steepest at ``pivot``."""

    def logistic(z):
        return 1.0 / (1.0 + np.exp(-contrast * (z - pivot)))

    lo, hi = logistic(0.0), logistic(1.0)
    return (logistic(x) - lo) / (hi - lo)


def photocopy(
    image: np.ndarray,
    *,
    copies: int = 5,
    blur: float = 0.5,
    pivot: float = 0.55,
    contrast: float = 10.0,
    noise: float = 0.01,
    seed: int | None = None,
) -> np.ndarray:
    """A model of an inexpensive copy machine, applied ``copies`` times (1990 Fig. 10).

    Each copy (of the previous copy) goes through

    1. toner spread: a Gaussian blur of ``blur`` pixels (standard deviation);
    2. the copier's tone curve: a normalised logistic, steepest at the grey ``pivot``
       (``0 -> 0``, ``1 -> 1``). Copiers reproduce black and paper but not tones: with the
       default contrast greys darker than about the pivot end up darker, lighter ones lighter
       (the slope at the pivot is ~2.5, so mid-tone differences grow 2.5-fold per copy and
       their gradation is crushed into black and paper); a pivot a little above mid grey
       models toner that darkens, so thin antialiased lines are regenerated rather than lost;
    3. sensor noise: Gaussian, standard deviation ``noise`` (seeded RNG);
    4. 8-bit re-quantisation.

    Parameters
    ----------
    image : (H, W) or (H, W, C) array in [0, 1]
        Grey (1 = paper) or colour, copied per channel.
    copies : int in [0, 100], default: 5
        Generations (0 returns the image, clipped to [0, 1] and quantised to 8 bits); at most
        ``LIMITS["copies"]`` = 100.
    blur : float in [0, 64], default: 0.5
        Toner spread in pixels. Lines narrower than about three times ``blur`` fade a little
        in each copy and lose their ends (blur + threshold is a curvature flow); with 1-pixel
        lines ``blur`` above ~0.55 erases them within five copies. At most
        ``LIMITS["blur"]`` = 64.
    pivot : float in (0, 1), default: 0.55
        Grey level where the tone curve is steepest.
    contrast : float > 0, default: 10
        Steepness of the logistic (slope at the pivot ~ ``contrast / 4``).
    noise : float >= 0, default: 0.01
        Standard deviation of the noise added in each copy.
    seed : int, optional
        Seed of the noise; the same seed gives the same copies.

    Returns
    -------
    float32 array shaped like ``image``, in [0, 1], multiples of 1/255.
    """
    copies = _validate.count(copies, "copies", "copies", low=0)
    # the blur's kernel is 8 sigma wide: bounded like a line width
    bl = _validate.size(blur, "blur", "blur", closed=True)
    pv = _validate.finite(pivot, "pivot")
    if not 0 < pv < 1:
        raise InputError(f"pivot: expected a grey level in (0, 1), got {pivot!r}")
    ct = _validate.positive(contrast, "contrast")
    nz = _validate.finite(noise, "noise")
    if not nz >= 0:
        raise InputError(f"noise: expected a finite number >= 0, got {noise!r}")
    if not (seed is None or (isinstance(seed, (int, np.integer)) and not isinstance(seed, bool))):
        raise InputError(f"seed: expected None or an integer, got {_validate.brief(seed)}")
    if seed is not None and seed < 0:
        raise InputError(f"seed: expected an integer >= 0, got {seed!r}")
    try:
        img = np.asarray(image, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"image: expected a numeric array, got {_validate.brief(image)}") from None
    if img.ndim not in (2, 3) or img.size == 0:
        raise InputError(f"image: expected an (H, W) or (H, W, C) array, got shape {img.shape}")
    if not np.all(np.isfinite(img)):
        raise InputError("image: contains NaN or inf")
    rng = np.random.default_rng(seed)
    sigma = (bl, bl) + (0.0,) * (img.ndim - 2)  # blur across the page, not across channels
    out = np.round(np.clip(img, 0.0, 1.0) * 255.0) / 255.0
    for _ in range(int(copies)):
        if bl > 0:
            out = ndimage.gaussian_filter(out, sigma=sigma, mode="nearest")
        out = _tone_curve(out, pv, ct)
        if nz > 0:
            out = out + rng.normal(0.0, nz, size=out.shape)
        out = np.round(np.clip(out, 0.0, 1.0) * 255.0) / 255.0
    return out.astype(np.float32)


def with_section_uv(gb: GBuffer) -> GBuffer:
    """The G-buffer with ``uv`` replaced by two world coordinates, for surfaces without a
    parameterisation: curved hatching of them draws parallel sections (1990 §3.4), across the
    two world axes least aligned with the line of sight."""
    sight = np.abs(np.asarray(gb.camera.direction, dtype=np.float64))
    a, b = sorted(np.argsort(sight)[:2])
    uv = np.where(gb.mask[..., None], gb.world[..., [a, b]], np.float32(np.nan))
    return dataclasses.replace(gb, uv=uv.astype(np.float32))


def drawing(gb: GBuffer, *, combo: str = "shuv", **options) -> np.ndarray:
    """:func:`line_drawing` as an RGB picture, for any surface: one without texture coordinates
    is hatched along sections of world axes (:func:`with_section_uv`) and, since two crossing
    families of sections make moire on curved parts, with one family only (``shuv`` becomes
    ``shu``); the surface parameterisation of u and v does not.

    Returns
    -------
    (H, W, 3) float32 grey RGB in [0, 1], 1 = paper.
    """
    gb = check_gbuffer(gb)
    if gb.uv is None:
        gb = with_section_uv(gb)
        combo = {"shuv": "shu", "cv": "cu", "shv": "shu"}.get(combo, combo)
    grey = line_drawing(gb, combo=combo, **options)
    return np.repeat(grey[..., None], 3, axis=2)


register(
    "drawing",
    "line drawing: profiles and shade-modulated curved hatching (1990 Fig. 9)",
    fronts=("npr",),
    draw=drawing,
    aliases=("lines",),
)
