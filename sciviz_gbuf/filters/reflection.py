"""Surface-analysis line patterns of a G-buffer: reflection lines, highlight lines, isophotes.

Saito & Takahashi 1990 §4.5: a *pseudo-highlight pattern* is the image, reflected in the
surface, of a family of parallel straight lights at infinity. In cylindrical coordinates whose
axis is parallel to the lights each light has a constant angle ``theta``; per pixel the view ray
is reflected about the G-buffer normal and its ``theta`` around the axis computed, and contour
lines (or alternating stripes, the "zebra" of CAD tools) of ``theta`` draw the pattern. The
lines turn sharply where the curvature jumps (a C1, not C2, seam) and break at a crease (G0).
*Highlight lines* (Beier & Chen 1994) use the normal itself instead of the reflected ray, so the
pattern does not move with the eye. *Isophotes* are curves of constant ``N . L``.

All are drawn with the contour operator (1990 Eq. 7-15) or, for stripes, with the same
distance-over-gradient antialiasing, so lines are antialiased and of even width in pixels.
Images are at the G-buffer's output size (``supersample`` antialiases them); ink in [0, 1].
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _validate
from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError
from . import _reflection_kernels as _rk
from .contours import contour_lines

__all__ = ["highlight_lines", "isophotes", "reflection_angle", "reflection_lines"]

MODES = ("reflection", "highlight")
PATTERNS = ("lines", "stripes")


def _unit(vector: Sequence[float], name: str) -> np.ndarray:
    try:
        v = np.asarray(vector, dtype=np.float64).reshape(3)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a 3-vector, got {_validate.brief(vector)}") from None
    if not (np.isfinite(v).all() and np.linalg.norm(v) > 0):
        raise InputError(
            f"{name}: expected a finite non-zero 3-vector, got {_validate.brief(vector)}"
        )
    return v / np.linalg.norm(v)


def _axis_frame(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing ``axis`` to a right-handed frame; ``theta = 0`` along the
    first, which is the world axis least aligned with ``axis`` made perpendicular to it."""
    w = np.eye(3)[int(np.argmin(np.abs(axis)))]
    e1 = w - (w @ axis) * axis
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(axis, e1)


def reflection_angle(
    gb: GBuffer, *, axis: Sequence[float] = (0.0, 0.0, 1.0), mode: str = "reflection"
) -> np.ndarray:
    """``theta`` per buffer pixel: the angle around ``axis`` of the reflected view ray
    (``mode="reflection"``, 1990 §4.5) or of the normal (``"highlight"``), in radians.

    Parameters
    ----------
    gb : GBuffer
    axis : 3 floats, default: (0, 0, 1)
        World direction of the parallel lights at infinity.
    mode : {"reflection", "highlight"}

    Returns
    -------
    (H, W) float32 in (-pi, pi] at the buffer's size; NaN on the background.
    """
    gb = check_gbuffer(gb)
    a = _unit(axis, "axis")
    mode = _validate.choice(mode, "mode", MODES)
    return _theta(gb, a, mode, 0.0)


def _theta(gb: GBuffer, axis: np.ndarray, mode: str, phase_rad: float) -> np.ndarray:
    cam = gb.camera
    e1, e2 = _axis_frame(axis)
    out = np.empty(gb.mask.shape, dtype=np.float32)
    _rk.theta_image(
        np.ascontiguousarray(gb.normal, dtype=np.float32),
        np.ascontiguousarray(gb.world, dtype=np.float32),
        gb.mask,
        np.ascontiguousarray(cam.view_matrix_array[:3, :3], dtype=np.float32),
        np.asarray(cam.position, dtype=np.float32),
        np.asarray(cam.direction, dtype=np.float32),
        bool(cam.parallel_projection),
        mode == "reflection",
        e1.astype(np.float32),
        e2.astype(np.float32),
        np.float32(np.angle(np.exp(1j * phase_rad))),
        out,
    )
    return out


def _wrapped_gradient(theta: np.ndarray) -> np.ndarray:
    """|grad theta| in radians per pixel with central differences taken modulo 2 pi, so the
    branch cut of ``arctan2`` is no edge; one-sided next to the background and image border."""
    out = np.empty(theta.shape, dtype=np.float32)
    _rk.wrapped_gradient(np.ascontiguousarray(theta, dtype=np.float32), out)
    return out


def _stripes(theta: np.ndarray, period: float, duty: float) -> np.ndarray:
    """Antialiased stripes: ink where ``theta / period mod 1 < duty``, the edge's coverage from
    its distance in pixels (angle distance over the gradient, as Eq. 7)."""
    g = _wrapped_gradient(theta)
    u = np.mod(theta / np.float32(period), np.float32(1.0))
    # Signed distance to the nearest stripe edge, in periods: > 0 inside the ink.
    inside = np.minimum(u, np.float32(duty) - u)
    outside = np.minimum(u - np.float32(duty), np.float32(1.0) - u)
    signed = np.where(u < duty, inside, -outside) * np.float32(period)
    with np.errstate(divide="ignore", invalid="ignore"):
        px = np.where(g > 0, signed / g, np.sign(signed) * np.float32(np.inf))
    ink = np.clip(np.float32(0.5) + px, 0.0, 1.0)
    return np.where(np.isfinite(theta), ink, np.float32(0.0)).astype(np.float32)


def _check_pattern(count: float, width: float, style: str, duty: float) -> None:
    # One line per level of theta: as many as contour levels (LIMITS["levels"]).
    _validate.size(count, "stripes", "levels", low=1.0, closed=True)
    _validate.size(width, "width", "line_width")
    _validate.choice(style, "style", PATTERNS)
    if not 0.0 < _validate.finite(duty, "duty") < 1.0:
        raise InputError(f"duty: expected a fraction in (0, 1), got {duty!r}")


def _pattern(
    gb: GBuffer, t: np.ndarray, *, count: float, width: float, style: str, duty: float
) -> np.ndarray:
    """Lines or stripes of the angle image ``t`` (in [-pi, pi), NaN off the surface)."""
    period = 2.0 * np.pi / float(count)
    valid = np.isfinite(t)
    if style == "stripes":
        ink = _stripes(t, period, duty)
    else:
        # A level at the branch cut of theta would be lost (the 3x3 range test of the contour
        # operator sees -pi and pi as far apart). So draw twice, with the cut at pi and at 0,
        # and keep each pixel from the drawing whose cut is a quarter turn away; 2 pi is a
        # whole number of periods, so both place the same lines.
        opts = {
            "interval": period,
            "width": width * gb.supersample,
            "mask": valid,
            "gradient": _wrapped_gradient(t),
            "c_dense": 1.0,
        }
        around_pi = contour_lines(t, **opts)
        around_zero = contour_lines(np.where(t < 0, t + np.float32(2 * np.pi), t), **opts)
        ink = np.where(np.abs(t) < np.float32(np.pi / 2), around_pi, around_zero)
    return np.clip(np.nan_to_num(gb.downsample(np.where(valid, ink, np.nan))), 0.0, 1.0)


def reflection_lines(
    gb: GBuffer,
    *,
    axis: Sequence[float] = (0.0, 0.0, 1.0),
    stripes: float = 16,
    width: float = 1.5,
    style: str = "lines",
    duty: float = 0.5,
    phase: float = 0.0,
    mode: str = "reflection",
) -> np.ndarray:
    """Reflection lines (pseudo-highlight pattern, 1990 §4.5): the mirror image of parallel
    lights at infinity, drawn as contour lines or stripes of the reflection angle ``theta``.

    Parameters
    ----------
    gb : GBuffer
        Any capture; the normals should be smooth (analytic patch normals are best).
    axis : 3 floats, default: (0, 0, 1)
        World direction of the lights (the cylinder axis of the paper).
    stripes : float in [1, 100000], default: 16
        Lights per full turn around the axis: lines every ``360 / stripes`` degrees of theta;
        at most ``LIMITS["levels"]`` = 100000.
    width : float in (0, 64], default: 1.5
        Line width in output pixels (style ``"lines"``); at most ``LIMITS["line_width"]`` = 64.
    style : {"lines", "stripes"}, default: "lines"
        Antialiased contour lines of theta, or alternating dark and light stripes ("zebra"),
        each stripe ``duty`` of a period wide.
    duty : float in (0, 1), default: 0.5
        Fraction of each period that is dark (``"stripes"``).
    phase : float, default: 0
        Turns the lights around the axis, in degrees.
    mode : {"reflection", "highlight"}, default: "reflection"
        ``"highlight"``: highlight lines (the normal instead of the reflected ray; the pattern
        does not depend on the eye).

    Returns
    -------
    (H, W) float32 ink in [0, 1] at the output size; 0 on the background.
    """
    gb = check_gbuffer(gb)
    a = _unit(axis, "axis")
    mode = _validate.choice(mode, "mode", MODES)
    _check_pattern(stripes, width, style, duty)
    phase = _validate.finite(phase, "phase")
    t = _theta(gb, a, mode, float(np.radians(phase)))
    return _pattern(gb, t, count=stripes, width=width, style=style, duty=duty)


def highlight_lines(gb: GBuffer, **options) -> np.ndarray:
    """Highlight lines (Beier & Chen 1994): :func:`reflection_lines` with ``mode="highlight"``,
    a view-independent pattern of the normals' angle around ``axis``."""
    return reflection_lines(gb, mode="highlight", **options)


def isophotes(
    gb: GBuffer,
    *,
    light: Sequence[float] = (0.0, 0.0, 1.0),
    interval: float = 10.0,
    levels: Sequence[float] | None = None,
    width: float = 1.0,
    frame: str = "eye",
) -> np.ndarray:
    """Isophotes: lines of constant ``N . L``, drawn as contour lines of the angle between the
    normal and the light, ``arccos(N . L)`` in degrees (evenly spread over the surface, unlike
    lines of ``N . L`` itself, which crowd where the surface faces the light).

    Parameters
    ----------
    gb : GBuffer
    light : 3 floats, default: (0, 0, 1)
        Direction towards the light; in eye space (default: a headlight) or world space.
    interval : float > 0, default: 10
        Degrees between isophotes, at least 180 / ``LIMITS["levels"]`` = 0.0018.
    levels : sequence of float, optional
        Explicit ``N . L`` values instead of ``interval``; at most ``LIMITS["levels"]`` =
        100000.
    width : float in (0, 64], default: 1
        Line width in output pixels; at most ``LIMITS["line_width"]`` = 64.
    frame : {"eye", "world"}, default: "eye"
        The frame of ``light``.

    Returns
    -------
    (H, W) float32 ink in [0, 1] at the output size.
    """
    gb = check_gbuffer(gb)
    lv = _unit(light, "light")
    frame = _validate.choice(frame, "frame", ("eye", "world"))
    width = _validate.size(width, "width", "line_width")
    n = gb.normal if frame == "eye" else gb.world_normal()
    cos = np.clip(n.astype(np.float32) @ lv.astype(np.float32), -1.0, 1.0)
    angle = np.degrees(np.arccos(cos)).astype(np.float32)
    angle = np.where(gb.mask, angle, np.float32(np.nan))
    if levels is not None:
        lv_cos = _validate.levels(levels, "levels")  # at most LIMITS["levels"], finite
        if not np.all(np.abs(lv_cos) <= 1.0):
            raise InputError(f"levels: expected N.L values in [-1, 1], got {lv_cos.tolist()}")
        opts = {"levels": np.sort(np.degrees(np.arccos(lv_cos)))}
    else:
        # a level every `interval` degrees over [0, 180]: at most LIMITS["levels"] of them
        step = _validate.positive(interval, "interval")
        if not 180.0 / step <= _validate.LIMITS["levels"]:
            raise InputError(
                f"interval: expected at least {180.0 / _validate.LIMITS['levels']:g} degrees "
                f"(LIMITS['levels'] isophotes over 180 degrees), got {interval!r}"
            )
        opts = {"interval": step}
    ink = contour_lines(angle, width=width * gb.supersample, mask=gb.mask, c_dense=1.0, **opts)
    return np.clip(np.nan_to_num(gb.downsample(np.where(gb.mask, ink, np.nan))), 0.0, 1.0)
