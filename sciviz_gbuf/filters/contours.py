"""Contour lines and curved hatching as image operations (Saito & Takahashi 1990 §3.3-3.4).

No line is traced: every pixel looks at its own value ``s`` and the gradient ``g`` of the
field there (Eq. 9, in field units per pixel), so ``t = |s - p| / g`` is its distance in pixels
to the level set ``s = p``, and a line profile ``f1(t)`` (Eq. 7-8, Fig. 4) turns that distance
into ink. Lines come out antialiased, of a width ``d`` in pixels whatever the gradient, around
saddles and singular points as anywhere else, and the work per pixel is constant.

Where the gradient vanishes the contours of real data are unsteady; below ``g_eps`` the ink
fades to ``c_sparse`` (Eq. 10-11). Where lines crowd closer than they are wide, the ink fades
to ``c_dense`` (Eq. 15): black keeps a dense region dark, white thins the lines out, which is
how minor contours give way to major ones on a topographic map (Fig. 11). Curved hatching
(Eq. 17-21) instead chooses the interval per pixel so lines keep a constant on-screen spacing.

Masked pixels, and pixels whose value is NaN or inf, get no ink; their neighbours see them
through the border rule of :mod:`.operators` (linear extrapolation), so a hole neither draws
nor hides a line around it.

References
----------
T. Saito, T. Takahashi, "Comprehensible Rendering of 3-D Shapes", SIGGRAPH 1990, §3.3-3.4.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from . import _contour_generalize as _gen
from . import _contour_kernels as _p
from . import _stencil_kernels as _stencil

__all__ = [
    "band_heights",
    "contour_halo",
    "contour_line_parameters",
    "contour_lines",
    "generalized_field",
    "hatching",
    "modulated_hatching",
]

# f1 per profile: the width W of its ramp (px) and P(v) = v (p1 + v (p2 + v p3)) along it: a
# step; a linear ramp one pixel wide, the exact area coverage of a pixel by a straight line;
# and a smoothstep over 1.5 px.
_PROFILES = {
    "bilevel": (1e-6, (1.0, 0.0, 0.0)),
    "linear": (1.0, (1.0, 0.0, 0.0)),
    "smooth": (1.5, (0.0, 3.0, -2.0)),
}
PROFILES = tuple(_PROFILES)
#: Cells read around each output cell (the 3x3 operator), for chunked evaluation.
RADIUS = 1
#: Cells the generalisation's smoothing reads around each cell (``generalize=True``).
SMOOTH_RADIUS = _gen.SMOOTH_RADIUS
#: Default ``min_ring`` of ``generalize=True``, in widths of the widest line.
MIN_RING_WIDTHS = 3.0
# Default g_eps: lines more than this many pixels apart count as lying in a flat region.
FLAT_SPACING = 1000.0


def _unit(value, name: str) -> float:
    return _validate.unit_interval(value, name)


def _line_shape(d: float, ramp: float) -> tuple[float, float]:
    """``a`` and ``cap`` of the f1 profile for width ``d``: the ramp is centred on the line's
    edge; a line thinner than the ramp is drawn ramp-wide at ``d / ramp`` of full ink, so the
    ink across any line is ``d``."""
    if d >= ramp:
        return (d / 2 + ramp / 2) / ramp, 1.0
    return 1.0, d / ramp


def _params(width: float, profile: str) -> np.ndarray:
    d = _validate.size(width, "width", "line_width", buffer=True)
    profile = _validate.choice(profile, "profile", PROFILES)
    ramp, poly = _PROFILES[profile]
    prm = np.zeros(_p.NPRM, dtype=np.float64)
    prm[_p.LINE_A], prm[_p.LINE_CAP] = _line_shape(d, ramp)
    prm[_p.LINE_B] = 1 / ramp
    prm[[_p.P1, _p.P2, _p.P3]] = poly
    prm[_p.INV_D] = 1 / d
    prm[_p.DENSE_AT] = -1e30
    return prm


def _prepare(field, mask, gradient) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    s = _validate.image(field, "field")
    m = _validate.mask(mask, s.shape)
    if gradient is None:
        return s, m, None
    g = np.asarray(gradient)
    if g.shape != s.shape:
        raise InputError(f"gradient: expected shape {s.shape} (like field), got {g.shape}")
    return s, m, _validate.image(g, "gradient")


def _run(code: str, s, m, g, prm: np.ndarray) -> np.ndarray:
    return _stencil.run(code, s, m, k=0.0 if g is None else 1.0, aux=g, prm=prm.astype(np.float32))


def contour_lines(
    field: np.ndarray,
    *,
    interval: float | None = None,
    levels: Sequence[float] | np.ndarray | None = None,
    base: float = 0.0,
    width: float = 1.0,
    mask: np.ndarray | None = None,
    profile: str = "linear",
    g_eps: float | None = None,
    c_sparse: float = 0.0,
    c_dense: float | None = None,
    dense_spacing: float | None = None,
    major_interval: float | None = None,
    major_width: float | None = None,
    gradient: np.ndarray | None = None,
    generalize: bool = False,
    min_ring: float | None = None,
) -> np.ndarray:
    """Contour lines of a scalar image without line tracking (1990 Eq. 7-15).

    Each pixel gets the ink of the line profile ``f1(|s - p_k| / g)`` for its nearest levels,
    where ``g`` is the Eq. 9 gradient, then the flat-region and dense-region blends ``f_g``.
    A level is drawn only where the field reaches it: within the range of the pixel's 3x3
    neighbourhood (widened by how far a wide line reaches beyond one pixel), so a summit just
    below a level gets no line on its top; as in GDAL, a value equal to a level counts as
    above it. The lines then lie within 1 px of ``gdal_contour``'s (tested).

    Parameters
    ----------
    field : (H, W) array
        Any scalar image: height ``wz``, depth, a CT coordinate, a reflection angle, ``u``...
        NaN and inf are treated as masked (DEM nodata).
    interval : float > 0, optional
        ``q`` of Eq. 12: lines at ``base + n * interval`` for every integer ``n``.
    levels : sequence of float, optional
        Explicit level values ``p`` (Eq. 7), instead of ``interval``; one of the two is needed.
        At most ``LIMITS["levels"]`` = 100000 values.
    base : float, default: 0
        ``p0`` of Eq. 12.
    width : float in (0, 512], default: 1
        Line width ``d`` in pixels, honoured wherever lines are further apart than that; at
        most ``LIMITS["line_width"] * LIMITS["supersample"]`` = 512 (the field may be a
        supersampled G-buffer channel: 64 output pixels at supersample 8).
    mask : (H, W) bool, optional
        Coverage; masked pixels get no ink.
    profile : {"linear", "smooth", "bilevel"}
        ``f1``: the exact coverage of a pixel by a line of width ``d`` (Fig. 4b, the
        default), a smoother higher-order profile (Fig. 4c) or the aliased step of Eq. 8.
        Each one puts ``d`` pixels of ink across a straight line.
    g_eps : float >= 0, optional
        Eq. 11: where ``g < g_eps`` the ink fades linearly to ``c_sparse``. Default:
        ``interval / 1000`` (lines more than 1000 px apart are unsteady) or, for explicit
        levels, the smallest gap between them / 1000; 0 for a single level. Exactly flat
        pixels (``g = 0``) always get ``c_sparse``.
    c_sparse : float in [0, 1], default: 0
        Ink of flat regions.
    c_dense : float in [0, 1], optional
        Eq. 15: ink of regions where lines crowd: 1 keeps them dark, 0 thins them out to the
        background, 0.5 gives a grey tone (Fig. 5). Default: no dense handling (crowded lines
        merge into solid ink), or 0 for the minor lines when ``major_interval`` is given.
    dense_spacing : float in (0, 8192], optional
        On-screen spacing (px) below which lines start to fade to ``c_dense``; they reach it
        one line width closer. Default ``2 * width``: lines are gone where they would touch.
        ``dense_spacing=width`` is Eq. 15 exactly. At most
        ``LIMITS["spacing"] * LIMITS["supersample"]`` = 8192.
    major_interval : float > 0, optional
        A second, major family of lines at ``base + n * major_interval`` (Fig. 11, e.g. 20 m
        majors over 5 m minors); majors never thin out. Needs ``interval``.
    major_width : float in (0, 512], optional
        Width of the major lines; default ``2 * width``. At most
        ``LIMITS["line_width"] * LIMITS["supersample"]`` = 512, as ``width``.
    gradient : (H, W) array, optional
        Your own gradient magnitude of ``field`` in field units per pixel, instead of Eq. 9.
        Not with ``generalize=True`` (the lines are then of the smoothed field).
    generalize : bool, default: False
        Cartographic generalisation, as on a printed map (the maps of
        :mod:`sciviz_gbuf.recipes` turn it on). False: the exact lines of the field, within
        1 px of ``gdal_contour``'s. True: (1) the field is smoothed first by a Gaussian whose
        width follows the local line spacing ``s = q / g`` (``q`` the interval, or the smallest
        gap between ``levels``; ``g`` the gradient of the field smoothed at 1 px):
        ``sigma = clip(0.25 (s - 3), 0, 4)`` px, so where lines are at most 3 px apart
        nothing moves, where they are 7 px apart sigma is 1 px, and on flat ground (integer
        metres, noise) the level is averaged over up to 4 px instead of wandering; but each
        smoothed value stays within the heights the exact surface takes within 0.6 px of the
        cell (a tolerance band), so no line moves more than 0.6 px from the exact one and
        the lines stay within 1 px of ``gdal_contour``'s wherever they are more than 2 px
        apart (tested). The fit is a local plane over the valid cells, so nodata holes and
        the grid edge bend no line.
        Line widths and the crowding fade (Eq. 15) follow the gradient of that fit at least
        1 px wide, so noise does not make minors flicker into dashes. (2) Rings and specks
        whose 8-connected ink fits in ``min_ring`` px are removed at every ink level (line
        ends that touch nodata or the grid's edge are not rings: they stay unless they fit in
        ``min_ring / 3`` px, one line width): each pixel keeps its ink only up to the highest
        level ``T`` at which its component of ``ink >= T`` is larger (an attribute opening).
        At the lowest ink that is hysteresis, so a line that fades where the level is noisy
        or where minors crowd (Eq. 15) stays one line; at the higher levels its short darker
        stretches are lowered to the ink of the piece, so no threshold shows it as dashes,
        and specks go whatever their ink. On steep ground
        (lines <= 4 px apart) the lines move < 0.25 px; they stay within 1 px of
        ``gdal_contour``'s where lines are at most 8 px apart (tested).
    min_ring : float >= 0, optional
        With ``generalize=True``: the largest ring or speck removed, as the longer side of
        its bounding box in pixels; 0 keeps every ring. Default ``3`` line widths (of the
        widest line: ``major_width`` when majors are drawn). At most
        ``LIMITS["line_width"] * LIMITS["supersample"]`` = 512.

    Returns
    -------
    (H, W) float32 ink in [0, 1]; 0 where masked or not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from sciviz_gbuf.filters import contour_lines
    >>> y, x = np.mgrid[-1:1:256j, -1:1:256j]
    >>> ink = contour_lines(x * y, interval=0.05, width=1.5, c_dense=1.0)
    >>> ink.shape, ink.dtype
    ((256, 256), dtype('float32'))
    """
    if (interval is None) == (levels is None):
        raise InputError("contour_lines: give exactly one of interval= or levels=")
    # Every parameter is checked before the field is touched (or a dask graph is built).
    code, prm = _contour_params(
        interval, levels, base, width, profile, g_eps, c_sparse, c_dense, dense_spacing,
        major_interval, major_width,
    )  # fmt: skip
    ring = _ring(generalize, min_ring, gradient, prm)
    if _chunks.any_dask(field, mask, gradient):
        return _chunks.map_stencil(
            contour_lines,
            {"field": field, "mask": mask, "gradient": gradient},
            halo=_halo(ring),
            interval=interval,
            levels=levels,
            base=base,
            width=width,
            profile=profile,
            g_eps=g_eps,
            c_sparse=c_sparse,
            c_dense=c_dense,
            dense_spacing=dense_spacing,
            major_interval=major_interval,
            major_width=major_width,
            generalize=generalize,
            min_ring=min_ring,
        )
    s, m, g = _prepare(field, mask, gradient)
    if ring is None:
        return _run(code, s, m, g, prm)
    valid = np.isfinite(s) if m is None else np.isfinite(s) & m
    s, g = _gen.smooth_field(s, valid, float(prm[_p.GAP]))
    ink = _run(code, s, m, g, prm)
    return _gen.drop_small_rings(ink, ring, valid, ring / MIN_RING_WIDTHS)


def generalized_field(
    field: np.ndarray, *, interval: float, mask: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The smoothed field whose level lines ``contour_lines(field, interval=interval,
    generalize=True)`` draws, and its gradient magnitude (field units per pixel, of the local
    fit at least 1 px wide, as the lines' widths and crowding use it): for vector lines that
    are the drawn ones (:func:`~sciviz_gbuf.filters.contour_polylines` of the first).

    Returns
    -------
    (smoothed, gradient) : two (H, W) float32 arrays, NaN where masked or not finite.
    """
    s, m, _ = _prepare(field, mask, None)
    q = _validate.positive(interval, "interval")
    valid = np.isfinite(s) if m is None else np.isfinite(s) & m
    smooth, grad = _gen.smooth_field(s, valid, float(q))
    smooth = np.where(valid, smooth, np.float32(np.nan)).astype(np.float32)
    return smooth, np.where(valid, grad, np.float32(np.nan)).astype(np.float32)


def _ring(generalize, min_ring, gradient, prm: np.ndarray) -> float | None:
    """The checked ``min_ring`` of a generalised call (its default from the widths), or None
    without generalisation."""
    if not _validate.boolean(generalize, "generalize"):
        if min_ring is not None:
            raise InputError("min_ring: only used with generalize=True")
        return None
    if gradient is not None:
        raise InputError("gradient: not used with generalize=True (the field is smoothed)")
    if min_ring is None:
        widest = 1 / prm[_p.INV_D]
        if prm[_p.MAJOR_Q] > 0:
            widest = max(widest, prm[_p.MAJOR_WIDTH])
        return MIN_RING_WIDTHS * float(widest)
    return _validate.size(min_ring, "min_ring", "line_width", closed=True, buffer=True)


def band_heights(
    field: np.ndarray,
    *,
    band_interval: float | None = None,
    band_levels: Sequence[float] | np.ndarray | None = None,
    base: float = 0.0,
    mask: np.ndarray | None = None,
    min_ring: float = 3.0 * MIN_RING_WIDTHS,
) -> np.ndarray:
    """Heights for colour bands (hypsometric tints) that agree with the lines of
    ``contour_lines(field, generalize=True)``: every band island whose ink ring those lines
    drop (an 8-connected piece of one band, at most ``min_ring`` px on its longer side, away
    from the grid's edge and nodata) takes the height of the nearest cell around it, so no
    speck of a band's colour is left where a ring was removed. The other cells keep their
    heights: their band edges are the exact lines, which the generalised lines follow within
    0.6 px (their tolerance band), under the width of a line.

    Parameters
    ----------
    field : (H, W) array (numpy or dask)
    band_interval, band_levels
        The bands: every ``band_interval`` from ``base``, or between the sorted ``band_levels``
        (exactly one of them). A height equal to an edge is in the band above it.
    base : float, default: 0
    mask : (H, W) bool array, optional
        False cells are nodata (NaN in the result).
    min_ring : float, default: 9
        The largest island filled (px): that of the lines, 3 widths of the widest line (a map
        with 1 px minors and 2 px majors: 6 px).

    Returns
    -------
    (H, W) float32, NaN at nodata. Chunked (dask) input: the same cells, chunk by chunk.
    """
    if (band_interval is None) == (band_levels is None):
        raise InputError("band_heights: give exactly one of band_interval= or band_levels=")
    if band_interval is not None:
        spec = {
            "step": _validate.positive(band_interval, "band_interval"),
            "base": _validate.finite(base, "base"),
        }
    else:
        spec = {"edges": _validate.levels(band_levels, "band_levels", limit="bands")}
    ring = _validate.size(min_ring, "min_ring", "line_width", closed=True, buffer=True)
    if _chunks.any_dask(field, mask):
        return _chunks.map_stencil(
            band_heights,
            {"field": field, "mask": mask},
            halo=2 * (int(np.ceil(ring)) + 1),
            band_interval=band_interval,
            band_levels=band_levels,
            base=base,
            min_ring=ring,
        )
    s, m, _ = _prepare(field, mask, None)
    valid = np.isfinite(s) if m is None else np.isfinite(s) & m
    return _gen.band_heights(s, valid, ring, **spec)


def _halo(ring: float | None) -> int:
    """Chunk halo of :func:`contour_lines`: its 3x3 stencil, plus with generalisation the
    smoothing's reach and the largest ring removed (decided within ``min_ring`` cells)."""
    if ring is None:
        return RADIUS
    return RADIUS + SMOOTH_RADIUS + int(np.ceil(ring))


def contour_halo(*, generalize: bool = False, min_ring: float | None = None, **options) -> int:
    """The halo (cells) that chunked evaluation of :func:`contour_lines` with these keyword
    arguments needs: 1 for exact lines, ``1 + SMOOTH_RADIUS + ceil(min_ring)`` generalised
    (the options are checked as by :func:`contour_lines`)."""
    interval, levels = options.pop("interval", None), options.pop("levels", None)
    if (interval is None) == (levels is None):
        raise InputError("contour_lines: give exactly one of interval= or levels=")
    args = {"base": 0.0, "width": 1.0, "profile": "linear", "g_eps": None, "c_sparse": 0.0,
            "c_dense": None, "dense_spacing": None, "major_interval": None,
            "major_width": None}  # fmt: skip
    unknown = set(options) - set(args)
    if unknown:
        raise InputError(f"contour_halo: unknown options {sorted(unknown)}")
    args.update(options)
    _, prm = _contour_params(interval, levels, **args)
    return _halo(_ring(generalize, min_ring, None, prm))


#: The per-pixel parameters of regular contour lines by name (the kernel's ``prm`` slots).
_NAMED_SLOTS = {
    "base": _p.BASE,
    "q": _p.Q,
    "line_a": _p.LINE_A,
    "line_cap": _p.LINE_CAP,
    "line_b": _p.LINE_B,
    "p1": _p.P1,
    "p2": _p.P2,
    "p3": _p.P3,
    "inv_geps": _p.INV_GEPS,
    "c_sparse": _p.C_SPARSE,
    "c_dense": _p.C_DENSE,
    "dense_at": _p.DENSE_AT,
    "inv_d": _p.INV_D,
    "major_q": _p.MAJOR_Q,
    "major_a": _p.MAJOR_A,
    "major_cap": _p.MAJOR_CAP,
}


def contour_line_parameters(
    *,
    interval: float,
    base: float = 0.0,
    width: float = 1.0,
    profile: str = "linear",
    g_eps: float | None = None,
    c_sparse: float = 0.0,
    c_dense: float | None = None,
    dense_spacing: float | None = None,
    major_interval: float | None = None,
    major_width: float | None = None,
) -> dict[str, float]:
    """The checked per-pixel parameters of :func:`contour_lines` with regular levels, by name:
    what its kernel evaluates Eq. 7-15 with, for a renderer that evaluates them elsewhere
    (the live overlay's fragment shader, :mod:`sciviz_gbuf.live.contours`), so both draw
    the same lines from the same numbers.

    The arguments are those of :func:`contour_lines` (same checks, same errors). The line
    profile at ``t`` px from a line's centre is ``cap P(clip(a - b t, 0, 1))`` with
    ``P(v) = v (p1 + v (p2 + v p3))``; ``dense_at`` is ``-1e30`` without dense handling,
    ``major_q`` 0 without majors, ``inv_geps`` ``1e30`` for ``g_eps = 0``.
    """
    _, prm = _contour_params(
        interval, None, base, width, profile, g_eps, c_sparse, c_dense, dense_spacing,
        major_interval, major_width,
    )  # fmt: skip
    prm32 = prm.astype(np.float32)  # as the kernel reads them
    return {name: float(prm32[i]) for name, i in _NAMED_SLOTS.items()}


_F32_MAX = float(np.finfo(np.float32).max)


def _f32(value: float, name: str) -> float:
    """``value`` if float32 holds it: the kernels and shaders compare heights in float32, where
    a larger base or interval would become inf and draw nothing without a word."""
    if abs(value) > _F32_MAX:
        raise InputError(
            f"{name}: expected a magnitude below {_F32_MAX:.3g} (float32), got {value:g}"
        )
    return value


def _contour_params(
    interval, levels, base, width, profile, g_eps, c_sparse, c_dense, dense_spacing,
    major_interval, major_width,
) -> tuple[str, np.ndarray]:  # fmt: skip
    """The checked parameters of :func:`contour_lines`: the kernel's code and ``prm``."""
    prm = _params(width, profile)
    d = 1 / prm[_p.INV_D]
    prm[_p.BASE] = _f32(_validate.finite(base, "base"), "base")
    prm[_p.C_SPARSE] = _unit(c_sparse, "c_sparse")
    if major_interval is not None and interval is None:
        raise InputError("major_interval: needs interval= (regular minor levels)")
    if major_interval is not None and c_dense is None:
        c_dense = 0.0
    if c_dense is not None:
        prm[_p.C_DENSE] = _unit(c_dense, "c_dense")
        dense = (
            2 * d
            if dense_spacing is None
            else _validate.size(dense_spacing, "dense_spacing", "spacing", buffer=True)
        )
        prm[_p.DENSE_AT] = dense
    elif dense_spacing is not None:
        raise InputError("dense_spacing: only used with c_dense= (or major_interval=)")

    if interval is not None:
        q = _f32(_validate.positive(interval, "interval"), "interval")
        prm[_p.Q] = q
        gap = q
        if major_interval is not None:
            prm[_p.MAJOR_Q] = _f32(
                _validate.positive(major_interval, "major_interval"), "major_interval"
            )
            mw = (
                2 * d
                if major_width is None
                else _validate.size(major_width, "major_width", "line_width", buffer=True)
            )
            prm[_p.MAJOR_A], prm[_p.MAJOR_CAP] = _line_shape(mw, _PROFILES[profile][0])
            prm[_p.MAJOR_WIDTH] = mw
        elif major_width is not None:
            raise InputError("major_width: only used with major_interval=")
        code = "contour"
    else:
        if major_interval is not None or major_width is not None:
            raise InputError("major_interval/major_width: need interval=, not levels=")
        # the kernel compares in float32: levels that round together are one level
        lv = np.unique(_validate.levels(levels).astype(np.float32)).astype(np.float64)
        gap = float(np.min(np.diff(lv))) if lv.size > 1 else 0.0
        prm = np.concatenate([prm, lv])
        code = "levels"
    eps = gap / FLAT_SPACING if g_eps is None else _validate.finite(g_eps, "g_eps")
    if not (np.isfinite(eps) and eps >= 0):
        raise InputError(f"g_eps: expected a finite number >= 0, got {g_eps!r}")
    prm[_p.INV_GEPS] = 1 / eps if eps > 0 else 1e30
    prm[_p.GAP] = gap
    return code, prm


def hatching(
    field: np.ndarray,
    *,
    spacing: float = 8.0,
    width: float = 1.0,
    mask: np.ndarray | None = None,
    interval: float = 1.0,
    base: float = 0.0,
    profile: str = "linear",
    transition: float = 0.04,
    gradient: np.ndarray | None = None,
) -> np.ndarray:
    """Curved hatching: lines of a scalar field at a constant on-screen spacing (Eq. 17-21).

    Binary thinning out: at each pixel the interval ``p_n = 2^n p_d`` is the one whose lines
    lie between ``spacing`` and ``2 * spacing`` pixels apart (Eq. 19-20); the lines halfway
    between them are added as that spacing grows (Eq. 18). Lines are removed where they would
    crowd and added where they spread, continuously, so hatching follows e.g. the ``u`` or
    ``v`` lines of a surface, latitudes of a sphere, or parallel sections, at an even density.

    Parameters
    ----------
    field : (H, W) array
        The scalar field whose level lines are the hatch lines (NaN/inf: masked).
    spacing : float in (0, 8192], default: 8
        ``d_i``: the on-screen spacing in pixels to keep; it stays within +-35%. At most
        ``LIMITS["spacing"] * LIMITS["supersample"]`` = 8192 (pixels of the field, which may
        be a supersampled G-buffer channel).
    width : float in (0, 512], default: 1
        Line width ``d`` in pixels; keep it well below ``spacing``. At most
        ``LIMITS["line_width"] * LIMITS["supersample"]`` = 512.
    mask : (H, W) bool, optional
    interval : float > 0, default: 1
        ``p_d``, the standard interval: lines are drawn at ``base + k * 2^n * interval``.
    base : float, default: 0
        Offset of the line family.
    profile : {"linear", "smooth", "bilevel"}
        Line profile ``f1``, as in :func:`contour_lines`.
    transition : float in (0, 1], default: 0.04
        Over what fraction of a doubling of the spacing the in-between lines fade in. The
        default switches them on crisply around 4/3 of ``d_i``, which keeps every visible
        spacing within +-35% of ``d_i`` whatever threshold counts a line as visible. 1 is
        Eq. 18 exactly: a linear fade that keeps the mean ink density constant but leaves
        faint lines where the spacing is up to 1.5 ``d_i``.
    gradient : (H, W) array, optional
        Your own gradient magnitude of ``field`` in field units per pixel, instead of Eq. 9.

    Returns
    -------
    (H, W) float32 ink in [0, 1]; 0 where masked, not finite or without a gradient.
    """
    prm = _hatch_params(spacing, width, interval, base, profile, transition)
    s, m, g = _prepare(field, mask, gradient)
    return _run("hatch", s, m, g, prm)


def _hatch_params(spacing, width, interval, base, profile, transition) -> np.ndarray:
    """The kernel parameters of :func:`hatching` (float64), every argument validated."""
    prm = _params(width, profile)
    prm[_p.SPACING] = _validate.size(spacing, "spacing", "spacing", buffer=True)
    prm[_p.Q] = _validate.positive(interval, "interval")
    prm[_p.BASE] = _validate.finite(base, "base")
    fade = _validate.finite(transition, "transition")
    if not 0 < fade <= 1:
        raise InputError(f"transition: expected a number in (0, 1], got {transition!r}")
    # Centre the fade on 4/3 (equal worst cases 4/3 and 2/3 of d_i) if it fits in (1, 2].
    prm[_p.SWITCH] = min(max(4 / 3, 1 + fade / 2), 2 - fade / 2)
    prm[_p.INV_FADE] = 1 / fade
    return prm


def modulated_hatching(
    field: np.ndarray,
    modulation: np.ndarray,
    *,
    spacing: float = 8.0,
    width: float = 1.0,
    mask: np.ndarray | None = None,
    interval: float = 1.0,
    base: float = 0.0,
    profile: str = "linear",
    transition: float = 0.04,
) -> np.ndarray:
    """Curved hatching whose lines thin out and fade with a modulation: Fig. 9's hatching
    "enhanced with the sh image" (1990 §4.2), in one pass.

    With ``full`` = :func:`hatching` at ``width`` and ``thin`` = at ``width / 2`` (Eq. 17-21,
    same field, spacing and gradient), the ink is ``thin + (2 m - 1)(full - thin)`` where the
    modulation ``m >= 0.5`` (the line's edges move out as ``m`` goes to 1) and ``2 m thin``
    below (the thin line fades to nothing at ``m = 0``). Narrowing before fading keeps the
    lines crisp, which is what survives copying (Fig. 10). The same as computing both
    hatchings and blending them, within float32 rounding (the blend may be fused into one
    multiply-add), for the price of one: the gradient (Eq. 9) is taken once.

    Parameters
    ----------
    field : (H, W) array
        As in :func:`hatching` (NaN/inf: masked).
    modulation : (H, W) array of numbers in [0, 1]
        How strongly the lines are drawn, e.g. :func:`sciviz_gbuf.styles.modulation` of a
        shade; values outside [0, 1] are clipped to it, NaN is read as 0 (no ink).
    spacing, width, mask, interval, base, profile, transition
        As in :func:`hatching` (the same bounds).

    Returns
    -------
    (H, W) float32 ink in [0, 1]; 0 where masked, not finite or without a gradient.
    """
    full = _hatch_params(spacing, width, interval, base, profile, transition)
    d = _validate.size(width, "width", "line_width", buffer=True)
    thin = _hatch_params(spacing, 0.5 * d, interval, base, profile, transition)
    s, m, _ = _prepare(field, mask, None)
    mod = np.asarray(modulation)
    if mod.shape != s.shape or not np.issubdtype(mod.dtype, np.number):
        raise InputError(
            f"modulation: expected an array of numbers shaped like field {s.shape}, got "
            f"{mod.dtype} {mod.shape}"
        )
    mod = np.ascontiguousarray(mod, dtype=np.float32)
    # the thin line's parameters follow the full one's (the kernel reads them at NPRM)
    full[_p.MODULATE] = 1.0
    prm = np.concatenate([full, thin]).astype(np.float32)
    return _stencil.run("hatch", s, m, aux=mod, prm=prm)
