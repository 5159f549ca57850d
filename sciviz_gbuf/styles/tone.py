"""Tone-based NPR styles on a G-buffer, combined with the 2003 edge map.

* :func:`gooch`: the cool-to-warm technical-illustration shading of Gooch et al. (SIGGRAPH
  1998) with white inner edges and black profiles, as in Nienhaus & Döllner (WSCG 2003) §5.1,
  Fig. 7.
* :func:`toon`: the cartoon shading of Lake et al. (NPAR 2000), a 1D shade texture indexed by
  ``max(N.L, 0)`` with nearest lookup, optionally with smoothed colour transitions (the 2003
  "cartoon map", §5, Fig. 9), and the 2003 edge map.

Both shade at the buffer size from the eye-space normals and reduce to the output size
(``gb.output_shape``), so silhouettes against the background are antialiased by coverage.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from ..filters import edge_map, enhance
from . import _tone_kernels as _tk
from .illustration import LIGHT, PAPER, thin_edge_map
from .registry import register

__all__ = [
    "GOOCH_ALPHA",
    "GOOCH_BASE",
    "GOOCH_BETA",
    "GOOCH_COOL",
    "GOOCH_INNER_COLOR",
    "GOOCH_PROFILE_COLOR",
    "GOOCH_WARM",
    "MAX_LEVELS",
    "TOON_BASE",
    "TOON_DARKEST",
    "TOON_INNER_COLOR",
    "TOON_LEVELS",
    "TOON_PROFILE_COLOR",
    "gooch",
    "toon",
    "toon_shades",
]

#: Largest shade texture :func:`toon` accepts (texels): ``LIMITS["shade_levels"]``.
MAX_LEVELS = int(_validate.LIMITS["shade_levels"])


#: :func:`gooch` defaults (Gooch et al. 1998): base colour, warm and cool tones and how much of
#: the base each takes (``alpha`` cool, ``beta`` warm); white inner edges, black profiles.
GOOCH_BASE = (0.75, 0.75, 0.75)
GOOCH_WARM = (0.4, 0.4, 0.0)
GOOCH_COOL = (0.0, 0.0, 0.4)
GOOCH_ALPHA = 0.2
GOOCH_BETA = 0.6
GOOCH_INNER_COLOR = (1.0, 1.0, 1.0)
GOOCH_PROFILE_COLOR = (0.0, 0.0, 0.0)
#: :func:`toon` defaults (Lake et al. 2000): shade levels, base colour, black edges.
TOON_LEVELS = 3
TOON_BASE = (0.9, 0.55, 0.3)
TOON_INNER_COLOR = (0.0, 0.0, 0.0)
TOON_PROFILE_COLOR = (0.0, 0.0, 0.0)
#: The darkest of ``k`` shade levels (``levels=k``), as a fraction of the base colour: light
#: enough that the black lines stay apart from it. With the default base its luminance is
#: 0.24, so even a half-inked pixel of an outline over it (0.12) is lighter than black
#: (< 0.1): outline and band never merge into one black area, as they did with ``1 / k``.
TOON_DARKEST = 0.4


def toon_shades(levels: int) -> np.ndarray:
    """The ``levels`` shades of ``toon(levels=k)``, darkest first: evenly spaced from
    :data:`TOON_DARKEST` to 1 (1 alone for one level). (k,) float64."""
    k = int(levels)
    if k == 1:
        return np.ones(1)
    return TOON_DARKEST + (1.0 - TOON_DARKEST) * np.arange(k, dtype=np.float64) / (k - 1)


def _unit_light(light: object) -> np.ndarray:
    try:
        lv = np.asarray(light, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        lv = np.zeros(0)
    if lv.size != 3 or not np.isfinite(lv).all() or not np.linalg.norm(lv) > 0:
        raise InputError(
            f"light: expected a finite non-zero 3-vector (eye space), got {_validate.brief(light)}"
        )
    return (lv / np.linalg.norm(lv)).astype(np.float32)


def _n_dot_l(gb: GBuffer, light: np.ndarray) -> np.ndarray:
    """``N.L`` at buffer size; 0 on background normals (the caller paints those pixels)."""
    n = np.asarray(gb.normal, dtype=np.float32)
    # Taken on the raw normals: cleaning the NaN of the background first would copy the whole
    # (H, W, 3) buffer. Surface pixels with a NaN component are redone on cleaned normals.
    # Summed as the one-pass kernels sum it (``_tone_kernels``), so both give the same bits.
    ndl = n[..., 0] * light[0]
    ndl += n[..., 1] * light[1]
    ndl += n[..., 2] * light[2]
    bad = np.isnan(ndl)
    np.copyto(ndl, np.float32(0.0), where=bad)
    bad &= np.asarray(gb.mask, dtype=bool)
    if bad.any():
        nb = np.nan_to_num(n[bad], nan=0.0)
        ndl[bad] = nb[:, 0] * light[0] + nb[:, 1] * light[1] + nb[:, 2] * light[2]
    return np.clip(ndl, -1.0, 1.0, out=ndl)


def _finish(gb: GBuffer, rgb: np.ndarray) -> np.ndarray:
    """The box filter to output size of the (H, W, 3) float32 colour, paper already outside
    the mask, so silhouettes blend with the background by coverage. ``rgb`` may be reused."""
    out = rgb if gb.supersample == 1 else gb.downsample(rgb)
    return np.clip(out, 0.0, 1.0, out=out)


def _edges(
    gb: GBuffer,
    rgb: np.ndarray,
    *,
    operator: str,
    crease_angle: float,
    depth_jump: float,
    width: float,
    inner_color: np.ndarray | None,
    profile_color: np.ndarray,
) -> np.ndarray:
    emap = edge_map(
        gb, operator=operator, crease_angle=crease_angle, depth_jump=depth_jump, width=width
    )
    if inner_color is None:
        # No inner edges: only the profiles are drawn.
        emap[..., :3] = 0.0
        inner_color = np.ones(3, dtype=np.float32)
    # Dark lines never fill an area (a bolt hole smaller than its outline): their clumps keep
    # only the skeleton, the inner edges' too when they are drawn dark (toon's black ones).
    emap = thin_edge_map(emap, width, inner_color=inner_color)
    return enhance(rgb, emap, inner_color=inner_color, profile_color=profile_color)


def _gooch_clip(k_warm: np.ndarray, k_cool: np.ndarray) -> bool:
    """Whether the blend needs its clip: with t in [0, 1] and both tones in [0, 1 - 2**-20]
    the float32 blend cannot leave [0, 1] (three roundings add at most 3 * 2**-24)."""
    return max(float(k_warm.max()), float(k_cool.max())) > 1.0 - 2.0**-20


def gooch(
    gb: GBuffer,
    *,
    light: Sequence[float] = LIGHT,
    base: Sequence[float] = GOOCH_BASE,
    warm: Sequence[float] = GOOCH_WARM,
    cool: Sequence[float] = GOOCH_COOL,
    alpha: float = GOOCH_ALPHA,
    beta: float = GOOCH_BETA,
    edges: bool = True,
    operator: str = "diagonal",
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
    inner_color: Sequence[float] = GOOCH_INNER_COLOR,
    profile_color: Sequence[float] = GOOCH_PROFILE_COLOR,
    background: Sequence[float] = PAPER,
) -> np.ndarray:
    """Cool-to-warm technical illustration (Gooch et al. 1998) with the 2003 edge map.

    Per surface pixel, from the eye-space normal ``N`` and the unit light ``L``::

        k_cool = cool + alpha * base
        k_warm = warm + beta * base
        t      = (1 + N.L) / 2
        colour = t * k_warm + (1 - t) * k_cool        (clipped to [0, 1])

    so the hue, not only the brightness, carries the orientation: surfaces facing the light are
    warm, those facing away cool, and the whole range of ``N.L`` in [-1, 1] is used (no black
    unlit side, which keeps black for the profiles). Then, if ``edges``, the edge map of
    Nienhaus & Döllner (2003 §4) is composited with :func:`~sciviz_gbuf.filters.enhance`:
    inner edges in ``inner_color`` (white), profiles in ``profile_color`` (black), as in 2003
    §5.1, Fig. 7.

    Parameters
    ----------
    gb : GBuffer
    light : 3 floats, default: :data:`~sciviz_gbuf.styles.illustration.LIGHT`
        Eye-space direction towards the light (x right, y up, z towards the viewer).
    base, warm, cool : RGB in [0, 1]
        Object colour ``k_d`` and the blue/yellow tones of the paper (``b``, ``y``).
    alpha, beta : float in [0, 1], default: 0.2, 0.6
        How much of the object colour enters the cool and the warm tone.
    edges : bool, default: True
        Composite the 2003 edge map; where its dark lines crowd into a clump thicker than a
        line, only the clump's skeleton is drawn
        (:func:`~sciviz_gbuf.styles.illustration.thin_edge_map`).
    operator, crease_angle, depth_jump, width
        As in :func:`sciviz_gbuf.filters.edge_map` (``width`` in [1, 64] output pixels: at
        most ``LIMITS["line_width"]``).
    inner_color, profile_color : RGB in [0, 1]
        Colours of inner (crease) edges and profiles.
    background : RGB in [0, 1], default: white
        Paper colour, blended with the surface at the silhouette by coverage.

    Returns
    -------
    (H, W, 3) float32 RGB in [0, 1] at ``gb.output_shape``.
    """
    gb = check_gbuffer(gb)
    lv = _unit_light(light)
    base_c, warm_c, cool_c = (
        _validate.rgb(base, "base"),
        _validate.rgb(warm, "warm"),
        _validate.rgb(cool, "cool"),
    )
    a = np.float32(_validate.unit_interval(alpha, "alpha"))
    b = np.float32(_validate.unit_interval(beta, "beta"))
    inner_c, prof_c = (
        _validate.rgb(inner_color, "inner_color"),
        _validate.rgb(profile_color, "profile_color"),
    )
    bg = _validate.rgb(background, "background")
    edges = _validate.boolean(edges, "edges")
    if edges:  # before any image is made (edge_map checks the rest)
        _validate.size(width, "width", "line_width", low=1.0, closed=True)

    k_cool = cool_c + a * base_c
    k_warm = warm_c + b * base_c
    # The shade per buffer pixel and its box filter to output size in one pass.
    rgb = np.empty((*gb.output_shape, 3), dtype=np.float32)
    _tk.gooch_shade(
        np.ascontiguousarray(gb.normal, dtype=np.float32),
        np.ascontiguousarray(gb.mask, dtype=np.bool_),
        lv,
        k_warm.astype(np.float32),
        k_cool.astype(np.float32),
        bg,
        _gooch_clip(k_warm, k_cool),
        _validate.count(gb.supersample, "gb.supersample", "supersample"),
        rgb,
    )
    if not edges:
        return rgb
    return _edges(
        gb,
        rgb,
        operator=operator,
        crease_angle=crease_angle,
        depth_jump=depth_jump,
        width=width,
        inner_color=inner_c,
        profile_color=prof_c,
    )


def _shade_table(levels: object, base: np.ndarray) -> np.ndarray:
    """The 1D shade texture as an (n, 3) float32 colour table, darkest texel first."""
    expected = (
        f"an int in [1, {MAX_LEVELS}], a sequence of 1..{MAX_LEVELS} shades in [0, 1] or an "
        f"(n, 3) table of RGB colours in [0, 1]"
    )
    if isinstance(levels, (bool, np.bool_)):
        raise InputError(f"levels: expected {expected}, got {_validate.brief(levels)}")
    if isinstance(levels, (int, np.integer)):
        k = int(levels)
        if not 1 <= k <= MAX_LEVELS:
            raise InputError(f"levels: expected {expected}, got {_validate.brief(levels)}")
        # k shades evenly spaced from TOON_DARKEST (not black) to 1 (the full base colour)
        return (toon_shades(k)[:, None] * base[None, :]).astype(np.float32)
    try:
        arr = np.asarray(levels, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        arr = np.zeros((0,))
    ok_range = arr.size > 0 and bool(np.all((arr >= 0.0) & (arr <= 1.0)))
    if arr.ndim == 1 and 1 <= arr.size <= MAX_LEVELS and ok_range:
        return (arr[:, None] * base[None, :]).astype(np.float32)
    if arr.ndim == 2 and arr.shape[1] == 3 and 1 <= arr.shape[0] <= MAX_LEVELS and ok_range:
        return arr.astype(np.float32)
    raise InputError(f"levels: expected {expected}, got {_validate.brief(levels)}")


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _toon_colour(
    gb: GBuffer, lv: np.ndarray, table: np.ndarray, sm: float, bg: np.ndarray
) -> np.ndarray:
    """The toon colour at buffer size, paper off the mask (see :func:`toon`).

    The paper is one more texel, looked up where there is no surface, so a single gather of
    whole texels makes the image. The texels are in [0, 1] already (``_shade_table``), so only
    pixels on a smoothed transition need the clip.
    """
    n = table.shape[0]
    s = np.maximum(_n_dot_l(gb, lv), np.float32(0.0))
    idx = (s * np.float32(n)).astype(np.intp)
    np.minimum(idx, n - 1, out=idx)
    mask = np.asarray(gb.mask, dtype=bool)
    ramps = None if sm == 0.0 or n == 1 else _toon_ramps(s, idx, mask, table, sm)
    np.copyto(idx, n, where=~mask)
    colour = np.take(np.vstack([table, bg[None, :]]), idx, axis=0)
    if ramps is not None:
        at, fixed = ramps
        colour.reshape(-1, 3)[at] = fixed
    return colour


def _toon_ramps(
    s: np.ndarray, idx: np.ndarray, mask: np.ndarray, table: np.ndarray, sm: float
) -> tuple[np.ndarray, np.ndarray]:
    """Flat indices of the surface pixels on a smoothed transition, and their clipped colours.

    The sum over thresholds ``j`` of ``d_j (smoothstep - step)`` where ``|s - j / n| < sm / 2``
    is taken in increasing ``j``, in float32, as a loop over all thresholds on the whole image
    would, but only on pixels near a threshold and only over the thresholds near each: a pixel
    sees those within ``sm / 2 * n`` texels of its nearest one.
    """
    n = table.shape[0]
    half = np.float32(0.5 * sm)
    taus = np.array([np.float32(j / n) for j in range(n)], dtype=np.float32)
    lows = taus - half  # the ramp's start, as ``tau - half`` per threshold
    steps = table[1:] - table[:-1]  # d_j = table[j] - table[j - 1] at steps[j - 1]
    # Candidates: the nearest threshold closer than sm / 2, with a margin far above float32
    # round-off, so that no pixel the exact test below accepts is left out.
    near_j = np.clip(np.rint(s * np.float32(n)), 1, n - 1)
    near_j *= np.float32(1.0 / n)
    near_j -= s
    cand = np.abs(near_j, out=near_j) < half + np.float32(1e-4)
    cand &= mask
    at = np.flatnonzero(cand)
    sc = s.reshape(-1)[at]
    ic = idx.reshape(-1)[at]
    colour = table[ic]
    centre = np.clip(np.rint(sc * np.float32(n)).astype(np.intp), 1, n - 1)
    reach = min(int(np.ceil(float(half) * n)) + 1, n)
    for o in range(-reach, reach + 1):  # increasing j for every pixel
        j = centre + o
        ok = (j >= 1) & (j <= n - 1)
        jj = np.where(ok, j, 1)
        ok &= np.abs(sc - taus[jj]) < half
        sel = np.flatnonzero(ok)
        if sel.size == 0:
            continue
        js = jj[sel]
        # the step is taken from the lookup itself, so both agree exactly at the threshold
        ramp = _smoothstep((sc[sel] - lows[js]) / np.float32(sm)) - (ic[sel] >= js)
        colour[sel] += ramp[:, None].astype(np.float32) * steps[js - 1]
    np.clip(colour, 0.0, 1.0, out=colour)
    return at, colour


def toon(
    gb: GBuffer,
    *,
    light: Sequence[float] = LIGHT,
    levels: int | Sequence[float] | Sequence[Sequence[float]] = TOON_LEVELS,
    base: Sequence[float] = TOON_BASE,
    smooth: float = 0.0,
    edges: bool = True,
    operator: str = "diagonal",
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
    inner_color: Sequence[float] | None = TOON_INNER_COLOR,
    profile_color: Sequence[float] = TOON_PROFILE_COLOR,
    background: Sequence[float] = PAPER,
) -> np.ndarray:
    """Cartoon shading (Lake et al. 2000) with the 2003 edge map (Nienhaus & Döllner 2003 §5).

    A 1D shade texture of ``n`` texels is indexed by ``s = max(N.L, 0)`` with nearest lookup,
    texel ``i = min(floor(n s), n - 1)``: the surface falls into ``n`` flat colour patches,
    darker away from the light, with hard transitions at ``s = j / n`` (j = 1 .. n-1).

    ``smooth > 0`` is the 2003 "cartoon map" variant (Fig. 9: "sampling neighbouring colour
    values smoothes colour transition"), done analytically in the texture coordinate instead of
    by resampling the image: across each threshold ``j / n`` the colour ramps from texel
    ``j - 1`` to texel ``j`` with a smoothstep over ``|s - j / n| < smooth / 2``. The width is
    therefore in units of ``N.L`` (not pixels): on screen the ramp is wide where ``N.L``
    changes slowly and narrow near silhouettes. Outside the ramps the colours are exactly the
    texels, and with a monotone texture the result stays monotone in ``N.L``. With
    ``supersample > 1`` the transitions are in addition box-filtered by the downsampling.

    Parameters
    ----------
    gb : GBuffer
    light : 3 floats, default: :data:`~sciviz_gbuf.styles.illustration.LIGHT`
        Eye-space direction towards the light.
    levels : int, sequence of floats or (n, 3) array, default: 3
        The shade texture. An int ``k``: ``k`` shades evenly spaced from :data:`TOON_DARKEST`
        = 0.4 to 1, times ``base`` (:func:`toon_shades`; the darkest band is not black, so
        the black outline stays apart from it). A sequence
        of shades in [0, 1] (darkest first, for ``s`` from 0 to 1): multiplied by ``base``. An
        (n, 3) table: RGB colours in [0, 1] used as they are (``base`` is ignored). At most
        :data:`MAX_LEVELS` = ``LIMITS["shade_levels"]`` = 256 texels.
    base : RGB in [0, 1], default: orange
        Fully lit material colour.
    smooth : float in [0, 1], default: 0
        Width, in units of ``N.L``, of the smoothed transitions; 0 keeps them hard.
    edges : bool, default: True
        Composite the 2003 edge map; where its dark lines crowd into a clump thicker than a
        line, only the clump's skeleton is drawn
        (:func:`~sciviz_gbuf.styles.illustration.thin_edge_map`).
    operator, crease_angle, depth_jump, width
        As in :func:`sciviz_gbuf.filters.edge_map` (``width`` in [1, 64] output pixels: at
        most ``LIMITS["line_width"]``).
    inner_color : RGB in [0, 1] or None, default: black
        Colour of inner (crease) edges; None draws no inner edges.
    profile_color : RGB in [0, 1], default: black
    background : RGB in [0, 1], default: white

    Returns
    -------
    (H, W, 3) float32 RGB in [0, 1] at ``gb.output_shape``.
    """
    gb = check_gbuffer(gb)
    lv = _unit_light(light)
    table = _shade_table(levels, _validate.rgb(base, "base"))
    try:
        sm = float(smooth)
    except (TypeError, ValueError):
        sm = float("nan")
    if isinstance(smooth, bool) or not 0.0 <= sm <= 1.0:
        raise InputError(
            f"smooth: expected a width in units of N.L in [0, 1], got {_validate.brief(smooth)}"
        )
    inner_c = None if inner_color is None else _validate.rgb(inner_color, "inner_color")
    prof_c = _validate.rgb(profile_color, "profile_color")
    bg = _validate.rgb(background, "background")
    edges = _validate.boolean(edges, "edges")
    if edges:  # before any image is made (edge_map checks the rest)
        _validate.size(width, "width", "line_width", low=1.0, closed=True)

    if sm == 0.0 or table.shape[0] == 1:
        # Flat shade levels: texel per buffer pixel and box filter in one pass.
        rgb = np.empty((*gb.output_shape, 3), dtype=np.float32)
        _tk.toon_shade(
            np.ascontiguousarray(gb.normal, dtype=np.float32),
            np.ascontiguousarray(gb.mask, dtype=np.bool_),
            lv,
            np.ascontiguousarray(table, dtype=np.float32),
            bg,
            _validate.count(gb.supersample, "gb.supersample", "supersample"),
            rgb,
        )
    else:
        rgb = _finish(gb, _toon_colour(gb, lv, table, sm, bg))
    if not edges:
        return rgb
    return _edges(
        gb,
        rgb,
        operator=operator,
        crease_angle=crease_angle,
        depth_jump=depth_jump,
        width=width,
        inner_color=inner_c,
        profile_color=prof_c,
    )


register(
    "gooch",
    "technical illustration: warm-cool shading, white inner edges, black profiles",
    fronts=("npr", "explore"),
    draw=gooch,
)
register(
    "toon",
    "cartoon shading: a few flat shade levels and black profiles",
    fronts=("npr", "explore"),
    draw=toon,
)
