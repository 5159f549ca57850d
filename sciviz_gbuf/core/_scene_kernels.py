"""Compiled mesh preparation of a capture: face normals, the corner test of the normal
splitting and the split normals themselves (:func:`sciviz_gbuf.core.scene.split_normals`).

The numpy statement of the same method (``tests/helpers/split_reference.py``) took 3.4 s of a
4 s capture of a 1M-triangle surface (``np.add.at``, einsum and an argsort over every
corner); these loops do it in one pass over the corners and one over the triangles around
each point, about 50x faster, with the same decisions and normals (tested against it).

Every output is allocated by the caller (the kernels run without numba's reference counting,
``_nrt=False``, like the band kernels). Geometry is float64 throughout: the points are
float64 world coordinates and the normals' angles are compared against the feature angle's
cosine, where float32 would move corners across the threshold.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "corner_adjacency",
    "face_normals_into",
    "point_bounds",
    "split_corners",
    "stale_point_normals",
    "triangle_heights",
]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def face_normals_into(points, triangles, face, area2):
    """Unit face normals (zero for zero-area triangles) and twice the areas, into ``face``
    (m, 3) and ``area2`` (m,)."""
    for t in range(triangles.shape[0]):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        ux = points[b, 0] - points[a, 0]
        uy = points[b, 1] - points[a, 1]
        uz = points[b, 2] - points[a, 2]
        vx = points[c, 0] - points[a, 0]
        vy = points[c, 1] - points[a, 1]
        vz = points[c, 2] - points[a, 2]
        nx = uy * vz - uz * vy
        ny = uz * vx - ux * vz
        nz = ux * vy - uy * vx
        length = np.sqrt(nx * nx + ny * ny + nz * nz)
        area2[t] = length
        if length > 0.0:
            face[t, 0] = nx / length
            face[t, 1] = ny / length
            face[t, 2] = nz / length
        else:
            face[t, 0] = 0.0
            face[t, 1] = 0.0
            face[t, 2] = 0.0


@njit(cache=True, nogil=True, _nrt=False)
def corner_adjacency(triangles, n_points, start, adj):
    """The corners around each point (CSR): corners ``adj[start[p]:start[p + 1]]`` (flat
    corner indices ``3 * triangle + k``, ascending) are those of point ``p``.

    ``start`` is (n_points + 1,), ``adj`` (3 m,). Returns False if a triangle names a point
    outside ``[0, n_points)`` (checked before: never expected)."""
    m = triangles.shape[0]
    for p in range(n_points + 1):
        start[p] = 0
    for t in range(m):
        for k in range(3):
            p = triangles[t, k]
            if p < 0 or p >= n_points:
                return False
            start[p + 1] += 1
    for p in range(n_points):
        start[p + 1] += start[p]
    # fill in ascending corner order, so each point's list is ascending (a stable argsort)
    for t in range(m):
        for k in range(3):
            p = triangles[t, k]
            adj[start[p]] = 3 * t + k
            start[p] += 1
    for p in range(n_points, 0, -1):
        start[p] = start[p - 1]
    start[0] = 0
    return True


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def stale_point_normals(unit, face, area2, start, adj, cos_limit, cos_half, sharp, out):
    """Point normals that no longer fit their faces, replaced by their faces' mean.

    A point is smooth when every two triangles around it lie within the feature angle of each
    other (``sharp[p]`` is set otherwise). At a smooth point the file's normal should be about
    the mean of its faces; one more than half the feature angle away from the area-weighted
    mean is stale (the points were moved after the normals were computed) and is replaced by
    that mean, on its own side. ``out`` (n, 3) starts as ``unit`` and gets the new normals.

    Returns the number of normals replaced.
    """
    n = start.shape[0] - 1
    replaced = 0
    for p in range(n):
        s0, s1 = start[p], start[p + 1]
        ux, uy, uz = unit[p, 0], unit[p, 1], unit[p, 2]
        # the faces' area-weighted mean, neighbours wound the other way (an inconsistent
        # file) counted on the normal's side
        ax = 0.0
        ay = 0.0
        az = 0.0
        for i in range(s0, s1):
            t = adj[i] // 3
            w = area2[t]
            if face[t, 0] * ux + face[t, 1] * uy + face[t, 2] * uz < 0.0:
                w = -w
            ax += face[t, 0] * w
            ay += face[t, 1] * w
            az += face[t, 2] * w
        length = np.sqrt(ax * ax + ay * ay + az * az)
        if length > 0.0:
            ax /= length
            ay /= length
            az /= length
        # Sharp or smooth: if every face lies within half the feature angle of the mean, any
        # two lie within the feature angle of each other (the angles add) and the point is
        # smooth without comparing pairs; only the rest (creases, corners) compare pairs.
        near_mean = length > 0.0
        for i in range(s0, s1):
            t = adj[i] // 3
            if area2[t] <= 0.0:
                continue
            if abs(face[t, 0] * ax + face[t, 1] * ay + face[t, 2] * az) < cos_half:
                near_mean = False
                break
        is_sharp = False
        if not near_mean:
            for i in range(s0, s1):
                ti = adj[i] // 3
                if area2[ti] <= 0.0:
                    continue
                for j in range(i + 1, s1):
                    tj = adj[j] // 3
                    if area2[tj] <= 0.0:
                        continue
                    d = (
                        face[ti, 0] * face[tj, 0]
                        + face[ti, 1] * face[tj, 1]
                        + face[ti, 2] * face[tj, 2]
                    )
                    if abs(d) < cos_limit:
                        is_sharp = True
                        break
                if is_sharp:
                    break
        sharp[p] = is_sharp
        if is_sharp or length <= 0.0:
            continue
        if ax * ux + ay * uy + az * uz < cos_half:
            out[p, 0] = ax
            out[p, 1] = ay
            out[p, 2] = az
            replaced += 1
    return replaced


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def split_corners(unit, face, area2, triangles, start, adj, cos_limit, sharp, bad):
    """Mark the corners to split (``bad``, (3 m,) bool) and return how many.

    A corner is split when its point is shared across a sharp edge (a face around it turns by
    more than the feature angle from the corner's face) or its normal disagrees with its face
    by more than the feature angle; corners of zero-area triangles never are. ``sharp`` (from
    :func:`stale_point_normals`) says which points have faces that far apart at all: only
    their corners need the scan of the faces around them.
    """
    count = 0
    for t in range(triangles.shape[0]):
        for k in range(3):
            c = 3 * t + k
            bad[c] = False
            if area2[t] <= 0.0:
                continue
            p = triangles[t, k]
            fx, fy, fz = face[t, 0], face[t, 1], face[t, 2]
            across = False
            for i in range(start[p], start[p + 1] if sharp[p] else start[p]):
                o = adj[i] // 3
                if area2[o] <= 0.0:
                    continue
                d = fx * face[o, 0] + fy * face[o, 1] + fz * face[o, 2]
                if abs(d) < cos_limit:
                    across = True
                    break
            if not across:
                d = abs(unit[p, 0] * fx + unit[p, 1] * fy + unit[p, 2] * fz)
                across = d < cos_limit
            if across:
                bad[c] = True
                count += 1
    return count


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def split_normals_into(unit, face, area2, triangles, start, adj, cos_limit, corners, out):
    """The normal of each split corner (``corners``: flat corner indices), into ``out``.

    The area-weighted mean of the normals of the triangles around the corner's point that lie
    within the feature angle of the corner's own triangle (the smoothing ``vtkPolyDataNormals``
    does with splitting on): the faces of a crease shade flat, a smooth region beside it stays
    smooth. Neighbours wound the other way count by orientation-free angle; the result is
    turned to the side of the normal it replaces, and is the corner's face normal where the
    mean vanishes.
    """
    for j in range(corners.shape[0]):
        c = corners[j]
        t = c // 3
        p = triangles[t, c - 3 * t]
        fx, fy, fz = face[t, 0], face[t, 1], face[t, 2]
        ax = 0.0
        ay = 0.0
        az = 0.0
        for i in range(start[p], start[p + 1]):
            o = adj[i] // 3
            if area2[o] <= 0.0:
                continue
            d = fx * face[o, 0] + fy * face[o, 1] + fz * face[o, 2]
            if abs(d) >= cos_limit:
                w = area2[o] if d >= 0.0 else -area2[o]
                ax += face[o, 0] * w
                ay += face[o, 1] * w
                az += face[o, 2] * w
        length = np.sqrt(ax * ax + ay * ay + az * az)
        if length > 0.0:
            ax /= length
            ay /= length
            az /= length
        else:
            ax, ay, az = fx, fy, fz
        if ax * unit[p, 0] + ay * unit[p, 1] + az * unit[p, 2] < 0.0:
            ax, ay, az = -ax, -ay, -az
        out[j, 0] = ax
        out[j, 1] = ay
        out[j, 2] = az


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def triangle_heights(points, triangles):
    """The largest triangle height (twice the area over the longest side) of a surface: a
    surface whose largest height is within its coordinates' rounding draws nothing."""
    best = 0.0
    for t in range(triangles.shape[0]):
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        ux = points[b, 0] - points[a, 0]
        uy = points[b, 1] - points[a, 1]
        uz = points[b, 2] - points[a, 2]
        vx = points[c, 0] - points[a, 0]
        vy = points[c, 1] - points[a, 1]
        vz = points[c, 2] - points[a, 2]
        wx = points[a, 0] - points[c, 0]
        wy = points[a, 1] - points[c, 1]
        wz = points[a, 2] - points[c, 2]
        nx = uy * vz - uz * vy
        ny = uz * vx - ux * vz
        nz = ux * vy - uy * vx
        area2 = np.sqrt(nx * nx + ny * ny + nz * nz)
        l0 = np.sqrt(ux * ux + uy * uy + uz * uz)
        bx = points[c, 0] - points[b, 0]
        by = points[c, 1] - points[b, 1]
        bz = points[c, 2] - points[b, 2]
        l1 = np.sqrt(bx * bx + by * by + bz * bz)
        l2 = np.sqrt(wx * wx + wy * wy + wz * wz)
        longest = max(l0, max(l1, l2))
        if longest > 0.0:
            h = area2 / longest
            if h > best:
                best = h
    return best


@njit(cache=True, nogil=True, _nrt=False)
def point_bounds(points, lo, hi):
    """Per-axis minimum and maximum of (n, 3) points into ``lo`` and ``hi`` (3,), and the
    largest coordinate magnitude (one pass instead of numpy's five reductions)."""
    for k in range(3):
        lo[k] = points[0, k]
        hi[k] = points[0, k]
    for i in range(points.shape[0]):
        for k in range(3):
            v = points[i, k]
            if v < lo[k]:
                lo[k] = v
            if v > hi[k]:
                hi[k] = v
    far = 0.0
    for k in range(3):
        far = max(far, max(abs(lo[k]), abs(hi[k])))
    return far
