"""Per-pixel kernels that turn a triangle-index image into float G-buffers.

For every covered pixel the ray through the pixel centre (from the camera's own world->clip
matrix) is intersected in float64 with the triangle the rasteriser found there
(Moeller & Trumbore 1997). The hit point gives world coordinates and linear depth; its
barycentric coordinates interpolate normals, texture coordinates and point scalars exactly
as a perspective-correct rasteriser would, but without its float32 round-off.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .bands import run_bands

__all__ = [
    "accumulate_codes",
    "interpolate_points",
    "labels_and_sz",
    "labels_and_sz_into",
    "lookup_cells",
    "resolve_hits",
    "resolve_hits_into",
]

# Barycentric overshoot beyond which the hit is clamped onto the triangle. Below it, a pixel
# centre just outside the exact triangle is the rasteriser's sub-pixel vertex snapping.
_MAX_OVERSHOOT = 0.5


def accumulate_codes(px, shift, out):
    """OR the 24-bit RGB codes of a bottom-up (H, W, 3) uint8 readback into ``out`` (row 0 on
    top), shifted left by ``shift`` bits."""
    run_bands(_codes_rows, out.shape[0], px, shift, out)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _codes_rows(r0, r1, px, shift, out):
    """Rows ``r0 .. r1`` of :func:`accumulate_codes` (one band of :func:`.run_bands`)."""
    h, w = out.shape
    for r in range(r0, r1):
        src = h - 1 - r
        for c in range(w):
            code = (
                np.int64(px[src, c, 0])
                | (np.int64(px[src, c, 1]) << 8)
                | (np.int64(px[src, c, 2]) << 16)
            )
            out[r, c] |= code << shift


@njit(inline="always", cache=True)
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


def resolve_hits(tid, points, triangles, normals, inv_clip, eye, view_dir, rot, parallel):
    """World position, depth, eye-space normal and barycentrics per pixel (new arrays; see
    :func:`resolve_hits_into`)."""
    h, w = tid.shape
    world = np.empty((h, w, 3), dtype=np.float32)
    depth = np.empty((h, w), dtype=np.float32)
    nrm = np.empty((h, w, 3), dtype=np.float32)
    bary = np.empty((h, w, 3), dtype=np.float32)
    resolve_hits_into(
        tid, points, triangles, normals, inv_clip, eye, view_dir, rot, parallel,
        world, depth, nrm, bary,
    )  # fmt: skip
    return world, depth, nrm, bary


def resolve_hits_into(
    tid, points, triangles, normals, inv_clip, eye, view_dir, rot, parallel, world, depth, nrm, bary
):
    """World position, depth, eye-space normal and barycentrics per pixel, into the given
    arrays (every pixel written: a capture session reuses them frame after frame).

    Parameters
    ----------
    tid : (H, W) int64, triangle index per pixel, -1 for background, row 0 on top.
    points : (n, 3) float64 world points; triangles : (m, 3) int64; normals : (n, 3) float32.
    inv_clip : (4, 4) float64 clip -> world matrix.
    eye, view_dir : (3,) float64 camera position and unit viewing direction.
    rot : (3, 3) float64 world -> eye rotation.
    parallel : bool, orthographic camera.

    world (H, W, 3) f32, depth (H, W) f32, normal (H, W, 3) f32, bary (H, W, 3) f32
        The outputs; NaN on background.
    """
    run_bands(
        _hits_rows, tid.shape[0], tid, points, triangles, normals, inv_clip, eye, view_dir, rot,
        parallel, world, depth, nrm, bary,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _hits_rows(
    r0, r1, tid, points, triangles, normals, inv_clip, eye, view_dir, rot, parallel, world, depth,
    nrm, bary,
):  # fmt: skip
    """Rows ``r0 .. r1`` of :func:`resolve_hits_into` (one band of :func:`.run_bands`)."""
    h, w = tid.shape
    nan = np.float32(np.nan)
    m = inv_clip
    for r in range(r0, r1):
        yn = 2.0 * ((h - 1 - r) + 0.5) / h - 1.0
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                depth[r, c] = nan
                for k in range(3):
                    world[r, c, k] = nan
                    nrm[r, c, k] = nan
                    bary[r, c, k] = nan
                continue
            xn = 2.0 * (c + 0.5) / w - 1.0
            # unproject the pixel centre at the near (z=-1) and far (z=+1) planes
            h0 = m[3, 0] * xn + m[3, 1] * yn - m[3, 2] + m[3, 3]
            h1 = m[3, 0] * xn + m[3, 1] * yn + m[3, 2] + m[3, 3]
            bx = m[0, 0] * xn + m[0, 1] * yn + m[0, 3]
            by = m[1, 0] * xn + m[1, 1] * yn + m[1, 3]
            bz = m[2, 0] * xn + m[2, 1] * yn + m[2, 3]
            ox, oy, oz = (bx - m[0, 2]) / h0, (by - m[1, 2]) / h0, (bz - m[2, 2]) / h0
            dx = (bx + m[0, 2]) / h1 - ox
            dy = (by + m[1, 2]) / h1 - oy
            dz = (bz + m[2, 2]) / h1 - oz
            i0 = triangles[t, 0]
            i1 = triangles[t, 1]
            i2 = triangles[t, 2]
            v0x, v0y, v0z = points[i0, 0], points[i0, 1], points[i0, 2]
            e1x, e1y, e1z = points[i1, 0] - v0x, points[i1, 1] - v0y, points[i1, 2] - v0z
            e2x, e2y, e2z = points[i2, 0] - v0x, points[i2, 1] - v0y, points[i2, 2] - v0z
            px, py, pz = _cross(dx, dy, dz, e2x, e2y, e2z)
            det = e1x * px + e1y * py + e1z * pz
            gx, gy, gz = _cross(e1x, e1y, e1z, e2x, e2y, e2z)
            b1 = 1.0 / 3.0
            b2 = 1.0 / 3.0
            tt = np.nan
            if det != 0.0:
                tx, ty, tz = ox - v0x, oy - v0y, oz - v0z
                inv_det = 1.0 / det
                b1 = (tx * px + ty * py + tz * pz) * inv_det
                qx, qy, qz = _cross(tx, ty, tz, e1x, e1y, e1z)
                b2 = (dx * qx + dy * qy + dz * qz) * inv_det
                tt = (e2x * qx + e2y * qy + e2z * qz) * inv_det
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
                x = v0x + b1 * e1x + b2 * e2x
                y = v0y + b1 * e1y + b2 * e2y
                z = v0z + b1 * e1z + b2 * e2z
            else:
                # a small overshoot is the rasteriser's sub-pixel snapping: stay on the ray and
                # extrapolate attributes consistently with the position
                x = ox + tt * dx
                y = oy + tt * dy
                z = oz + tt * dz
            world[r, c, 0] = x
            world[r, c, 1] = y
            world[r, c, 2] = z
            depth[r, c] = (
                (x - eye[0]) * view_dir[0] + (y - eye[1]) * view_dir[1] + (z - eye[2]) * view_dir[2]
            )
            bary[r, c, 0] = b0
            bary[r, c, 1] = b1
            bary[r, c, 2] = b2
            nx = b0 * normals[i0, 0] + b1 * normals[i1, 0] + b2 * normals[i2, 0]
            ny = b0 * normals[i0, 1] + b1 * normals[i1, 1] + b2 * normals[i2, 1]
            nz = b0 * normals[i0, 2] + b1 * normals[i1, 2] + b2 * normals[i2, 2]
            # the shading normal takes the side of the geometric normal, then both face the eye
            sign = 1.0 if nx * gx + ny * gy + nz * gz >= 0.0 else -1.0
            if parallel:
                facing = -(gx * view_dir[0] + gy * view_dir[1] + gz * view_dir[2])
            else:
                facing = gx * (eye[0] - x) + gy * (eye[1] - y) + gz * (eye[2] - z)
            if facing < 0.0:
                sign = -sign
                gx, gy, gz = -gx, -gy, -gz
            nx, ny, nz = sign * nx, sign * ny, sign * nz
            ln = np.sqrt(nx * nx + ny * ny + nz * nz)
            if not ln > 1e-12:
                # opposite vertex normals cancelled: fall back to the facet's own normal
                nx, ny, nz = gx, gy, gz
                ln = np.sqrt(nx * nx + ny * ny + nz * nz)
            for k in range(3):
                nrm[r, c, k] = (rot[k, 0] * nx + rot[k, 1] * ny + rot[k, 2] * nz) / ln


def labels_and_sz(tid, depth, tri_obj, tri_cell, dist, pixel, parallel):
    """Object id, cell id and Saito's sz (1990 Eq. 6) per pixel, in one pass.

    ``sz = d**2 / (w z_v)``; for a parallel projection its first-order expansion about the focal
    plane, ``(2 d - z_v) / w`` (see :meth:`CameraInfo.sz_from_depth`).
    """
    h, w = tid.shape
    obj = np.empty((h, w), dtype=np.int32)
    cell = np.empty((h, w), dtype=np.int64)
    sz = np.empty((h, w), dtype=np.float32)
    labels_and_sz_into(tid, depth, tri_obj, tri_cell, dist, pixel, parallel, obj, cell, sz)
    return obj, cell, sz


def labels_and_sz_into(tid, depth, tri_obj, tri_cell, dist, pixel, parallel, obj, cell, sz):
    """:func:`labels_and_sz` into the given arrays (every pixel written)."""
    run_bands(
        _labels_rows, tid.shape[0], tid, depth, tri_obj, tri_cell, dist, pixel, parallel, obj,
        cell, sz,
    )  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _labels_rows(r0, r1, tid, depth, tri_obj, tri_cell, dist, pixel, parallel, obj, cell, sz):
    """Rows ``r0 .. r1`` of :func:`labels_and_sz_into` (one band of :func:`.run_bands`)."""
    w = tid.shape[1]
    for r in range(r0, r1):
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                obj[r, c] = -1
                cell[r, c] = -1
                sz[r, c] = np.nan
                continue
            obj[r, c] = tri_obj[t]
            cell[r, c] = tri_cell[t]
            z = np.float64(depth[r, c])
            if parallel:
                sz[r, c] = (2.0 * dist - z) / pixel
            else:
                sz[r, c] = dist * dist / (pixel * z)


def interpolate_points(tid, bary, triangles, values):
    """Barycentric interpolation of point values (n, k) float64 -> (H, W, k) float32."""
    h, w = tid.shape
    out = np.full((h, w, values.shape[1]), np.nan, dtype=np.float32)
    run_bands(_interpolate_rows, h, tid, bary, triangles, values, out)
    return out


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _interpolate_rows(r0, r1, tid, bary, triangles, values, out):
    """Rows ``r0 .. r1`` of :func:`interpolate_points` into ``out`` (NaN where it stays)."""
    w = tid.shape[1]
    k = values.shape[1]
    for r in range(r0, r1):
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


def lookup_cells(tid, values):
    """Per-triangle values (m, k) float32 -> (H, W, k) float32 by triangle index."""
    h, w = tid.shape
    out = np.full((h, w, values.shape[1]), np.nan, dtype=np.float32)
    run_bands(_lookup_rows, h, tid, values, out)
    return out


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _lookup_rows(r0, r1, tid, values, out):
    """Rows ``r0 .. r1`` of :func:`lookup_cells` into ``out`` (NaN where it stays)."""
    w = tid.shape[1]
    k = values.shape[1]
    for r in range(r0, r1):
        for c in range(w):
            t = tid[r, c]
            if t < 0:
                continue
            for j in range(k):
                out[r, c, j] = values[t, j]
