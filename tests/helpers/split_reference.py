"""The numpy statement of ``core.scene.split_normals`` (the method as array expressions, kept
as the reference its compiled kernels are tested against, CONTRIBUTING rule 8).

Returns the fitted point normals (stale ones replaced), the flat indices of the split corners
and their new normals: what the compiled route turns into the split surface.
"""

from __future__ import annotations

import numpy as np


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row dot products summed x, y, z in turn, as the kernels do (einsum may round a dot of
    perpendicular vectors to the other side of zero)."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def face_normals(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit face normals (zero for zero-area triangles) and twice the triangle areas."""
    pts = np.asarray(points, dtype=np.float64)
    a, b, c = (pts[triangles[:, k]] for k in range(3))
    cross = np.cross(b - a, c - a)
    area2 = np.sqrt(_dot(cross, cross))
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(area2[:, None] > 0, cross / area2[:, None], 0.0)
    return unit, area2


def split_reference(
    points: np.ndarray, normals: np.ndarray, triangles: np.ndarray, feature_angle: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(fitted normals (n, 3), split corners (k,), their normals (k, 3))``."""
    face, area2 = face_normals(points, triangles)
    n = points.shape[0]
    cos_limit = np.cos(np.radians(feature_angle))
    cos_half = np.cos(np.radians(feature_angle / 2.0))
    nrm = np.asarray(normals, dtype=np.float64)
    unit = nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    # Triangles around each point (CSR), then every (corner, triangle around its point) pair.
    flat = triangles.ravel()
    order = np.argsort(flat, kind="stable")
    start = np.searchsorted(flat[order], np.arange(n + 1))
    count = start[flat + 1] - start[flat]
    corner = np.repeat(np.arange(flat.size), count)
    offset = np.arange(corner.size) - np.repeat(np.cumsum(count) - count, count)
    other = order[start[flat][corner] + offset] // 3
    own = corner // 3
    dots = _dot(face[own], face[other])
    both = (area2[own] > 0) & (area2[other] > 0)
    # Stale normals: at a smooth point (no two faces around it apart by more than the
    # feature angle) a normal over half the angle from its faces' area-weighted mean.
    sharp = np.zeros(n, dtype=bool)
    sharp[flat[corner[both & (np.abs(dots) < cos_limit)]]] = True
    tri_of = np.arange(flat.size) // 3
    side = np.where(_dot(face[tri_of], unit[flat]) < 0, -1.0, 1.0)
    mean = np.zeros((n, 3))
    np.add.at(mean, flat, face[tri_of] * (area2[tri_of] * side)[:, None])
    length = np.linalg.norm(mean, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_unit = mean / length[:, None]
    off = _dot(np.nan_to_num(mean_unit), unit) < cos_half
    stale = ~sharp & (length > 0) & off
    fitted = np.where(stale[:, None], np.nan_to_num(mean_unit), unit)
    # Corners split across sharp edges or where the normal disagrees with the face.
    near = (np.abs(dots) >= cos_limit) & (area2[other] > 0)
    across = np.zeros(flat.size, dtype=bool)
    across[corner[~near & (area2[other] > 0)]] = True
    corner_dot = np.abs(_dot(fitted[flat], face[tri_of]))
    bad = (across | (corner_dot < cos_limit)) & (area2[tri_of] > 0)
    index = np.full(flat.size, -1)
    index[bad] = np.arange(int(bad.sum()))
    sel = bad[corner]
    corner, other, dots, near = index[corner[sel]], other[sel], dots[sel], near[sel]
    bt = np.flatnonzero(bad) // 3
    bp = flat[np.flatnonzero(bad)]
    sign = np.where(dots < 0, -1.0, 1.0)
    acc = np.zeros((bp.size, 3))
    np.add.at(acc, corner[near], (face[other] * (area2[other] * sign)[:, None])[near])
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    new_normals = np.where(length > 0, acc / np.maximum(length, 1e-300), face[bt])
    flip = _dot(new_normals, fitted[bp]) < 0
    new_normals[flip] *= -1.0
    return fitted, np.flatnonzero(bad), new_normals
