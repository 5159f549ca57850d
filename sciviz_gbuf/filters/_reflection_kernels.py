"""Per-pixel kernels of :mod:`.reflection`: the reflection angle and its gradient."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["theta_image", "wrapped_gradient"]

_PI = np.float32(np.pi)
_TWO_PI = np.float32(2.0 * np.pi)


@njit(inline="always", cache=True)
def _wrap(d):
    # a difference of two angles in [-pi, pi) lies in (-2 pi, 2 pi): one turn at most brings
    # it back across the branch cut of arctan2
    if d >= _PI:
        return d - _TWO_PI
    if d < -_PI:
        return d + _TWO_PI
    return d


def theta_image(normal, world, mask, rot, eye, view_dir, parallel, reflect, e1, e2, phase, out):
    """``theta - phase`` wrapped into [-pi, pi) per pixel, NaN off the mask.

    ``normal`` are eye-space normals; ``rot`` the view matrix's rotation (world normal =
    ``normal @ rot``); ``reflect``: the reflected view ray, else the normal itself. All float32
    (``phase`` in [-pi, pi]).
    """
    run_bands(
        _theta_rows, mask.shape[0], normal, world, mask, rot, eye, view_dir, parallel, reflect,
        e1, e2, phase, out,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _theta_rows(r0, r1, normal, world, mask, rot, eye, view_dir, parallel, reflect, e1, e2, phase,
                out):  # fmt: skip
    """Rows ``r0 .. r1`` of :func:`theta_image` (one band of :func:`.run_bands`)."""
    w = mask.shape[1]
    for r in range(r0, r1):
        for c in range(w):
            if not mask[r, c]:
                out[r, c] = np.nan
                continue
            nx = normal[r, c, 0] * rot[0, 0] + normal[r, c, 1] * rot[1, 0]
            nx += normal[r, c, 2] * rot[2, 0]
            ny = normal[r, c, 0] * rot[0, 1] + normal[r, c, 1] * rot[1, 1]
            ny += normal[r, c, 2] * rot[2, 1]
            nz = normal[r, c, 0] * rot[0, 2] + normal[r, c, 1] * rot[1, 2]
            nz += normal[r, c, 2] * rot[2, 2]
            if reflect:
                if parallel:
                    dx, dy, dz = view_dir[0], view_dir[1], view_dir[2]
                else:
                    dx = world[r, c, 0] - eye[0]
                    dy = world[r, c, 1] - eye[1]
                    dz = world[r, c, 2] - eye[2]
                    length = np.sqrt(dx * dx + dy * dy + dz * dz)
                    if length > 0:
                        dx, dy, dz = dx / length, dy / length, dz / length
                dn = np.float32(2.0) * (dx * nx + dy * ny + dz * nz)
                vx, vy, vz = dx - dn * nx, dy - dn * ny, dz - dn * nz
            else:
                vx, vy, vz = nx, ny, nz
            a = vx * e1[0] + vy * e1[1] + vz * e1[2]
            b = vx * e2[0] + vy * e2[1] + vz * e2[2]
            out[r, c] = _wrap(np.arctan2(b, a) - phase)


def wrapped_gradient(theta, out):
    """|grad theta| per pixel, central differences taken modulo 2 pi (one-sided beside NaN and
    the border; 0 where both sides are missing)."""
    run_bands(_gradient_rows, theta.shape[0], theta, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _gradient_rows(r0, r1, theta, out):
    """Rows ``r0 .. r1`` of :func:`wrapped_gradient`."""
    h, w = theta.shape
    for r in range(r0, r1):
        for c in range(w):
            t = theta[r, c]
            if np.isnan(t):
                out[r, c] = 0.0
                continue
            gx = np.float32(0.0)
            n = 0
            if c + 1 < w and not np.isnan(theta[r, c + 1]):
                gx += _wrap(theta[r, c + 1] - t)
                n += 1
            if c > 0 and not np.isnan(theta[r, c - 1]):
                gx += _wrap(t - theta[r, c - 1])
                n += 1
            if n > 0:
                gx /= n
            gy = np.float32(0.0)
            n = 0
            if r + 1 < h and not np.isnan(theta[r + 1, c]):
                gy += _wrap(theta[r + 1, c] - t)
                n += 1
            if r > 0 and not np.isnan(theta[r - 1, c]):
                gy += _wrap(t - theta[r - 1, c])
                n += 1
            if n > 0:
                gy /= n
            out[r, c] = np.sqrt(gx * gx + gy * gy)
