"""Independent (hand-derived) pinhole geometry to check captures against; shares no code with
the package."""

from __future__ import annotations

import numpy as np
from scipy import ndimage


def camera_basis(cam):
    """Unit (direction, right, up) of a CameraInfo, from its position/focal point/view up only."""
    d = np.subtract(cam.focal_point, cam.position)
    d = d / np.linalg.norm(d)
    right = np.cross(d, cam.view_up)
    right /= np.linalg.norm(right)
    up = np.cross(right, d)
    return d, right, up


def rays_by_hand(cam):
    """Ray origins and unit directions through pixel centres (row 0 on top), float64.

    Textbook pinhole / orthographic camera from the view angle or parallel scale; shares no code
    with the package.
    """
    w, h = cam.window_size
    d, right, up = camera_basis(cam)
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2
    xx, yy = np.meshgrid(x, y)
    aspect = w / h
    eye = np.asarray(cam.position, dtype=np.float64)
    if cam.parallel_projection:
        s = cam.parallel_scale
        origin = eye + (xx[..., None] * s * aspect) * right + (yy[..., None] * s) * up
        direction = np.broadcast_to(d, origin.shape).copy()
    else:
        t = np.tan(np.radians(cam.view_angle) / 2)
        direction = d + (xx[..., None] * t * aspect) * right + (yy[..., None] * t) * up
        direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
        origin = np.broadcast_to(eye, direction.shape).copy()
    return origin, direction


def to_eye(cam, v):
    """World vectors -> eye space (x right, y up, z towards the viewer)."""
    d, right, up = camera_basis(cam)
    return np.stack([v @ right, v @ up, -(v @ d)], axis=-1)


def angle_deg(a, b):
    """Angle between vectors in degrees; atan2 form (arccos of a dot product near 1 is
    ill-conditioned: float32 rounding alone would read as 0.01 degree)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.degrees(np.arctan2(cross, np.sum(a * b, axis=-1)))


def interior(mask, px: int = 1):
    """Covered pixels at least ``px`` pixels away from any uncovered pixel or the image border."""
    padded = np.pad(mask, px, constant_values=False)
    return ndimage.binary_erosion(padded, np.ones((2 * px + 1, 2 * px + 1)))[px:-px, px:-px]
