"""Cameras that frame data: pick a viewing direction, get the eye that frames it by one rule.

The framing rule of every recipe and command: the screen-space bounding box of the visible
data's points, projected with the actual camera, is centred in the image and fills
:data:`FILL` (85 %) of the limiting image dimension (the width or the height, whichever the
data reaches first). Perspective makes near parts larger, so the eye is placed by a few
fixed-point steps on the projected points (move sideways until the box is centred, along the
line of sight until it has the size), not from the bounding box's corners, which overestimate
oblique views and leave the data pushed to one side.

The up axis: :func:`default_up` reads it from the convention of the file a dataset was read
from (:func:`sciviz_gbuf.readers.up_axis`: OFF/OBJ/PLY/glTF y-up; STL, VTK, DEM, DICOM z-up);
``up=`` overrides it.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..readers.formats import UP_AXES, up_axis
from ..readers.mesh import source_name
from .camera import VIEWS

__all__ = [
    "FILL",
    "check_up",
    "default_up",
    "framed_camera",
    "framing",
    "named_view_camera",
    "oblique_camera",
    "terrain_birdseye_camera",
]

_AXES = {"x": 0, "y": 1, "z": 2}
#: Fraction of the limiting image dimension that framed data fills (the 75-92 % rule).
FILL = 0.85
# Fixed-point steps of the perspective fit and its tolerance (in fractions of the half image).
_STEPS = 40
_TOL = 1e-3

Camera = tuple[tuple[float, ...], tuple[float, ...], tuple[float, float, float]]


def check_up(up: object) -> str:
    """``up`` as ``"x"``, ``"y"`` or ``"z"`` (case-insensitive), else an InputError."""
    key = up.strip().lower() if isinstance(up, str) else None
    if key not in UP_AXES:
        raise InputError(f"up: expected 'x', 'y' or 'z', got {up!r}")
    return key


def default_up(scene: object) -> str:
    """The up axis of a file, a dataset or a list of them, by the convention of the file's
    format (for a dataset, of the file :func:`~sciviz_gbuf.readers.read_mesh` read it from):
    ``"y"`` for OFF/OBJ/PLY/glTF, ``"z"`` otherwise, for data not read from a file and for
    files that disagree."""
    items = scene if isinstance(scene, (list, tuple)) else [scene]
    axes = set()
    for item in items:
        if isinstance(item, (str, os.PathLike)):
            name = item
        else:
            try:
                name = source_name(item)
            except (TypeError, ValueError, AttributeError, NotImplementedError):
                name = None  # not a dataset (a PatchSet, an array): no file convention
        axes.add(up_axis(name))
    return axes.pop() if len(axes) == 1 else "z"


def _frame_points(bounds: Sequence[float], points: np.ndarray | None) -> np.ndarray:
    if points is None:
        if len(bounds) != 6:
            raise InputError(
                f"bounds: expected (xmin, xmax, ymin, ymax, zmin, zmax), got {bounds!r}"
            )
        lo = np.asarray(bounds[0::2], dtype=np.float64)
        hi = np.asarray(bounds[1::2], dtype=np.float64)
        return np.array(np.meshgrid(*np.stack([lo, hi], axis=1))).reshape(3, -1).T
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts) == 0:
        raise InputError("points: expected at least one finite point to frame")
    return pts


def framing(
    points: np.ndarray, position: Sequence[float], focal_point: Sequence[float],
    view_up: Sequence[float], *, view_angle: float = 30.0, aspect: float = 4 / 3,
    parallel_scale: float | None = None,
) -> tuple[float, float, float]:  # fmt: skip
    """How ``points`` sit in a camera's image: ``(fill, dx, dy)``.

    ``fill`` is the fraction of the limiting image dimension their projected bounding box
    spans; ``dx``, ``dy`` the offset of its centre from the image centre, in fractions of the
    image width and height (right and up positive). ``parallel_scale``: an orthographic camera
    of that half height. Points behind the eye make ``fill`` infinite.
    """
    pos = np.asarray(position, dtype=np.float64)
    fwd = np.asarray(focal_point, dtype=np.float64) - pos
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.asarray(view_up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    x, y = _project(np.asarray(points, dtype=np.float64) - pos, fwd, right, up,
                    view_angle, aspect, parallel_scale)  # fmt: skip
    if x is None:
        return float("inf"), 0.0, 0.0
    fill = max(x.max() - x.min(), y.max() - y.min()) / 2
    return float(fill), float(x.max() + x.min()) / 4, float(y.max() + y.min()) / 4


def _project(rel, fwd, right, up, view_angle, aspect, parallel_scale):
    """Normalised device x, y (-1..1 across the image) of points relative to the eye."""
    tan_v = np.tan(np.radians(view_angle) / 2)
    if parallel_scale is not None:
        return rel @ right / (parallel_scale * aspect), rel @ up / parallel_scale
    z = rel @ fwd
    if z.min() <= 0:
        return None, None
    return rel @ right / (z * tan_v * aspect), rel @ up / (z * tan_v)


def framed_camera(
    bounds: Sequence[float],
    direction: Sequence[float],
    view_up: Sequence[float],
    *,
    view_angle: float = 30.0,
    aspect: float = 4 / 3,
    margin: float = 1.0 - FILL,
    points: np.ndarray | None = None,
    parallel: bool = False,
) -> Camera:
    """A camera looking along ``-direction`` that frames the data by the one rule.

    The projected bounding box of the data (``points``, else the corners of ``bounds``) is
    centred in the image and spans ``1 - margin`` of the limiting image dimension.

    Parameters
    ----------
    bounds : (xmin, xmax, ymin, ymax, zmin, zmax)
        As ``pyvista.DataSet.bounds``; ignored when ``points`` are given.
    direction : 3 floats
        From the data towards the eye (any length).
    view_up : 3 floats
        World direction that should point up in the image; must not be parallel to
        ``direction``.
    view_angle : float, default: 30.0
        The camera's vertical view angle in degrees (VTK's default).
    aspect : float, default: 4/3
        Width / height of the image.
    margin : float, default: 0.15
        Empty part of the limiting image dimension, shared equally by both sides: the data
        fills :data:`FILL` = 85 % of it by default.
    points : (N, 3) array, optional
        Frame these points instead of the corners of ``bounds``: the true projected extent
        (corners overestimate oblique views).
    parallel : bool, default: False
        Frame for an orthographic capture (``capture(..., parallel_projection=True)``, which
        keeps ``distance * tan(view_angle / 2)`` as the parallel scale).

    Returns
    -------
    position, focal_point, view_up : tuple of float
        As accepted by :func:`sciviz_gbuf.capture`'s ``camera``; the focal point is on the
        line of sight at the depth of the data's centre.
    """
    to_eye = np.asarray(direction, dtype=np.float64).reshape(3)
    world_up = np.asarray(view_up, dtype=np.float64).reshape(3)
    if not (np.isfinite(to_eye).all() and np.linalg.norm(to_eye) > 0):
        raise InputError(f"direction: expected a finite non-zero 3-vector, got {direction!r}")
    to_eye = to_eye / np.linalg.norm(to_eye)
    right = np.cross(-to_eye, world_up)
    if not (np.isfinite(right).all() and np.linalg.norm(right) > 1e-9 * np.linalg.norm(world_up)):
        raise InputError(f"view_up: expected a vector not parallel to direction, got {view_up!r}")
    if not 0.0 < view_angle < 180.0:
        raise InputError(f"view_angle: expected degrees in (0, 180), got {view_angle!r}")
    if not 0.0 <= margin < 1.0:
        raise InputError(f"margin: expected a fraction in [0, 1), got {margin!r}")
    right /= np.linalg.norm(right)
    up = np.cross(right, -to_eye)
    pts = _frame_points(bounds, points)
    fill = 1.0 - margin
    tan_v = np.tan(np.radians(view_angle) / 2)
    tan_h = tan_v * aspect
    r, u, t = pts @ right, pts @ up, pts @ to_eye
    # The view-plane box of the points: exact for an orthographic camera.
    centre = right * (r.min() + r.max()) / 2 + up * (u.min() + u.max()) / 2
    centre = centre + to_eye * (t.min() + t.max()) / 2
    half = max((r.max() - r.min()) / (2 * aspect), (u.max() - u.min()) / 2) / fill
    if parallel or half <= 0.0:
        scale = half if half > 0.0 else 1.0
        # At the distance that keeps ``scale`` when the capture switches to orthographic (the
        # capture moves an orthographic eye back if data lies behind it).
        position = centre + to_eye * (scale / tan_v)
        return tuple(position.tolist()), tuple(centre.tolist()), tuple(float(v) for v in world_up)
    # Start where every point is in view (a point at lateral offset r and height t towards
    # the eye is in view once the eye is farther than t + |r| / tan(half field) from the
    # focal plane), then step: sideways by the box's offset, along the line of sight by its
    # size, each measured at the depth of the points that make the box's sides.
    rel = pts - centre
    distance = max(
        np.max(rel @ to_eye + np.abs(rel @ right) / (tan_h * fill)),
        np.max(rel @ to_eye + np.abs(rel @ up) / (tan_v * fill)),
    )
    eye = centre + distance * to_eye
    fwd = -to_eye
    for _ in range(_STEPS):
        d = pts - eye
        z = d @ fwd
        x = d @ right / (z * tan_h)
        y = d @ up / (z * tan_v)
        ix0, ix1, iy0, iy1 = x.argmin(), x.argmax(), y.argmin(), y.argmax()
        cx, cy = (x[ix1] + x[ix0]) / 2, (y[iy1] + y[iy0]) / 2
        size = max((x[ix1] - x[ix0]) / 2, (y[iy1] - y[iy0]) / 2)
        if abs(cx) < _TOL and abs(cy) < _TOL and abs(size - fill) < _TOL:
            break
        zx, zy = (z[ix0] + z[ix1]) / 2, (z[iy0] + z[iy1]) / 2
        eye = eye + right * (cx * zx * tan_h) + up * (cy * zy * tan_v)
        zref = zx if (x[ix1] - x[ix0]) / 2 >= (y[iy1] - y[iy0]) / 2 else zy
        # Closer by at most half the nearest depth: a point never passes behind the eye.
        step = max(zref * (size / fill - 1.0), -0.5 * z.min())
        eye = eye - fwd * step
    focal = eye + fwd * ((centre - eye) @ fwd)
    return tuple(eye.tolist()), tuple(focal.tolist()), tuple(float(v) for v in world_up)


def oblique_camera(
    bounds: Sequence[float],
    *,
    up_axis: str = "z",
    elevation: float = 45.0,
    azimuth: float = 0.0,
    **kwargs,
) -> Camera:
    """A camera looking down on an object at ``elevation`` degrees, its ``up_axis`` upright.

    Parameters
    ----------
    bounds : (xmin, xmax, ymin, ymax, zmin, zmax)
    up_axis : {"x", "y", "z"}, default: "z"
        World axis that is vertical in the image (the axis of a nut, the up of a terrain).
    elevation : float, default: 45.0
        Angle of the line of sight above the plane normal to ``up_axis``, in (0, 90].
    azimuth : float, default: 0.0
        Rotation of the eye about ``up_axis``, in degrees, from the next axis in cyclic order
        (x -> y, y -> z, z -> x).
    **kwargs
        ``view_angle``, ``aspect``, ``margin``, ``points``, ``parallel`` of
        :func:`framed_camera` (``points``: frame the data's points, tighter than the corners
        of ``bounds``).
    """
    if up_axis not in _AXES:
        raise InputError(f"up_axis: expected 'x', 'y' or 'z', got {up_axis!r}")
    if not 0.0 < elevation <= 90.0:
        raise InputError(f"elevation: expected degrees in (0, 90], got {elevation!r}")
    k = _AXES[up_axis]
    up, front, side = np.eye(3)[k], np.eye(3)[(k + 1) % 3], np.eye(3)[(k + 2) % 3]
    el, az = np.radians(elevation), np.radians(azimuth)
    direction = np.cos(el) * (np.cos(az) * front + np.sin(az) * side) + np.sin(el) * up
    # Straight down the axis, "up" in the image is the front axis.
    view_up = up if elevation < 90.0 else -front
    return framed_camera(bounds, direction, view_up, **kwargs)


def terrain_birdseye_camera(
    bounds: Sequence[float],
    *,
    azimuth: float = 135.0,
    elevation: float = 35.0,
    view_angle: float = 30.0,
    aspect: float = 4 / 3,
    margin: float = 1.0 - FILL,
    points: np.ndarray | None = None,
) -> Camera:
    """A perspective camera looking down on a terrain from a compass direction, framed by the
    one rule (the terrain's projected box centred, filling :data:`FILL` of the image).

    Parameters
    ----------
    bounds : (xmin, xmax, ymin, ymax, zmin, zmax)
        Of the surface, with +x east, +y north and +z up (as ``pyvista.DataSet.bounds``).
    azimuth : float, default: 135.0
        Compass direction of the eye seen from the centre, in degrees clockwise from north
        (GDAL's convention); 135 is south-east.
    elevation : float, default: 35.0
        Angle of the line of sight above the horizontal, in degrees (0 < elevation < 90).
    view_angle : float, default: 30.0
        The camera's vertical view angle (VTK's default), which the distance is fitted to.
    aspect : float, default: 4/3
        Width / height of the image.
    margin : float, default: 0.15
        Empty part of the limiting image dimension (see :func:`framed_camera`).
    points : (N, 3) array, optional
        The surface's points (valid ground only): framed instead of the corners of
        ``bounds``, which would leave the far edge's empty corners in the picture.

    Returns
    -------
    position, focal_point, view_up : tuple of float
        As accepted by :func:`sciviz_gbuf.capture`'s ``camera``.
    """
    if not 0.0 < elevation < 90.0:
        raise InputError(f"elevation: expected degrees in (0, 90), got {elevation!r}")
    az, el = np.radians(azimuth), np.radians(elevation)
    to_eye = (np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el))
    return framed_camera(
        bounds, to_eye, (0.0, 0.0, 1.0), view_angle=view_angle, aspect=aspect, margin=margin,
        points=points,
    )  # fmt: skip


def named_view_camera(
    points: np.ndarray,
    view: str,
    *,
    aspect: float = 4 / 3,
    up: str | None = None,
    view_angle: float = 30.0,
    margin: float = 1.0 - FILL,
    parallel: bool = False,
) -> Camera:
    """PyVista's named view (``"iso"``, ``"xy"``, ... as :func:`~sciviz_gbuf.capture` takes
    them) framed on ``points`` by the one rule (:func:`framed_camera`), so the object fills
    the picture instead of its bounding sphere.

    Parameters
    ----------
    points : (N, 3) array
    view : str
        One of :data:`~sciviz_gbuf.core.camera.VIEWS`.
    aspect : float, default: 4/3
        Width / height of the image.
    up : {"x", "y", "z"}, optional
        The world axis upright in the ``"iso"`` view (the eye at +x +y +z, above the object
        whichever axis is up); default ``"z"``. The planar views (``"xy"``, ``"xz"``, ...)
        show their plane as named, first axis to the right and second up, whatever ``up``.
    view_angle, margin, parallel
        As in :func:`framed_camera`.
    """
    if view not in VIEWS:
        raise InputError(f"view: expected one of {sorted(VIEWS)}, got {view!r}")
    direction, view_up = VIEWS[view]
    if view == "iso" and up is not None:
        view_up = tuple(np.eye(3)[_AXES[check_up(up)]])
    return framed_camera(
        (), direction, view_up, aspect=aspect, points=points, view_angle=view_angle,
        margin=margin, parallel=parallel,
    )  # fmt: skip
