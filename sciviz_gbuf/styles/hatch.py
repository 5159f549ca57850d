"""Halftone hatching with a prioritised stroke texture (Nienhaus & Döllner 2003 §5, Fig. 8).

Nienhaus & Döllner combine their edge map with the real-time halftoning of Freudenberg et al.
(2002): a stroke texture whose texels carry a *priority* (the tone at which they turn to ink)
and a *smooth threshold function* that turns tone and priority into antialiased ink instead of
binary dither. Here the stroke texture is procedural and evaluated per pixel from the G-buffer:

* the tone is ``t = 1 - shade`` with the Lambert shade of the eye-space normals (1990 §4.2 sh);
* the families together cover the fraction ``m t`` of the paper, ``m = max_ink`` < 1: even the
  darkest tone keeps a share ``1 - m`` of paper between the strokes, so a face in shadow stays
  hatched (its strokes, outlines and the direction of the hatching readable) instead of
  turning solid black;
* stroke family ``f`` (``angles[f]``, in priority order) is a set of parallel strokes
  ``spacing`` pixels apart; it switches on when ``t`` passes its threshold ``tau_f`` and its
  stroke width grows continuously with ``t`` (Freudenberg's smooth threshold), so ink never
  decreases as the tone rises;
* darker tones add families (cross-hatching) rather than widening strokes until they merge:
  every family grows to the same final coverage ``a = 1 - (1 - m)^(1/N)`` (with the defaults a
  quarter of the spacing, 1.6 px strokes and 4.4 px of paper between them). With families at
  different angles overlapping independently the union is ``1 - prod(1 - c_f)``, so family
  ``f`` covers ``c_f = 1 - (1 - m t) / (1 - a)^f`` on ``[tau_f, tau_(f+1)]`` with
  ``tau_f = (1 - (1 - a)^f) / m``: the union is ``m t`` exactly;
* where the strokes crowd on screen (``"uv"`` strokes near a silhouette or a pole of the
  parameterisation, where their local period shrinks towards a pixel) they fade out between a
  period of :data:`CROWD_FULL` and :data:`CROWD_NONE` output pixels, so they never merge into a
  solid area;
* ink falls off over one pixel at the stroke's edges, measured as the distance in pixels to
  the stroke centre, so strokes are antialiased at any width (a stroke thinner than a pixel is
  drawn one pixel wide at proportionally less ink, keeping its ink per length).

The profile edges of the G-buffer are then drawn black on top (the 2003 edge enhancement),
with a one-pixel halo of paper on either side that keeps the strokes off them: outlines stay
visible over the darkest hatching.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import ndimage

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from ..filters import lambert
from ..filters.shading import unit_light
from . import _hatch_kernels as _hk
from .illustration import LIGHT, PAPER, profile_ink
from .registry import register

__all__ = [
    "CROWD_FULL",
    "CROWD_NONE",
    "HALO_CORE",
    "HATCH_ANGLES",
    "HATCH_MAX_INK",
    "HATCH_SPACING",
    "SPACES",
    "crowding",
    "family_thresholds",
    "hatch",
    "profile_halo",
    "stroke_ink",
    "tone_coverage",
]

#: Where the strokes live: fixed screen directions, or the surface's (u, v) parameterisation.
SPACES = ("screen", "uv")
#: :func:`hatch` defaults: stroke spacing in output pixels and the angles of the stroke
#: families in order of priority (the first covers the lightest tones).
HATCH_SPACING = 6.0
HATCH_ANGLES = (45.0, -45.0, 0.0, 90.0)
#: :func:`hatch` default: the share of the paper the strokes cover at the darkest tone.
HATCH_MAX_INK = 0.7
#: Profile ink from which a pixel counts as part of the line (no halo there, see
#: :func:`profile_halo`).
HALO_CORE = 0.25
#: Local stroke period, in output pixels, above which strokes are drawn in full ...
CROWD_FULL = 3.0
#: ... and below which they are left out (they would merge with their neighbours).
CROWD_NONE = 1.5
# More families than this do not darken anything further and only cost time.
_MAX_FAMILIES = int(_validate.LIMITS["families"])


def _angles(value) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        raise InputError(
            f"angles: expected a sequence of degrees, got {_validate.brief(value)}"
        ) from None
    if not 1 <= a.size <= _MAX_FAMILIES or not np.all(np.isfinite(a)):
        raise InputError(
            f"angles: expected 1 to {_MAX_FAMILIES} finite angles in degrees, got {value!r}"
        )
    return np.radians(a)


def family_thresholds(n_families: int, max_ink: float = HATCH_MAX_INK):
    """Thresholds and paper shares of the prioritised stroke families (see the module notes).

    Returns
    -------
    tau : (N + 1,) float32
        Family ``f`` switches on at ``tau[f]`` and is complete at ``tau[f + 1]``
        (``tau[0] = 0``, ``tau[N] = 1``).
    left : (N,) float32
        ``(1 - a)^f``: the paper the families before ``f`` leave when all are complete.
    a : float
        The final coverage of every family, ``1 - (1 - max_ink)^(1 / N)``.
    """
    n, m = int(n_families), float(max_ink)
    a = 1.0 - (1.0 - m) ** (1.0 / n)
    left = (1.0 - a) ** np.arange(n + 1, dtype=np.float64)
    tau = np.clip((1.0 - left) / m, 0.0, 1.0)
    tau[-1] = 1.0
    return tau.astype(np.float32), left[:-1].astype(np.float32), a


def tone_coverage(tone: np.ndarray, n_families: int, max_ink: float = HATCH_MAX_INK) -> np.ndarray:
    """Paper fraction ``c_f`` each stroke family covers at tone ``t`` (prioritised thresholds).

    Family ``f`` switches on at ``t = tau_f`` (:func:`family_thresholds`) and grows to the
    common final coverage ``a`` at ``tau_(f+1)``, so that ``1 - prod_f (1 - c_f) = max_ink t``:
    the families together cover the tone, scaled so that the darkest tone keeps ``1 - max_ink``
    of paper (cross-hatching, no solid black).

    Parameters
    ----------
    tone : (H, W) array in [0, 1]
        ``1 - shade``.
    n_families : int >= 1
    max_ink : float in (0, 1], default: :data:`HATCH_MAX_INK`

    Returns
    -------
    (N, H, W) float32 in [0, 1], non-decreasing in ``tone``.
    """
    t = np.clip(np.asarray(tone, dtype=np.float32), 0.0, 1.0)
    n = int(n_families)
    return np.stack([_family_coverage(t, f, n, max_ink) for f in range(n)]).astype(np.float32)


def stroke_ink(distance: np.ndarray, width: np.ndarray) -> np.ndarray:
    """Antialiased ink of a stroke ``width`` pixels wide at ``distance`` pixels from its centre.

    The ink ramps linearly over one pixel centred on the stroke's edge (the pixel-area coverage
    of a straight edge, as the 1990 line profile f1, Fig. 4b); strokes narrower than a pixel are
    a pixel wide at ``width`` of full ink. Either way a stroke puts ``width`` pixels of ink
    across itself, so a family of strokes ``s`` pixels apart covers ``width / s`` of the paper.
    """
    w = np.maximum(np.asarray(width, dtype=np.float32), np.float32(0.0))
    d = np.abs(np.asarray(distance, dtype=np.float32))
    a = np.maximum((w + np.float32(1.0)) * np.float32(0.5), np.float32(1.0))
    cap = np.minimum(w, np.float32(1.0))
    return (cap * np.clip(a - d, 0.0, 1.0)).astype(np.float32)


def _robust_gradient(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel (d/dx, d/dy) of ``f`` (x right, y up), from the smaller one-sided difference.

    One-sided differences that cross a NaN (background) or a parameter seam (u jumping from 1
    back to 0 on a torus) are much larger than, or unavailable next to, the other side's, so
    taking the smaller one keeps the surface's own gradient there.
    """

    f = np.asarray(f, dtype=np.float32)

    def along(axis: int) -> np.ndarray:
        def cut(lo, hi):  # slice lo:hi along `axis`
            return (slice(None), slice(lo, hi)) if axis == 1 else (slice(lo, hi), slice(None))

        out = np.zeros_like(f)
        if f.shape[axis] < 2:
            return out
        diff = np.diff(f, axis=axis)
        # First and last pixel: the only one-sided difference there is.
        out[cut(0, 1)] = diff[cut(0, 1)]
        out[cut(-1, None)] = diff[cut(-1, None)]
        fwd, back = diff[cut(1, None)], diff[cut(None, -1)]
        # The smaller of the two; a NaN side loses (a NaN forward one fails the comparison).
        take_fwd = np.abs(fwd) <= np.abs(back)
        take_fwd |= np.isnan(back)
        out[cut(1, -1)] = np.where(take_fwd, fwd, back)
        return np.nan_to_num(out, copy=False, nan=0.0)

    # rows run downwards: y up is minus the row derivative
    dy = along(0)
    np.negative(dy, out=dy)
    return along(1), dy


def _tone(normal: np.ndarray, light: object, mask: np.ndarray) -> np.ndarray:
    """``1 - lambert(normal, light, mask)`` with NaN and the background at 0, as (H, W) float32
    (in place on the shade, no further full-size array)."""
    shade = lambert(normal, light=light, mask=mask)
    np.nan_to_num(shade, copy=False, nan=1.0)
    return np.subtract(np.float32(1.0), shade, out=shade)


def _family_coverage(tone: np.ndarray, f: int, n: int, max_ink: float) -> np.ndarray:
    """Coverage of family ``f`` of ``n`` (ink where ``tone > tau_f``): one family of
    :func:`tone_coverage`, in float32 (the explorer's fused kernel takes the same steps)."""
    tau, left, _ = family_thresholds(n, max_ink)
    top = np.minimum(tone, tau[f + 1])  # each family stops growing at its band's end
    cover = np.float32(1.0) - (np.float32(1.0) - np.float32(max_ink) * top) / left[f]
    return np.clip(cover, 0.0, 1.0).astype(np.float32, copy=False)


def crowding(period: np.ndarray, k: int = 1) -> np.ndarray:
    """Weight of strokes whose local period is ``period`` buffer pixels (``k`` per output
    pixel): 1 from :data:`CROWD_FULL` output pixels up, falling linearly to 0 at
    :data:`CROWD_NONE`, where neighbouring strokes would merge."""
    lo, hi = np.float32(CROWD_NONE * k), np.float32(CROWD_FULL * k)
    return np.clip((np.asarray(period, np.float32) - lo) / (hi - lo), 0.0, 1.0)


def profile_halo(profile: np.ndarray) -> np.ndarray:
    """How much the strokes give way to paper next to the profiles: the largest profile ink
    within one pixel (3 x 3), off the lines' own pixels (ink >= :data:`HALO_CORE`, where the
    strokes stay and keep an antialiased silhouette dark), so that the profiles stand out
    over dark hatching."""
    prof = np.asarray(profile, np.float32)
    halo = ndimage.maximum_filter(prof, size=3, mode="nearest")
    halo[prof >= np.float32(HALO_CORE)] = np.float32(0.0)
    return halo


def _uv_stroke(u, v, ux, uy, vx, vy, a: float, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Stroke coordinate and local stroke period (pixels) of the uv family at angle ``a``."""
    # Whole numbers of strokes per unit of u and of v: a closed parameterisation (a torus, a
    # surface of revolution) wraps from 1 to 0 without a seam in the strokes.
    nv, nu = np.round(scale * np.cos(a)), np.round(scale * np.sin(a))
    if nu == 0 and nv == 0:
        nv = 1.0
    ca, sa = np.float32(nv), np.float32(nu)
    c = np.nan_to_num(v * ca - u * sa, nan=0.0)
    grad = np.hypot(vx * ca - ux * sa, vy * ca - uy * sa)
    # local stroke period in pixels; where it cannot be measured, no stroke
    period = np.where(grad > 0, 1.0 / np.maximum(grad, 1e-30), 0.0).astype(np.float32)
    return c, period


def hatch(
    gb: GBuffer,
    *,
    light: Sequence[float] = LIGHT,
    space: str = "screen",
    spacing: float = HATCH_SPACING,
    angles: Sequence[float] = HATCH_ANGLES,
    max_ink: float = HATCH_MAX_INK,
    max_width: float | None = None,
    uv_scale: float | None = None,
    edges: bool = True,
    profile_width: float = 1.0,
    ink: Sequence[float] = (0.0, 0.0, 0.0),
    paper: Sequence[float] = PAPER,
) -> np.ndarray:
    """Edge-enhanced halftone hatching of a G-buffer (2003 §5, Fig. 8; Freudenberg et al. 2002).

    Parameters
    ----------
    gb : GBuffer
    light : 3 floats, default: ``LIGHT`` (upper left)
        Eye-space direction towards the light of the Lambert shade; tone ``t = 1 - shade``.
    space : {"screen", "uv"}, default: "screen"
        ``"screen"``: straight strokes at ``angles`` (degrees counter-clockwise from the image x
        axis), ``spacing`` output pixels apart. ``"uv"``: strokes follow the surface
        parameterisation: family ``a`` draws the level lines of ``n_v v - n_u u`` with the
        whole numbers ``n_v = round(uv_scale cos a)``, ``n_u = round(uv_scale sin a)``, i.e.
        lines of constant ``v`` for ``a = 0``, of constant ``u`` for ``a = 90`` and diagonals of
        the (u, v) grid in between, seamless where u or v wraps from 1 to 0; their
        on-screen spacing varies with the parameterisation and foreshortening, and the stroke
        widths follow the local spacing (the gradient of the stroke coordinate, in pixels) so
        coverage still tracks the tone. Needs ``gb.uv``.
    spacing : float in (0, 1024], default: 6
        Stroke spacing in output pixels (``"uv"``: the median spacing, when ``uv_scale`` is
        not given); at most ``LIMITS["spacing"]`` = 1024.
    angles : sequence of 1-16 floats, default: (45, -45, 0, 90)
        Stroke families in priority order: the first darkens the lightest tones. At most
        ``LIMITS["families"]`` = 16.
    max_ink : float in [0.01, 0.99], default: 0.7
        Share of the paper the strokes cover at the darkest tone (the tone scale is
        ``max_ink * t``); every family then grows to ``1 - (1 - max_ink)^(1/N)`` of its
        spacing, so the darkest tones are cross-hatched with paper between the strokes.
    max_width : float in (0, 64], optional
        A further cap on the stroke width in output pixels (``"uv"``: as a fraction of the
        local spacing, ``max_width / spacing``); where it binds, coverage saturates. At most
        ``LIMITS["line_width"]`` = 64.
    uv_scale : float > 0, optional
        Strokes per unit of u or v (``"uv"`` only). Default: chosen so that the median
        on-screen spacing is ``spacing``.
    edges : bool, default: True
        Draw the profile edges (:func:`~sciviz_gbuf.filters.profile_edges`) in black on top,
        whatever ``ink`` is, with a one-pixel halo of paper (:func:`profile_halo`) that keeps
        the strokes off them.
    profile_width : float in [1, 64], default: 1
        Their width in output pixels; at most ``LIMITS["line_width"]`` = 64.
    ink, paper : 3 floats in [0, 1]
        RGB of the strokes and of the paper (background).

    Returns
    -------
    (H, W, 3) float32 RGB in [0, 1] at ``gb.output_shape``.

    Raises
    ------
    InputError
        A bad parameter (named), or ``space="uv"`` without texture coordinates.
    """
    check_gbuffer(gb)
    space = _validate.choice(space, "space", SPACES)
    k = _validate.count(gb.supersample, "gb.supersample", "supersample")
    # buffer pixels: the strokes are drawn supersampled
    sp = _validate.size(spacing, "spacing", "spacing") * k
    theta = _angles(angles)
    m_ink = _validate.number_in(max_ink, "max_ink", 0.01, 0.99)
    cap_w = None if max_width is None else _validate.size(max_width, "max_width", "line_width") * k
    scale = None if uv_scale is None else _validate.positive(uv_scale, "uv_scale")
    if uv_scale is not None and space != "uv":
        raise InputError("uv_scale: only used with space='uv'")
    _validate.size(profile_width, "profile_width", "line_width", low=1.0, closed=True)
    pw = float(profile_width)
    edges = _validate.boolean(edges, "edges")
    ink_c, paper_c = _validate.rgb(ink, "ink"), _validate.rgb(paper, "paper")
    if space == "uv" and gb.uv is None:
        raise InputError("space: 'uv' needs texture coordinates, but gb.uv is None")

    mask = np.asarray(gb.mask, dtype=bool)
    h, w = gb.shape
    if space == "screen":
        # Every family per pixel in one pass (the arithmetic of _array_strokes, value for value).
        tau, left, _ = family_thresholds(theta.size, m_ink)
        strokes = np.empty((h, w), dtype=np.float32)
        _hk.screen_strokes(
            np.ascontiguousarray(gb.normal, dtype=np.float32),
            mask,
            unit_light(light),
            theta.astype(np.float64),
            float(sp),
            -1.0 if cap_w is None else float(cap_w),
            tau,
            left,
            float(m_ink),
            strokes,
        )
    else:
        tone = _tone(gb.normal, light, mask)
        strokes = _array_strokes(gb, tone, space, theta, sp, m_ink, cap_w, scale, k)
    prof = profile_ink(gb, width=pw) if edges else np.zeros((1, 1), np.float32)
    rgb = np.empty((*gb.output_shape, 3), dtype=np.float32)
    # box filter, halo, profiles and colour per output pixel in one pass
    _hk.hatch_compose(
        strokes, k, np.ascontiguousarray(mask), np.ascontiguousarray(prof, dtype=np.float32), edges,
        np.float32(HALO_CORE), ink_c, paper_c, rgb,
    )  # fmt: skip
    return rgb


def _array_strokes(
    gb: GBuffer,
    tone: np.ndarray,
    space: str,
    theta: np.ndarray,
    sp: float,
    m_ink: float,
    cap_w: float | None,
    scale: float | None,
    k: int,
) -> np.ndarray:
    """The stroke ink of :func:`hatch` at buffer size, family by family over flat arrays of
    the pixels each family inks (the uv strokes; in screen space the reference that
    :func:`._hatch_kernels.screen_strokes` is tested against)."""
    mask = np.asarray(gb.mask, dtype=bool)
    h, w = gb.shape
    # Only pixels with some tone can take ink (family f inks where tone > f / N): the strokes
    # are evaluated on those alone, as flat arrays, and the families on shrinking subsets.
    at = np.flatnonzero(tone.reshape(-1) > 0)
    t_at = tone.reshape(-1)[at]
    # Family f inks where tone > tau_f, so pixels sorted by the number of families inking them
    # make each family's pixels a prefix: slices instead of gathers in the loop below.
    lows = family_thresholds(theta.size, m_ink)[0][:-1]
    n_inking = np.ones(t_at.size, dtype=np.uint8)  # all of them have tone > 0
    for lo in lows[1:]:
        n_inking += t_at > lo
    order = np.argsort(np.uint8(theta.size) - n_inking, kind="stable")
    prefix = np.cumsum(np.bincount(n_inking, minlength=theta.size + 1)[::-1])[::-1]
    at, t_at = at[order], t_at[order]
    if space == "screen":
        rows = at // w  # divmod would take several times as long
        cols = at - rows * w
        # x right, y up, in buffer pixels, from the pixel centres
        x = np.arange(w, dtype=np.float32)
        y = np.arange(h - 1, -1, -1, dtype=np.float32)
    else:
        u = np.where(mask, gb.uv[..., 0], np.nan).astype(np.float32)
        v = np.where(mask, gb.uv[..., 1], np.nan).astype(np.float32)
        (ux, uy), (vx, vy) = _robust_gradient(u), _robust_gradient(v)
        if scale is None:
            # median parameter change per pixel over both coordinates -> median spacing `sp`
            g = np.concatenate([np.hypot(ux, uy)[mask], np.hypot(vx, vy)[mask]])
            g = g[g > 0]
            if g.size == 0:
                raise InputError("gb: the texture coordinates do not vary over the surface")
            scale = 1.0 / (sp * float(np.median(g)))
        uv_at = [a.reshape(-1)[at] for a in (u, v, ux, uy, vx, vy)]

    paper_left = np.ones(at.size, dtype=np.float32)
    for f, a in enumerate(theta):
        m = int(prefix[f + 1])  # pixels where family f inks
        if m == 0:
            break
        cover = _family_coverage(t_at[:m], f, theta.size, m_ink)
        if space == "screen":
            # float64, as the stroke coordinate is far from 0 across a large image
            along = (-x * np.sin(a))[cols[:m]]
            along += (y * np.cos(a))[rows[:m]]
            along /= sp
            period = np.float32(sp)
        else:
            along, period = _uv_stroke(*(c[:m] for c in uv_at), a, scale)
        distance = (along - np.round(along)) * period  # to the nearest stroke centre, in pixels
        width = cover * period  # coverage c_f of a family `period` px apart
        if cap_w is not None:
            width = np.minimum(width, np.float32(cap_w) * (period / np.float32(sp)))
        if space == "uv":
            # crowded strokes (a silhouette, a pole of u, v) thin out instead of merging
            width = width * crowding(period, k)
        # families at different angles overlap independently: the union keeps 1 - prod(1 - c)
        paper_left[:m] *= np.float32(1.0) - stroke_ink(distance, width)
    strokes = np.zeros(h * w, dtype=np.float32)
    strokes[at] = np.float32(1.0) - paper_left
    return strokes.reshape(h, w)


register(
    "hatch",
    "pen-and-ink hatching: strokes thickening with the shade, black profiles",
    fronts=("npr", "explore"),
    draw=hatch,
)
