"""Profile, internal and crease edges of a G-buffer, the 2003 edge map, and edge enhancement.

Saito & Takahashi (1990 §3.2): profiles are the 0th-order and internal edges the 1st-order
discontinuities of the ``sz`` image. Nienhaus & Döllner (2003 §4-5): inner edges from the
normal buffer, profiles from the depth buffer, both in one RGBA edge map composited over a
shaded image.

How the detection is made robust (see :mod:`._edge_kernels`):

- *Profile*: a step of ``sz`` between 4-neighbours that neither side's slope (nor a crease
  between them) explains, measured in pixel footprints at the nearer pixel; the nearer pixel
  carries the line, so lines are one pixel wide and belong to the occluding surface. Because
  ``sz`` is affine on planes, planes at grazing angles produce no profile. A covered pixel next
  to the background is a profile pixel (the outline of the coverage); the image border is not.
- *Crease / internal*: the angle between the normals of neighbouring pixels whose depths are
  continuous. The G-buffer's normals are interpolated across smooth tessellations and split at
  real creases (``capture(feature_angle=...)``), so facets of a tessellated sphere produce no
  line (the artefact of 1990 §5.3). The sign follows the monotone-normal-map test
  ``(n_Y - n_X) . (P_Y - P_X) > 0`` for convex edges.

Line width: lines are found one buffer pixel wide, dilated to ``width * supersample`` buffer
pixels, and box-filtered to the output size, which antialiases them when the G-buffer was
captured with ``supersample > 1``.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence

import numpy as np

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from . import _edge_kernels as _k

__all__ = [
    "INNER_COLOR",
    "PROFILE_COLOR",
    "crease_edges",
    "edge_map",
    "enhance",
    "hidden_edges",
    "id_edges",
    "internal_edges",
    "profile_and_crease_edges",
    "profile_edges",
]

DEFAULT_DEPTH_JUMP = 1.0
DEFAULT_CREASE_ANGLE = 30.0
#: Shortest isolated piece of line drawn, in output pixels (see ``min_length``).
DEFAULT_MIN_LENGTH = 5.0


#: :func:`enhance` defaults (2003 §5): white inner edges, black profiles.
INNER_COLOR = (1.0, 1.0, 1.0)
PROFILE_COLOR = (0.0, 0.0, 0.0)


def _check_params(depth_jump: float, crease_angle: float, width: float) -> None:
    dj = _validate.finite(depth_jump, "depth_jump")
    if not dj > 0:
        raise InputError(f"depth_jump: expected a number of pixel widths > 0, got {depth_jump!r}")
    ca = _validate.finite(crease_angle, "crease_angle")
    if not 0 < ca < 180:
        raise InputError(f"crease_angle: expected degrees in (0, 180), got {crease_angle!r}")
    # The dilation costs about 3 * width * supersample passes over the buffer: bounded.
    _validate.size(width, "width", "line_width", low=1.0, closed=True)


def _check_min_length(min_length: float) -> float:
    # Labelling costs the same for any length; the bound keeps the parameter a line length.
    return _validate.size(min_length, "min_length", "line_width", low=0.0, closed=True)


def _check_gb(gb: object) -> GBuffer:
    """:func:`check_gbuffer`, and a supersample the line dilation can afford (a G-buffer made
    by hand may carry any number there)."""
    gb = check_gbuffer(gb)
    _validate.count(gb.supersample, "gb.supersample", "supersample")
    return gb


def _camera_terms(gb: GBuffer) -> tuple[bool, float, float]:
    cam = gb.camera
    return bool(cam.parallel_projection), 1.0 / cam.distance, 1.0 / cam.pixel_size


def _kernel_inputs(gb: GBuffer) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``sz``, ``depth``, ``normal``, ``mask`` as the kernels take them (no copy if already so)."""
    return (
        np.ascontiguousarray(gb.sz, dtype=np.float32),
        np.ascontiguousarray(gb.depth, dtype=np.float32),
        np.ascontiguousarray(gb.normal, dtype=np.float32),
        np.ascontiguousarray(gb.mask, dtype=np.bool_),
    )


_NO_SECOND = np.zeros((1, 1), dtype=np.float32)  # edge_pass's second crease image, unused


def _pair_edges(
    gb: GBuffer,
    depth_jump: float,
    crease_angle: float,
    creases: bool = True,
    second_angle: float | None = None,
):
    """One-pixel profile and signed crease images (per-thread scratch: valid until the next
    call of this module in the same thread); with ``second_angle``, the crease image at that
    angle too (``profile, crease, crease2``), from the same pass."""
    parallel, inv_d, inv_w = _camera_terms(gb)
    h, w = gb.shape
    profile = _scratch("profile", (h, w), np.float32)
    crease = _scratch("crease", (h, w), np.float32)
    crease2 = _NO_SECOND if second_angle is None else _scratch("crease2", (h, w), np.float32)
    _k.edge_pass(
        *_kernel_inputs(gb),
        parallel,
        inv_d,
        inv_w,
        float(depth_jump),
        float(crease_angle),
        0.5 * float(crease_angle),
        bool(creases),
        _k.MODE_PAIRS,
        profile,
        crease,
        0.0 if second_angle is None else float(second_angle),
        0.0 if second_angle is None else 0.5 * float(second_angle),
        crease2,
    )
    if second_angle is None:
        return profile, crease
    return profile, crease, crease2


def _clean(
    gb: GBuffer, profile: np.ndarray, crease: np.ndarray, min_length: float
) -> tuple[np.ndarray, np.ndarray]:
    """Speck removal and hysteresis on the one-pixel line images of :func:`_pair_edges`
    (modified in place and returned).

    The lines of both images form one drawing, so they are judged together. A connected
    (8-neighbour) piece of strong ink (>= 0.5: a jump of at least 1.5 ``depth_jump`` or a
    turn of 1.25 ``crease_angle``) stays if it is at least ``min_length`` output pixels long
    or part of the outline of the coverage (a small object far away is drawn, however
    small); weak ink stays only where it is connected to a strong piece that stays (Canny's
    hysteresis: it continues lines, it does not start them). Noise of a scanned or decimated
    surface leaves short isolated marks; the short edges of a real feature (a cube's corner)
    are joined to the lines they meet and stay. Union-find over the ink pixels alone
    (:func:`._edge_kernels.clean_lines`): the same components as labelling the whole image.
    """
    ids = _scratch("ids", profile.shape, np.int32, zero=True)
    mask = np.ascontiguousarray(gb.mask, dtype=np.bool_)
    _k.clean_lines(profile, crease, mask, float(min_length * gb.supersample), ids)
    return profile, crease


_SCRATCH = threading.local()
#: Largest scratch image kept between calls (64 MB: a 4096^2 float32 buffer); larger ones are
#: made per call. About eight are kept per thread.
_SCRATCH_MAX_BYTES = 64 << 20


def _scratch(name: str, shape: tuple[int, ...], dtype: type, zero: bool = False) -> np.ndarray:
    """A buffer-sized intermediate image, kept per thread between calls.

    The one-pixel line images live only within one call of this module's functions; a fresh
    one is page-faulted in on every call (16 MB at 2048^2, ~1-2 ms/MB on a VM that hands free
    memory back to its host), which costs more than the kernels that fill it. ``zero``: the
    buffer is all 0 when first made and its user leaves it so (:func:`_clean`'s ids).
    """
    if int(np.prod(shape)) * np.dtype(dtype).itemsize > _SCRATCH_MAX_BYTES:
        # Not kept: a huge buffer would stay allocated for as long as the thread lives.
        return np.zeros(shape, dtype=dtype) if zero else np.empty(shape, dtype=dtype)
    pool = getattr(_SCRATCH, "pool", None)
    if pool is None:
        pool = _SCRATCH.pool = {}
    buf = pool.get(name)
    if buf is None or buf.shape != tuple(shape) or buf.dtype != dtype:
        buf = np.zeros(shape, dtype=dtype) if zero else np.empty(shape, dtype=dtype)
        pool[name] = buf
    return buf


def _lines(
    gb: GBuffer, depth_jump: float, crease_angle: float, min_length: float
) -> tuple[np.ndarray, np.ndarray]:
    """Profile and signed crease lines, one buffer pixel wide, cleaned by :func:`_clean`."""
    profile, crease = _pair_edges(gb, depth_jump, crease_angle)
    return _clean(gb, profile, crease, min_length)


def _disk(size: int) -> np.ndarray:
    """Footprint whose extent across any line direction is ``size`` pixels."""
    yy, xx = np.mgrid[:size, :size] - (size - 1) / 2.0
    return (xx * xx + yy * yy) <= (size / 2.0) ** 2


def _dilate(ink: np.ndarray, size: int, sign: float = 0.0, scratch: str = "") -> np.ndarray:
    """``scipy.ndimage.grey_dilation(ink, footprint=_disk(size), mode="constant", cval=0)``
    (of ``np.maximum(sign * ink, 0)`` if ``sign`` is not 0), in one numba pass: each row of
    the disk is a run of columns (:func:`._edge_kernels.dilate_kernel`). ``scratch``: the
    result goes into that per-thread scratch image (valid until this module's next call)."""
    foot = _disk(size)
    runs_a = np.array([np.flatnonzero(row)[0] for row in foot], dtype=np.int64)
    runs_b = np.array([np.flatnonzero(row)[-1] for row in foot], dtype=np.int64)
    h, w = ink.shape
    # the padded copy: border 0 when made, interior rewritten by every call
    pad = _scratch(f"pad{size}", (h + size - 1, w + size - 1), np.float32, zero=True)
    out = _scratch(scratch, ink.shape, np.float32) if scratch else np.empty(ink.shape, np.float32)
    _k.dilate_kernel(
        np.ascontiguousarray(ink, dtype=np.float32), np.float32(sign), (size - 1) // 2,
        runs_a, runs_b, pad, out,
    )  # fmt: skip
    return out


def _reduce(gb: GBuffer, ink: np.ndarray, signed: bool) -> np.ndarray:
    """A line image box-filtered to output size and clipped (:func:`._edge_kernels.finish_lines`;
    ``signed``: the clipped positive part minus the clipped negative part)."""
    k = _validate.count(gb.supersample, "gb.supersample", "supersample")
    out = np.empty(gb.output_shape, dtype=np.float32)
    _k.finish_lines(np.ascontiguousarray(ink, dtype=np.float32), k, signed, out)
    return out


def _finish(gb: GBuffer, *inks: np.ndarray, width: float) -> list[np.ndarray]:
    """Dilate one-pixel line images to ``width`` output pixels and reduce them to output size
    (box filter and clip to [0, 1] in one pass)."""
    size = max(1, round(width * gb.supersample))
    return [
        _reduce(gb, _dilate(ink, size, scratch="dilated") if size > 1 else ink, False)
        for ink in inks
    ]


def _finish_signed(gb: GBuffer, signed: np.ndarray, width: float) -> np.ndarray:
    """:func:`_finish` of the positive and the negative part, the second subtracted; one pass
    where no dilation is needed."""
    size = max(1, round(width * gb.supersample))
    if size == 1:
        return _reduce(gb, signed, True)
    pos = _reduce(gb, _dilate(signed, size, 1.0, scratch="dilated+"), False)
    neg = _reduce(gb, _dilate(signed, size, -1.0, scratch="dilated-"), False)
    return (pos - neg).astype(np.float32, copy=False)


def profile_edges(
    gb: GBuffer,
    *,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    width: float = 1.0,
    min_length: float = DEFAULT_MIN_LENGTH,
) -> np.ndarray:
    """Profile lines: 0th-order discontinuities of ``sz`` and the coverage outline (1990 §3.2).

    Parameters
    ----------
    gb : GBuffer
    depth_jump : float, default: 1.0
        A step between neighbouring pixels, not explained by the surface slope on either side,
        larger than this many pixel footprints (pixel widths at that depth) starts a line; the
        ink ramps linearly to full at twice the value. Silhouettes against the background are
        always full ink.
    width : float in [1, 64], default: 1
        Line width in output pixels, at most ``LIMITS["line_width"]`` = 64.
    min_length : float in [0, 64], default: 5
        Isolated pieces of line (not joined to other profile or crease ink, not part of the
        coverage outline) shorter than this many output pixels are dropped, as are pieces
        with only weak ink (hysteresis); 0 keeps every piece that has a strong pixel. At
        most ``LIMITS["line_width"]`` = 64.

    Returns
    -------
    (H, W) float32 ink in [0, 1] at the output size (``gb.output_shape``).

    Notes
    -----
    The jump is measured relative to the grazing angle: divided by ``sqrt(1 + s^2)``, ``s``
    the gentler of the two one-sided slopes in footprints per pixel, because the depth of a
    noisy or faceted surface wanders by that factor more where it is seen obliquely.
    Isolated pieces are judged with the crease lines at the default ``crease_angle``, as in
    :func:`crease_edges`: the two together make one drawing.
    """
    gb = _check_gb(gb)
    _check_params(depth_jump, DEFAULT_CREASE_ANGLE, width)
    min_length = _check_min_length(min_length)
    if min_length == 0:
        profile, crease = _pair_edges(gb, depth_jump, DEFAULT_CREASE_ANGLE, creases=False)
    else:
        profile, crease = _pair_edges(gb, depth_jump, DEFAULT_CREASE_ANGLE)
    profile, _ = _clean(gb, profile, crease, min_length)
    return _finish(gb, profile, width=width)[0]


def internal_edges(
    gb: GBuffer,
    *,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    width: float = 1.0,
    min_length: float = DEFAULT_MIN_LENGTH,
) -> np.ndarray:
    """Signed internal edges: 1st-order discontinuities, > 0 convex, < 0 concave (1990 §3.2).

    Neighbouring pixels whose depth is continuous (see ``depth_jump``) but whose surface turns
    by more than ``crease_angle`` degrees (between their normals, or in the depth's own
    cross-section, whichever is larger); the magnitude ramps from 0 at ``crease_angle`` to 1
    at 1.5 x ``crease_angle``, so it grows with the sharpness of the edge, as in the paper.
    Draw positive values white and negative ones black for the 1990 Fig. 7 style. ``width``:
    line width in output pixels in [1, 64] (at most ``LIMITS["line_width"]`` = 64).
    ``min_length``: isolated pieces shorter than this are dropped, see :func:`profile_edges`.

    A crease must be a crease on both scales the buffer shows: the normals beside the pair
    turn by less than half as much as across it (noise and sub-pixel facets turn the normals
    at random from pixel to pixel), and a crease seen in the depth is measured by the angle
    between the flanks' normals (estimated from the depth), not by the section's own angle,
    which grows without bound on surfaces seen at grazing angles.

    Returns
    -------
    (H, W) float32 in [-1, 1] at the output size.
    """
    gb = _check_gb(gb)
    _check_params(depth_jump, crease_angle, width)
    _, crease = _lines(gb, depth_jump, crease_angle, _check_min_length(min_length))
    return _finish_signed(gb, crease, width)


def crease_edges(
    gb: GBuffer,
    *,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    width: float = 1.0,
    min_length: float = DEFAULT_MIN_LENGTH,
) -> np.ndarray:
    """Crease lines: normal discontinuities sharper than ``crease_angle`` degrees (2003 §4).

    The unsigned counterpart of :func:`internal_edges`: ink in [0, 1] at the output size;
    ``width`` in [1, 64] output pixels (at most ``LIMITS["line_width"]`` = 64); isolated
    pieces shorter than ``min_length`` output pixels are dropped (see :func:`profile_edges`).
    """
    gb = _check_gb(gb)
    _check_params(depth_jump, crease_angle, width)
    _, crease = _lines(gb, depth_jump, crease_angle, _check_min_length(min_length))
    return _finish(gb, np.abs(crease), width=width)[0]


def profile_and_crease_edges(
    gb: GBuffer,
    *,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    width: float = 1.0,
    min_length: float = DEFAULT_MIN_LENGTH,
    signed: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """``(profile_edges(gb, ...), internal_edges(gb, ...))`` (``signed``) or
    ``(profile_edges(gb, ...), crease_edges(gb, ...))``, the same arrays, in one pass where
    they share it: both are cleaned together with the crease lines at ``crease_angle``, so at
    the default angle (the one :func:`profile_edges` judges its pieces with) the lines are
    found and cleaned once for both (1990 §3.2: one G-buffer, every edge image).
    """
    gb = _check_gb(gb)
    _check_params(depth_jump, crease_angle, width)
    min_length = _check_min_length(min_length)
    signed = _validate.boolean(signed, "signed")
    if min_length == 0:
        # profile_edges skips the creases without cleaning
        prof = profile_edges(gb, depth_jump=depth_jump, width=width, min_length=min_length)
        _, crease = _lines(gb, depth_jump, crease_angle, min_length)
    elif float(crease_angle) != DEFAULT_CREASE_ANGLE:
        # One pass for both angles: the profiles are cleaned with the default angle's creases
        # (as profile_edges cleans them), the creases with their own.
        profile, default, crease = _pair_edges(
            gb, depth_jump, DEFAULT_CREASE_ANGLE, second_angle=crease_angle
        )
        own = _scratch("profile2", profile.shape, np.float32)
        np.copyto(own, profile)
        prof = _finish(gb, _clean(gb, profile, default, min_length)[0], width=width)[0]
        _, crease = _clean(gb, own, crease, min_length)
    else:
        profile, crease = _lines(gb, depth_jump, crease_angle, min_length)
        prof = _finish(gb, profile, width=width)[0]
    if signed:
        return prof, _finish_signed(gb, crease, width)
    return prof, _finish(gb, np.abs(crease), width=width)[0]


def buffer_lines(
    gb: GBuffer,
    *,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    min_length: float = DEFAULT_MIN_LENGTH,
) -> tuple[np.ndarray, np.ndarray]:
    """The profile and (unsigned) crease lines of :func:`profile_and_crease_edges` before they
    are widened and reduced: one buffer pixel wide at the G-buffer's own (supersampled) size,
    ink in [0, 1], cleaned together with the creases at ``crease_angle``. For tracing them
    (:func:`~sciviz_gbuf.filters.strokes.edge_strokes`)."""
    gb = _check_gb(gb)
    _check_params(depth_jump, crease_angle, 1.0)
    profile, crease = _lines(gb, depth_jump, crease_angle, _check_min_length(min_length))
    return profile.copy(), np.abs(crease)


#: Hidden lines within this many output pixels of a line of a nearer layer are that line.
HIDDEN_CLEARANCE = 1.5


def hidden_edges(
    gb: GBuffer,
    *,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    width: float = 1.0,
    min_length: float = DEFAULT_MIN_LENGTH,
) -> np.ndarray:
    """Hidden lines: the profile and crease lines of the surfaces behind the visible one
    (1990 §3.2's edges of the extended G-buffer of §5.1), for dashed or thin drawing.

    ``gb`` must hold the layers behind its first surface (``capture(..., layers=k)``, k >= 2).
    Each layer's lines are found as :func:`profile_and_crease_edges` finds the visible ones
    (same ``crease_angle``, ``depth_jump``, ``min_length``); a line of a layer within
    ``HIDDEN_CLEARANCE`` = 1.5 px of a line of a nearer layer is dropped: it is that line (a
    hidden edge seen end-on behind a visible one) or where the layer's surface changes
    because a nearer surface ends there (the outline of a plate in front of a box).

    Returns
    -------
    (H, W) float32 ink in [0, 1] at the output size, ``width`` px wide (at most 64).
    """
    from scipy import ndimage

    gb = _check_gb(gb)
    _check_params(depth_jump, crease_angle, width)
    if not gb.layers:
        raise InputError(
            "gb: hidden lines need the surfaces behind the visible one: capture the G-buffer "
            "with layers=2 or more"
        )
    opts = {"crease_angle": crease_angle, "depth_jump": depth_jump,
            "min_length": min_length, "signed": False}  # fmt: skip
    prof, crease = profile_and_crease_edges(gb, **opts)
    nearer = (prof >= 0.5) | (crease >= 0.5)
    out = np.zeros(gb.output_shape, np.float32)
    for layer in gb.layers:
        prof, crease = profile_and_crease_edges(layer, **opts)
        ink = np.maximum(prof, crease)
        near = ndimage.distance_transform_edt(~nearer) <= HIDDEN_CLEARANCE
        np.maximum(out, np.where(near, np.float32(0.0), ink), out=out)
        nearer |= ink >= 0.5
    size = max(1, round(float(width)))
    if size > 1:
        out = ndimage.grey_dilation(out, footprint=_disk(size), mode="constant", cval=0.0)
    return out.astype(np.float32, copy=False)


def id_edges(gb: GBuffer, *, ids: str = "object", width: float = 1.0) -> np.ndarray:
    """Lines where the object id (or cell id) changes (1990 §3.2 and §5.2).

    Object-id lines outline each dataset of the scene, e.g. to restrict enhancement to one of
    them; ``ids="cell"`` draws the tessellation. The nearer pixel of a pair carries the line.
    ``width``: in [1, 64] output pixels (at most ``LIMITS["line_width"]`` = 64).

    Returns
    -------
    (H, W) float32 ink in [0, 1] at the output size.
    """
    gb = _check_gb(gb)
    _check_params(DEFAULT_DEPTH_JUMP, DEFAULT_CREASE_ANGLE, width)
    ids = _validate.choice(ids, "ids", ("object", "cell"))
    idimg = (gb.object_id if ids == "object" else gb.cell_id).astype(np.int64)
    idimg = np.where(gb.mask, idimg, -1)
    out = np.empty(gb.shape, dtype=np.float32)
    _k.id_edge_kernel(
        np.ascontiguousarray(idimg), np.ascontiguousarray(gb.depth, dtype=np.float32), out
    )
    return _finish(gb, out, width=width)[0]


def edge_map(
    gb: GBuffer,
    *,
    operator: str = "diagonal",
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    depth_jump: float = DEFAULT_DEPTH_JUMP,
    width: float = 1.0,
) -> np.ndarray:
    """The edge map of Nienhaus & Döllner (2003 §4.1): inner edges in RGB, profiles in alpha.

    Parameters
    ----------
    gb : GBuffer
    operator : {"diagonal", "c1"}, default: "diagonal"
        ``"diagonal"``: the 2003 first variant over the diagonal pairs (A, H), (C, F). Inner
        intensity from the angle between their normals; profile ``1 - I_Z`` with
        ``I_Z = (1 - |A-H|/2)^2 (1 - |C-F|/2)^2``, where ``|A-H|`` is the larger unexplained
        depth jump of A -> X and X -> H, scaled so that ``2 * depth_jump`` footprints reach 2.
        ``"c1"``: the profile from the C1 operator (1990 Eq. 9 / 2003 second variant) over
        the 8 neighbours with the same jump measure, scaled so that a straight step gives 1;
        inner edges as above.
        Both straddle the edge (lines about two pixels wide, softer than
        :func:`profile_edges`), as in the paper. Inner edges also include the creases the
        depth shows (see :func:`internal_edges`), for data whose normals are smoothed across
        real creases.
    crease_angle, depth_jump, width
        As in :func:`internal_edges` and :func:`profile_edges` (``width`` in [1, 64]:
        at most ``LIMITS["line_width"]``).

    Returns
    -------
    (H, W, 4) float32 in [0, 1] at the output size: R = G = B = inner-edge intensity,
    A = profile intensity (1 = full edge; the paper stores the complements).

    Notes
    -----
    The paper averages the two diagonal cosines; that halves the response of an edge running
    along a diagonal (only one pair crosses it), so the smaller cosine is used instead.
    """
    gb = _check_gb(gb)
    _check_params(depth_jump, crease_angle, width)
    operator = _validate.choice(operator, "operator", ("diagonal", "c1"))
    parallel, inv_d, inv_w = _camera_terms(gb)
    h, w = gb.shape
    # One pass: the 2003 inner edges with the depth's own creases added (data whose normals
    # are smoothed across real creases), and the 2003 profile, as two planar images.
    inner = _scratch("profile", (h, w), np.float32)
    alpha = _scratch("crease", (h, w), np.float32)
    _k.edge_pass(
        *_kernel_inputs(gb),
        parallel,
        inv_d,
        inv_w,
        float(depth_jump),
        float(crease_angle),
        0.5 * float(crease_angle),
        True,
        _k.MODE_C1 if operator == "c1" else _k.MODE_DIAGONAL,
        inner,
        alpha,
        0.0,
        0.0,
        _NO_SECOND,
    )
    # The 2003 lines already straddle the edge (two buffer pixels): dilate by one pixel less.
    size = max(1, round(width * gb.supersample) - 1)
    if size > 1:
        inner, alpha = (
            _dilate(inner, size, scratch="dilated+"),
            _dilate(alpha, size, scratch="dilated-"),
        )
    k = _validate.count(gb.supersample, "gb.supersample", "supersample")
    res = np.empty((*gb.output_shape, 4), dtype=np.float32)
    _k.edge_map_finish(inner, alpha, k, res)
    return res


def enhance(
    shaded_rgb: np.ndarray,
    edge_map: np.ndarray,
    inner_color: Sequence[float] = INNER_COLOR,
    profile_color: Sequence[float] = PROFILE_COLOR,
) -> np.ndarray:
    """Composite an edge map over a shaded image (2003 §5.1, technical illustration).

    First the inner edges: ``lerp(shaded, inner_color, R)``; then the profiles over that:
    ``lerp(result, profile_color, A)``.

    Parameters
    ----------
    shaded_rgb : (H, W, 3) or (H, W) float in [0, 1]
        The shaded image (a grey (H, W) image is broadcast to RGB); NaN (background) pixels
        are taken as white paper.
    edge_map : (H, W, 4) float in [0, 1]
        From :func:`edge_map`; any RGBA image with inner intensity in R and profile in A.
    inner_color, profile_color : RGB in [0, 1]
        Default: white inner edges (the 1990 Fig. 7 edge highlight) and black profiles.

    Returns
    -------
    (H, W, 3) float32 RGB in [0, 1].
    """
    em = np.asarray(edge_map, dtype=np.float32)
    if em.ndim != 3 or em.shape[2] != 4:
        raise InputError(f"edge_map: expected an (H, W, 4) RGBA array, got shape {em.shape}")
    img = np.asarray(shaded_rgb, dtype=np.float32)
    if (img.ndim != 3 and img.ndim != 2) or (img.ndim == 3 and img.shape[2] != 3):
        raise InputError(
            f"shaded_rgb: expected an (H, W, 3) or (H, W) image, got shape {img.shape}"
        )
    if img.shape[:2] != em.shape[:2]:
        raise InputError(
            f"edge_map: shape {em.shape[:2]} does not match shaded_rgb {img.shape[:2]}"
        )
    inner_c = _validate.rgb(inner_color, "inner_color")
    prof_c = _validate.rgb(profile_color, "profile_color")
    # The paper (NaN -> 1) and the clip of the grey or RGB input, then
    # lerp(lerp(base, inner_c, R), prof_c, A), per pixel in one pass (float32 throughout).
    base = np.ascontiguousarray(img if img.ndim == 3 else img[..., None], dtype=np.float32)
    out = np.empty((*img.shape[:2], 3), dtype=np.float32)
    _k.enhance_kernel(base, np.ascontiguousarray(em), inner_c, prof_c, out)
    return out
