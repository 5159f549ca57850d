"""Per-pixel kernels that turn a triangle-index image into float G-buffers.

For every covered pixel the ray through the pixel centre (from the camera's own world->clip
matrix) is intersected in float64 with the triangle the rasteriser found there
(Moeller & Trumbore 1997). The hit point gives world coordinates and linear depth; its
barycentric coordinates interpolate normals, texture coordinates and point scalars exactly
as a perspective-correct rasteriser would, but without its float32 round-off.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["interpolate_points", "lookup_cells", "resolve_hits"]

# Barycentric overshoot beyond which the hit is clamped onto the triangle. Below it, a pixel
# centre just outside the exact triangle is the rasteriser's sub-pixel vertex snapping.
_MAX_OVERSHOOT = 0.5


@njit(parallel=True, cache=True)
def resolve_hits(tid, points, triangles, normals, inv_clip, eye, view_dir, rot, parallel):
    """World position, depth, eye-space normal and barycentrics per pixel.

    Parameters
    ----------
    tid : (H, W) int64, triangle index per pixel, -1 for background, row 0 on top.
    points : (n, 3) float64 world points; triangles : (m, 3) int64; normals : (n, 3) float32.
    inv_clip : (4, 4) float64 clip -> world matrix.
    eye, view_dir : (3,) float64 camera position and unit viewing direction.
    rot : (3, 3) float64 world -> eye rotation.
    parallel : bool, orthographic camera.

    Returns
    -------
    world (H, W, 3) f32, depth (H, W) f32, normal (H, W, 3) f32, bary (H, W, 3) f32;
    NaN on background.
    """
    h, w = tid.shape
    world = np.full((h, w, 3), np.nan, dtype=np.float32)
    depth = np.full((h, w), np.nan, dtype=np.float32)
    nrm = np.full((h, w, 3), np.nan, dtype=np.float32)
    bary = np.full((h, w, 3), np.nan, dtype=np.float32)
    for r in prange(h):
        yn = 2.0 * ((h - 1 - r) + 0.5) / h - 1.0
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                continue
            xn = 2.0 * (c + 0.5) / w - 1.0
            # unproject the pixel centre at the near and far planes
            p0 = np.empty(3)
            p1 = np.empty(3)
            hw0 = inv_clip[3, 0] * xn + inv_clip[3, 1] * yn - inv_clip[3, 2] + inv_clip[3, 3]
            hw1 = inv_clip[3, 0] * xn + inv_clip[3, 1] * yn + inv_clip[3, 2] + inv_clip[3, 3]
            for k in range(3):
                base = inv_clip[k, 0] * xn + inv_clip[k, 1] * yn + inv_clip[k, 3]
                p0[k] = (base - inv_clip[k, 2]) / hw0
                p1[k] = (base + inv_clip[k, 2]) / hw1
            d = p1 - p0
            i0 = triangles[t, 0]
            i1 = triangles[t, 1]
            i2 = triangles[t, 2]
            v0 = points[i0]
            e1 = points[i1] - v0
            e2 = points[i2] - v0
            pv = np.array(
                [
                    d[1] * e2[2] - d[2] * e2[1],
                    d[2] * e2[0] - d[0] * e2[2],
                    d[0] * e2[1] - d[1] * e2[0],
                ]
            )
            det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2]
            g = np.array(
                [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ]
            )
            b1 = 1.0 / 3.0
            b2 = 1.0 / 3.0
            tt = np.nan
            if det != 0.0:
                tv = p0 - v0
                inv_det = 1.0 / det
                b1 = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv_det
                q = np.array(
                    [
                        tv[1] * e1[2] - tv[2] * e1[1],
                        tv[2] * e1[0] - tv[0] * e1[2],
                        tv[0] * e1[1] - tv[1] * e1[0],
                    ]
                )
                b2 = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv_det
                tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv_det
            b0 = 1.0 - b1 - b2
            if np.isnan(tt) or min(b0, min(b1, b2)) < -_MAX_OVERSHOOT:
                # clamp onto the triangle: never extrapolate far along a grazing plane
                b0 = max(b0, 0.0)
                b1 = max(b1, 0.0)
                b2 = max(b2, 0.0)
                s = b0 + b1 + b2
                b0 /= s
                b1 /= s
                b2 /= s
                x = v0 + b1 * e1 + b2 * e2
            else:
                # a small overshoot is the rasteriser's sub-pixel snapping: stay on the ray and
                # extrapolate attributes consistently with the position
                x = p0 + tt * d
            c0 = b0
            c1 = b1
            c2 = b2
            dep = 0.0
            for k in range(3):
                world[r, c, k] = x[k]
                dep += (x[k] - eye[k]) * view_dir[k]
            depth[r, c] = dep
            bary[r, c, 0] = c0
            bary[r, c, 1] = c1
            bary[r, c, 2] = c2
            n = np.empty(3)
            for k in range(3):
                n[k] = c0 * normals[i0, k] + c1 * normals[i1, k] + c2 * normals[i2, k]
            # the shading normal takes the side of the geometric normal, then both face the eye
            if n[0] * g[0] + n[1] * g[1] + n[2] * g[2] < 0.0:
                n = -n
            if parallel:
                facing = -(g[0] * view_dir[0] + g[1] * view_dir[1] + g[2] * view_dir[2])
            else:
                facing = g[0] * (eye[0] - x[0]) + g[1] * (eye[1] - x[1]) + g[2] * (eye[2] - x[2])
            if facing < 0.0:
                n = -n
                g = -g
            ln = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            if not ln > 1e-12:
                n = g
                ln = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            for k in range(3):
                nrm[r, c, k] = (rot[k, 0] * n[0] + rot[k, 1] * n[1] + rot[k, 2] * n[2]) / ln
    return world, depth, nrm, bary


@njit(parallel=True, cache=True)
def labels_and_sz(tid, depth, tri_obj, tri_cell, dist, pixel, parallel):
    """Object id, cell id and Saito's sz (1990 Eq. 6) per pixel, in one pass.

    ``sz = d**2 / (w z_v)``; for a parallel projection its first-order expansion about the focal
    plane, ``(2 d - z_v) / w`` (see :meth:`CameraInfo.sz_from_depth`).
    """
    h, w = tid.shape
    obj = np.full((h, w), -1, dtype=np.int32)
    cell = np.full((h, w), -1, dtype=np.int64)
    sz = np.full((h, w), np.nan, dtype=np.float32)
    for r in prange(h):
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                continue
            obj[r, c] = tri_obj[t]
            cell[r, c] = tri_cell[t]
            z = np.float64(depth[r, c])
            if parallel:
                sz[r, c] = (2.0 * dist - z) / pixel
            else:
                sz[r, c] = dist * dist / (pixel * z)
    return obj, cell, sz


@njit(parallel=True, cache=True)
def interpolate_points(tid, bary, triangles, values):
    """Barycentric interpolation of point values (n, k) float64 -> (H, W, k) float32."""
    h, w = tid.shape
    k = values.shape[1]
    out = np.full((h, w, k), np.nan, dtype=np.float32)
    for r in prange(h):
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                continue
            i0 = triangles[t, 0]
            i1 = triangles[t, 1]
            i2 = triangles[t, 2]
            for j in range(k):
                acc = np.float64(bary[r, c, 0]) * values[i0, j]
                acc += np.float64(bary[r, c, 1]) * values[i1, j]
                acc += np.float64(bary[r, c, 2]) * values[i2, j]
                out[r, c, j] = acc
    return out


@njit(parallel=True, cache=True)
def lookup_cells(tid, values):
    """Per-triangle values (m, k) float32 -> (H, W, k) float32 by triangle index."""
    h, w = tid.shape
    k = values.shape[1]
    out = np.full((h, w, k), np.nan, dtype=np.float32)
    for r in prange(h):
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                continue
            for j in range(k):
                out[r, c, j] = values[t, j]
    return out
