"""Numba kernels of :mod:`.frame`: G-buffers from the depth image of a rendered frame.

The window's depth ``d`` in [0, 1] is unprojected with the camera's own clip matrix into the
linear depth along the viewing axis (as :mod:`._capture_kernels` measures it), Saito's ``sz``
(1990 Eq. 6) follows from it, and the normals come from the eye-space positions of the pixel
and its neighbours: per axis, the one-sided difference towards the side that continues the
surface (the smaller second difference of ``sz``, which is linear on planes in screen space),
so a pixel next to a crease or a profile takes its own face's normal, not an average across.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .bands import run_bands

__all__ = ["frame_buffers"]

_HUGE = 1e300


@njit(inline="always", cache=True)
def _pos(depth, r, c, h, w, parallel, inv_d, inv_w):
    """Eye-space position of pixel (r, c) in pixel units (``edges``' ``_eye``)."""
    z = np.float64(depth[r, c])
    k = 1.0 if parallel else z * inv_d
    return (c + 0.5 - 0.5 * w) * k, (0.5 * h - r - 0.5) * k, -z * inv_w


@njit(inline="always", cache=True)
def _side_error(sz, mask, r1, c1, r2, c2, x, h, w):
    """How well the neighbour at (r1, c1) continues the surface of a pixel with ``sz`` x:
    the second difference with the one beyond it (r2, c2), or the first difference if that
    one is missing; ``_HUGE`` if the neighbour itself is missing."""
    if r1 < 0 or r1 >= h or c1 < 0 or c1 >= w or not mask[r1, c1]:
        return _HUGE
    s1 = np.float64(sz[r1, c1])
    if r2 < 0 or r2 >= h or c2 < 0 or c2 >= w or not mask[r2, c2]:
        return abs(s1 - x) * 1e6  # (a first difference: only if no side has a second one)
    return abs(2.0 * s1 - x - np.float64(sz[r2, c2]))


def frame_buffers(z, p22, p23, p32, p33, parallel, dist, pixel, depth, sz, normal, mask):
    """``depth``, ``sz``, ``normal`` (NaN off the surface) and ``mask`` (H, W) of the window
    depth image ``z`` (H, W), bottom row first as OpenGL reads it; row 0 of the outputs is
    the top row. ``p22 .. p33``: the clip matrix's depth rows (row-major indices [2, 2],
    [2, 3], [3, 2], [3, 3]); ``dist``, ``pixel``: ``CameraInfo.distance``, ``.pixel_size``.
    A depth of 1 (the far plane, where nothing was drawn) or not in [0, 1) is background.

    Two passes over bands of rows: the normals read the depths of rows beyond their band, so
    they start once every band of the depths has ended.
    """
    h = depth.shape[0]
    run_bands(_depth_rows, h, z, p22, p23, p32, p33, parallel, dist, pixel, depth, sz, mask)
    run_bands(_normal_rows, h, parallel, dist, pixel, depth, sz, normal, mask)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _depth_rows(r0, r1, z, p22, p23, p32, p33, parallel, dist, pixel, depth, sz, mask):
    """Rows ``r0 .. r1`` of ``depth``, ``sz`` and ``mask`` (one band of :func:`.run_bands`)."""
    h, w = depth.shape
    nan = np.float32(np.nan)
    for r in range(r0, r1):
        r = np.int64(r)
        src = h - 1 - r
        for c in range(w):
            d = np.float64(z[src, c])
            ok = d >= 0.0 and d < 1.0
            e = 0.0
            if ok:
                zn = 2.0 * d - 1.0  # NDC depth (glDepthRange 0..1)
                e = -(p23 - zn * p33) / (zn * p32 - p22)
                ok = e > 0.0 and e < _HUGE
            if ok:
                e32 = np.float32(e)
                zz = np.float64(e32)  # sz of the stored depth, as capture computes it
                depth[r, c] = e32
                sz[r, c] = (
                    np.float32((2.0 * dist - zz) / pixel)
                    if parallel
                    else np.float32(dist * dist / (pixel * zz))
                )
            else:
                depth[r, c] = nan
                sz[r, c] = nan
            mask[r, c] = ok


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _normal_rows(r0, r1, parallel, dist, pixel, depth, sz, normal, mask):
    """Rows ``r0 .. r1`` of ``normal``, from the whole of ``depth``, ``sz`` and ``mask``."""
    h, w = depth.shape
    nan = np.float32(np.nan)
    inv_d = 1.0 / dist
    inv_w = 1.0 / pixel
    for r in range(r0, r1):
        r = np.int64(r)
        for c in range(w):
            if not mask[r, c]:
                normal[r, c, 0] = nan
                normal[r, c, 1] = nan
                normal[r, c, 2] = nan
                continue
            x = np.float64(sz[r, c])
            px, py, pz = _pos(depth, r, c, h, w, parallel, inv_d, inv_w)
            # along the row (+x) ...
            ef = _side_error(sz, mask, r, c + 1, r, c + 2, x, h, w)
            eb = _side_error(sz, mask, r, c - 1, r, c - 2, x, h, w)
            tx, ty, tz = 1.0, 0.0, 0.0
            if ef < _HUGE and ef <= eb:
                qx, qy, qz = _pos(depth, r, c + 1, h, w, parallel, inv_d, inv_w)
                tx, ty, tz = qx - px, qy - py, qz - pz
            elif eb < _HUGE:
                qx, qy, qz = _pos(depth, r, c - 1, h, w, parallel, inv_d, inv_w)
                tx, ty, tz = px - qx, py - qy, pz - qz
            # ... and up the column (+y is the row above)
            ef = _side_error(sz, mask, r - 1, c, r - 2, c, x, h, w)
            eb = _side_error(sz, mask, r + 1, c, r + 2, c, x, h, w)
            ux, uy, uz = 0.0, 1.0, 0.0
            if ef < _HUGE and ef <= eb:
                qx, qy, qz = _pos(depth, r - 1, c, h, w, parallel, inv_d, inv_w)
                ux, uy, uz = qx - px, qy - py, qz - pz
            elif eb < _HUGE:
                qx, qy, qz = _pos(depth, r + 1, c, h, w, parallel, inv_d, inv_w)
                ux, uy, uz = px - qx, py - qy, pz - qz
            # the screen's orientation is kept: x right, y up gives a normal towards the viewer
            nx = ty * uz - tz * uy
            ny = tz * ux - tx * uz
            nz = tx * uy - ty * ux
            n = math.sqrt(nx * nx + ny * ny + nz * nz)
            if not (n > 0.0 and n < _HUGE):
                nx, ny, nz, n = 0.0, 0.0, 1.0, 1.0
            normal[r, c, 0] = np.float32(nx / n)
            normal[r, c, 1] = np.float32(ny / n)
            normal[r, c, 2] = np.float32(nz / n)
