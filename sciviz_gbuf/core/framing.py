"""Cameras that frame a bounding box: pick a viewing direction, get the closest eye position."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from .camera import VIEWS

__all__ = ["framed_camera", "named_view_camera", "oblique_camera", "terrain_birdseye_camera"]

_AXES = {"x": 0, "y": 1, "z": 2}

Camera = tuple[tuple[float, ...], tuple[float, ...], tuple[float, float, float]]


def framed_camera(
    bounds: Sequence[float],
    direction: Sequence[float],
    view_up: Sequence[float],
    *,
    view_angle: float = 30.0,
    aspect: float = 4 / 3,
    margin: float = 0.05,
    points: np.ndarray | None = None,
) -> Camera:
    """A perspective camera looking at the centre of ``bounds``, as close as it can be.

    Parameters
    ----------
    bounds : (xmin, xmax, ymin, ymax, zmin, zmax)
        As ``pyvista.DataSet.bounds``.
    direction : 3 floats
        From the centre of ``bounds`` towards the eye (any length).
    view_up : 3 floats
        World direction that should point up in the image; must not be parallel to
        ``direction``.
    view_angle : float, default: 30.0
        The camera's vertical view angle in degrees (VTK's default).
    aspect : float, default: 4/3
        Width / height of the image.
    margin : float, default: 0.05
        Empty border, as a fraction of the image's half width and half height.

    points : (N, 3) array, optional
        Frame these points instead of the corners of ``bounds`` (which is then ignored): a
        tighter fit for objects that fill their bounding box poorly.

    Returns
    -------
    position, focal_point, view_up : tuple of float
        As accepted by :func:`sciviz_gbuf.capture`'s ``camera``: all eight corners of
        ``bounds`` (or all ``points``) are in view.
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
    if points is None:
        lo = np.asarray(bounds[0::2], dtype=np.float64)
        hi = np.asarray(bounds[1::2], dtype=np.float64)
        centre = (lo + hi) / 2
        corners = np.array(np.meshgrid(*np.stack([lo, hi], axis=1))).reshape(3, -1).T - centre
    else:
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        pts = pts[np.isfinite(pts).all(axis=1)]
        if len(pts) == 0:
            raise InputError("points: expected at least one finite point to frame")
        # Centred on the view-plane extent of the points themselves, not of their box, so a
        # thin oblique object fills the picture.
        centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
        r, u = (pts - centre) @ right, (pts - centre) @ up
        centre = centre + right * (r.min() + r.max()) / 2 + up * (u.min() + u.max()) / 2
        corners = pts - centre
    tan_v = np.tan(np.radians(view_angle) / 2) * (1.0 - margin)
    tan_h = tan_v * aspect
    # A corner at lateral offset r and height t towards the eye is in view once the eye is
    # farther than t + |r| / tan(half field of view) from the focal plane.
    toward = corners @ to_eye
    distance = max(
        np.max(toward + np.abs(corners @ right) / tan_h),
        np.max(toward + np.abs(corners @ up) / tan_v),
    )
    position = centre + distance * to_eye
    return tuple(position.tolist()), tuple(centre.tolist()), tuple(float(v) for v in world_up)


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
        ``view_angle``, ``aspect``, ``margin`` of :func:`framed_camera`.
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
    margin: float = 0.05,
) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, float, float]]:
    """A perspective camera looking down at the centre of ``bounds`` from a compass direction.

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
    margin : float, default: 0.05
        Empty border, as a fraction of the image's half width and half height.

    Returns
    -------
    position, focal_point, view_up : tuple of float
        As accepted by :func:`sciviz_gbuf.capture`'s ``camera``. The eye is as close as it can
        be with all eight corners of ``bounds`` in view.
    """
    if not 0.0 < elevation < 90.0:
        raise InputError(f"elevation: expected degrees in (0, 90), got {elevation!r}")
    az, el = np.radians(azimuth), np.radians(elevation)
    to_eye = (np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el))
    return framed_camera(
        bounds, to_eye, (0.0, 0.0, 1.0), view_angle=view_angle, aspect=aspect, margin=margin
    )


def named_view_camera(points: np.ndarray, view: str, *, aspect: float = 4 / 3) -> Camera:
    """PyVista's named view (``"iso"``, ``"xy"``, ... as :func:`~sciviz_gbuf.capture` takes
    them) framed tightly on ``points`` rather than on their bounding sphere, so the object fills
    the picture (VTK's default 30 degree view angle)."""
    if view not in VIEWS:
        raise InputError(f"view: expected one of {sorted(VIEWS)}, got {view!r}")
    direction, up = VIEWS[view]
    return framed_camera((), direction, up, aspect=aspect, points=points)
