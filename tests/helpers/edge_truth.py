"""Object-space ground truth of visible feature lines, rasterised at a G-buffer's resolution.

Test helper (no tests in here). It shares no code with the package's image-space edge filters:
from a G-buffer it reads only ``gb.camera`` (matrices, eye, clipping range, buffer size). The
lines are found on the triangle meshes themselves and their visibility is decided by float64
ray casting against every triangle of the scene, so it can serve as an independent reference
for silhouette/border/crease detectors.

Method
------
1. Every dataset is reduced to triangles in world coordinates (``vtkDataSetSurfaceFilter`` for
   non-PolyData, then ``vtkTriangleFilter``), with the topology (point sharing) it has: nothing
   is merged or cleaned, exactly like the capture, so an unmerged STL has only border edges.
2. Edges are classified (:func:`classify_edges`): *border* = used by one triangle, or by more
   than two (non-manifold); *crease* = two triangles whose normals make an angle of at least
   ``feature_angle`` (VTK's ``dot <= cos`` rule); *silhouette* = two triangles of which one
   faces the eye and the other faces away.
3. Each edge is clipped to the view frustum, sampled at ``<= step_px`` pixel spacing in image
   space (perspective-correct), and a sample is kept when the segment from the near plane to
   the sample, shortened by half a pixel footprint, hits no triangle of the scene.
4. Kept samples are rasterised to the pixel containing them.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numba import njit, prange
from scipy import ndimage
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter

__all__ = [
    "classify_edges",
    "mesh_triangles",
    "precision_recall",
    "scene_triangles",
    "visible_edge_truth",
]

KINDS = ("silhouette", "border", "crease")
_SIL, _BORDER, _CREASE = 1, 2, 4


# --------------------------------------------------------------------------- meshes
def _leaves(obj) -> Iterable:
    import pyvista as pv

    ds = pv.wrap(obj)
    if isinstance(ds, pv.MultiBlock):
        for block in ds:
            if block is not None:
                yield from _leaves(block)
    else:
        yield ds


def mesh_triangles(mesh) -> tuple[np.ndarray, np.ndarray]:
    """World points ``(n, 3)`` float64 and triangles ``(m, 3)`` int64 of one dataset's surface.

    Polygons and strips are triangulated; vertices and lines are dropped. Points are not merged.
    """
    data = mesh
    if not isinstance(data, vtkPolyData):
        surf = vtkDataSetSurfaceFilter()
        surf.SetInputData(data)
        surf.Update()
        data = surf.GetOutput()
    tri = vtkTriangleFilter()
    tri.PassVertsOff()
    tri.PassLinesOff()
    tri.SetInputData(data)
    tri.Update()
    out = tri.GetOutput()
    if out.GetNumberOfPoints() == 0 or out.GetPolys().GetNumberOfCells() == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    points = vtk_to_numpy(out.GetPoints().GetData()).astype(np.float64)
    polys = out.GetPolys()
    offsets = vtk_to_numpy(polys.GetOffsetsArray())
    if not np.all(np.diff(offsets) == 3):
        raise ValueError("vtkTriangleFilter left non-triangle polygons")
    triangles = vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64).reshape(-1, 3)
    return points, triangles


def scene_triangles(meshes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All surfaces of ``meshes`` (a dataset or a list; MultiBlocks are flattened) in one array.

    Returns ``points (n, 3)``, ``triangles (m, 3)`` (indices into ``points``) and the index of
    the leaf dataset of each point (edges never join two datasets: their points are distinct).
    """
    if isinstance(meshes, (list, tuple)):
        items = [leaf for m in meshes for leaf in _leaves(m)]
    else:
        items = list(_leaves(meshes))
    pts, tris, owner = [], [], []
    n = 0
    for i, ds in enumerate(items):
        p, t = mesh_triangles(ds)
        pts.append(p)
        tris.append(t + n)
        owner.append(np.full(p.shape[0], i))
        n += p.shape[0]
    if not pts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(pts), np.concatenate(tris), np.concatenate(owner)


# --------------------------------------------------------------------------- edges
def classify_edges(
    points: np.ndarray,
    triangles: np.ndarray,
    *,
    feature_angle: float = 30.0,
    eye: np.ndarray | None = None,
    view_direction: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Unique edges of a triangle mesh and their kinds.

    Parameters
    ----------
    points, triangles
        As returned by :func:`mesh_triangles`.
    feature_angle
        Degrees; an edge is a crease when ``dot(n1, n2) <= cos(feature_angle)`` (unit face
        normals), the rule of ``vtkFeatureEdges`` and ``vtkPolyDataNormals``.
    eye, view_direction
        Silhouettes are found for a perspective eye position, or for a parallel projection along
        ``view_direction`` (eye towards scene). With neither, no edge is a silhouette.

    Returns
    -------
    dict with ``"edges"`` (k, 2) int64 point indices and bool (k,) ``"border"``, ``"crease"``,
    ``"silhouette"``.

    Notes
    -----
    Orientation. Triangle winding is not trusted globally: for each manifold edge the two
    triangles are compared *locally*. They are consistently wound iff they traverse the shared
    edge in opposite directions; if not, the second normal is flipped before both the crease and
    the facing test. This is exact for every edge, whereas a global re-orientation
    (``vtkPolyDataNormals`` with consistency on) can fail on non-orientable or non-manifold
    input, and ``|dot|`` would misclassify sharp folds (angles over 90 degrees) as smooth. On a
    consistently wound mesh the result is identical to ``vtkFeatureEdges``.

    Zero-area triangles have no normal. Like ``vtkFeatureEdges`` (whose normal is then zero),
    their edges count as creases when ``feature_angle < 90``; they are never silhouettes.

    Non-manifold edges (more than two triangles) are reported as borders: neither the crease
    nor the facing test is defined for them.
    """
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    m = triangles.shape[0]
    if m == 0:
        z = np.zeros(0, dtype=bool)
        return {"edges": np.zeros((0, 2), np.int64), "border": z, "crease": z, "silhouette": z}
    a, b, c = (points[triangles[:, i]] for i in range(3))
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.where(length > 0.0, length, 1.0)[:, None]
    unit[length == 0.0] = 0.0

    # directed edges (v_i -> v_{i+1}) of every triangle, grouped by their undirected key
    src = triangles.reshape(-1)
    dst = triangles[:, [1, 2, 0]].reshape(-1)
    owner = np.repeat(np.arange(m), 3)
    lo, hi = np.minimum(src, dst), np.maximum(src, dst)
    key = lo * (int(points.shape[0]) + 1) + hi
    order = np.argsort(key, kind="stable")
    key_sorted = key[order]
    first = np.flatnonzero(np.r_[True, key_sorted[1:] != key_sorted[:-1]])
    count = np.diff(np.r_[first, key_sorted.size])
    e0 = order[first]
    edges = np.stack([lo[e0], hi[e0]], axis=1)

    border = count != 2
    two = np.flatnonzero(count == 2)
    i1, i2 = order[first[two]], order[first[two] + 1]
    t1, t2 = owner[i1], owner[i2]
    # consistent winding: the two triangles run the edge in opposite directions
    sign = np.where(src[i1] == src[i2], -1.0, 1.0)

    crease = np.zeros(edges.shape[0], dtype=bool)
    cos_limit = np.cos(np.radians(float(feature_angle)))
    dots = np.einsum("ij,ij->i", unit[t1], unit[t2]) * sign
    crease[two] = dots <= cos_limit

    silhouette = np.zeros(edges.shape[0], dtype=bool)
    if eye is not None or view_direction is not None:
        if eye is not None:
            centroid = (a + b + c) / 3.0
            facing = np.einsum("ij,ij->i", unit, np.asarray(eye, np.float64) - centroid)
        else:
            facing = unit @ -np.asarray(view_direction, dtype=np.float64)
        silhouette[two] = facing[t1] * facing[t2] * sign < 0.0
    return {"edges": edges, "border": border, "crease": crease, "silhouette": silhouette}


# --------------------------------------------------------------------------- projection
def _clip_segments(c0: np.ndarray, c1: np.ndarray, margin_x: float, margin_y: float):
    """Liang-Barsky in homogeneous clip space: parameter range [t0, t1] of each segment inside
    ``-w <= z <= w`` and ``|x| <= w (1 + margin_x)``, ``|y| <= w (1 + margin_y)``."""
    n = c0.shape[0]
    t0 = np.zeros(n)
    t1 = np.ones(n)
    keep = np.ones(n, dtype=bool)
    planes = []
    for axis, mg in ((0, margin_x), (1, margin_y), (2, 0.0)):
        for s in (1.0, -1.0):
            planes.append((axis, s, 1.0 + mg))
    for axis, s, k in planes:
        d0 = k * c0[:, 3] - s * c0[:, axis]
        d1 = k * c1[:, 3] - s * c1[:, axis]
        keep &= ~((d0 < 0.0) & (d1 < 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            tc = d0 / (d0 - d1)
        enter = (d0 < 0.0) & (d1 >= 0.0)
        leave = (d0 >= 0.0) & (d1 < 0.0)
        t0 = np.where(enter, np.maximum(t0, tc), t0)
        t1 = np.where(leave, np.minimum(t1, tc), t1)
    keep &= t0 <= t1
    return keep, t0, t1


def _to_pixels(clip: np.ndarray, width: int, height: int) -> np.ndarray:
    """Clip coordinates -> continuous pixel coordinates (x right, y down; row 0 on top)."""
    ndc = clip[..., :2] / clip[..., 3:4]
    return np.stack([(ndc[..., 0] + 1.0) * 0.5 * width, (1.0 - ndc[..., 1]) * 0.5 * height], -1)


# --------------------------------------------------------------------------- ray casting
@njit(parallel=True, cache=True)
def _occluded(orig, end, tile, v0, e1, e2, tile_start, tile_tris, global_tris):  # pragma: no cover
    """For each segment orig[i] -> end[i]: does it hit a triangle of its tile or a global one?"""
    n = orig.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    tol = 1e-10
    for i in prange(n):
        ox, oy, oz = orig[i, 0], orig[i, 1], orig[i, 2]
        dx, dy, dz = end[i, 0] - ox, end[i, 1] - oy, end[i, 2] - oz
        tt = tile[i]
        n_local = tile_start[tt + 1] - tile_start[tt]
        for k in range(n_local + global_tris.shape[0]):
            if k < n_local:
                j = tile_tris[tile_start[tt] + k]
            else:
                j = global_tris[k - n_local]
            ax, ay, az = e1[j, 0], e1[j, 1], e1[j, 2]
            bx, by, bz = e2[j, 0], e2[j, 1], e2[j, 2]
            # Moller-Trumbore
            px, py, pz = dy * bz - dz * by, dz * bx - dx * bz, dx * by - dy * bx
            det = ax * px + ay * py + az * pz
            if det == 0.0:
                continue
            inv = 1.0 / det
            sx, sy, sz = ox - v0[j, 0], oy - v0[j, 1], oz - v0[j, 2]
            u = (sx * px + sy * py + sz * pz) * inv
            if u < -tol or u > 1.0 + tol:
                continue
            qx, qy, qz = sy * az - sz * ay, sz * ax - sx * az, sx * ay - sy * ax
            v = (dx * qx + dy * qy + dz * qz) * inv
            if v < -tol or u + v > 1.0 + tol:
                continue
            t = (bx * qx + by * qy + bz * qz) * inv
            if 0.0 <= t <= 1.0:
                out[i] = True
                break
    return out


def _bin_triangles(tri_px: np.ndarray, width: int, height: int, n_samples: int):
    """Bucket projected triangles (m, 3, 2) by pixel tiles; the tile size minimises a cost
    estimate (bucket entries + expected ray-triangle tests). Returns (tile size, tiles across,
    tile_start, tile_tris) in CSR form."""
    lo = np.floor(tri_px.min(axis=1) - 0.01)
    hi = np.floor(tri_px.max(axis=1) + 0.01)
    lo = np.clip(lo, 0, [width - 1, height - 1]).astype(np.int64)
    hi = np.clip(hi, -1, [width - 1, height - 1]).astype(np.int64)
    ok = np.all(hi >= lo, axis=1)
    best = None
    for size in (2, 4, 8, 16, 32, 64, 128):
        nx, ny = -(-width // size), -(-height // size)
        span = (hi[ok] // size - lo[ok] // size + 1).prod(axis=1)
        entries = int(span.sum())
        cost = entries + n_samples * entries / (nx * ny)
        if best is None or cost < best[0]:
            best = (cost, size, nx, ny)
    _, size, nx, ny = best
    ids = np.flatnonzero(ok)
    tlo, thi = lo[ids] // size, hi[ids] // size
    span_x = thi[:, 0] - tlo[:, 0] + 1
    span = span_x * (thi[:, 1] - tlo[:, 1] + 1)
    tri = np.repeat(ids, span)
    k = np.arange(tri.size) - np.repeat(np.cumsum(span) - span, span)
    sx = np.repeat(span_x, span)
    tx = np.repeat(tlo[:, 0], span) + k % sx
    ty = np.repeat(tlo[:, 1], span) + k // sx
    tile_id = ty * nx + tx
    order = np.argsort(tile_id, kind="stable")
    tile_start = np.r_[0, np.cumsum(np.bincount(tile_id, minlength=nx * ny))].astype(np.int64)
    return size, nx, tile_start, tri[order].astype(np.int64)


# --------------------------------------------------------------------------- the truth
def visible_edge_truth(
    meshes,
    gb,
    *,
    feature_angle: float = 30.0,
    silhouettes: bool = True,
    borders: bool = True,
    creases: bool = True,
    step_px: float = 0.25,
) -> dict[str, np.ndarray]:
    """Visible feature lines of ``meshes`` as seen by ``gb.camera``, as bool (H, W) images.

    Parameters
    ----------
    meshes : pyvista/VTK dataset or list of them
        The scene, in world coordinates (actor transforms of a Plotter are not applied). All of
        it occludes; lines are taken from every mesh.
    gb : GBuffer or CameraInfo
        Only the camera is used (its ``window_size`` is the buffer size, supersampling
        included).
    feature_angle : float
        Crease threshold in degrees, see :func:`classify_edges`.
    silhouettes, borders, creases : bool
        Which kinds to compute; a kind left out gives an all-False image.
    step_px : float
        Largest spacing of edge samples in pixels.

    Returns
    -------
    dict
        ``"silhouette"``, ``"border"``, ``"crease"`` and ``"all"`` (their union). An edge can be
        of several kinds (a crease that is also a silhouette).

    Notes
    -----
    A sample point ``S`` on an edge, at eye-space depth ``z``, is visible when the segment along
    its view ray from depth ``near`` (the camera's near clipping plane; the eye is on the ray in
    perspective) to ``S`` minus ``eps`` hits no triangle; ``eps`` is half a pixel footprint at
    ``z``. The triangles that contain ``S`` (those of the edge) meet the ray only at ``S``, so
    they never hide it; a surface closer than ``eps`` in front of ``S`` does not either. Edges
    are clipped to the near/far planes, like the rendering.
    """
    if not 0.0 <= float(feature_angle) <= 180.0:
        raise ValueError(f"feature_angle must be in [0, 180] degrees, got {feature_angle!r}")
    if not step_px > 0.0:
        raise ValueError(f"step_px must be positive, got {step_px!r}")
    cam = getattr(gb, "camera", gb)
    width, height = (int(v) for v in cam.window_size)
    out = {k: np.zeros((height, width), dtype=bool) for k in (*KINDS, "all")}

    points, triangles, _ = scene_triangles(meshes)
    if triangles.shape[0] == 0:
        return out
    eye = np.asarray(cam.position, dtype=np.float64)
    direction = np.subtract(cam.focal_point, cam.position, dtype=np.float64)
    direction /= np.linalg.norm(direction)
    parallel = bool(cam.parallel_projection)
    near = float(cam.clipping_range[0])
    m = cam.world_to_clip()

    kinds = classify_edges(
        points,
        triangles,
        feature_angle=feature_angle,
        eye=None if parallel else eye,
        view_direction=direction if parallel else None,
    )
    flags = np.zeros(kinds["edges"].shape[0], dtype=np.int64)
    for name, bit, wanted in (
        ("silhouette", _SIL, silhouettes),
        ("border", _BORDER, borders),
        ("crease", _CREASE, creases),
    ):
        if wanted:
            flags |= np.where(kinds[name], bit, 0)
    sel = flags != 0
    edges, flags = kinds["edges"][sel], flags[sel]
    if edges.shape[0] == 0:
        return out

    # clip each edge to the (slightly widened) frustum, then sample uniformly in image space
    hom = np.c_[points, np.ones(points.shape[0])] @ m.T
    keep, t0, t1 = _clip_segments(hom[edges[:, 0]], hom[edges[:, 1]], 2.0 / width, 2.0 / height)
    edges, flags, t0, t1 = edges[keep], flags[keep], t0[keep], t1[keep]
    p0, p1 = points[edges[:, 0]], points[edges[:, 1]]
    q0 = p0 + t0[:, None] * (p1 - p0)
    q1 = p0 + t1[:, None] * (p1 - p0)
    c0 = np.c_[q0, np.ones(len(q0))] @ m.T
    c1 = np.c_[q1, np.ones(len(q1))] @ m.T
    s0, s1 = _to_pixels(c0, width, height), _to_pixels(c1, width, height)
    n_seg = np.ceil(np.linalg.norm(s1 - s0, axis=1) / step_px).astype(np.int64)
    n_seg = np.maximum(n_seg, 1)
    per_edge = n_seg + 1
    edge_of = np.repeat(np.arange(edges.shape[0]), per_edge)
    k = np.arange(edge_of.size) - np.repeat(np.cumsum(per_edge) - per_edge, per_edge)
    u = k / n_seg[edge_of]  # linear in image space
    w0, w1 = c0[edge_of, 3], c1[edge_of, 3]
    tau = u * w0 / ((1.0 - u) * w1 + u * w0)  # the matching world parameter
    sample = q0[edge_of] + tau[:, None] * (q1 - q0)[edge_of]
    px = _to_pixels(np.c_[sample, np.ones(len(sample))] @ m.T, width, height)
    col = np.floor(px[:, 0]).astype(np.int64)
    row = np.floor(px[:, 1]).astype(np.int64)
    inside = (col >= 0) & (col < width) & (row >= 0) & (row < height)
    sample, col, row = sample[inside], col[inside], row[inside]
    sflags = flags[edge_of[inside]]
    if sample.shape[0] == 0:
        return out

    # view-ray segments from the near plane to just short of each sample
    depth = (sample - eye) @ direction
    if parallel:
        ray = np.broadcast_to(direction, sample.shape)
        origin = sample - (depth - near)[:, None] * direction
        eps = 0.5 * cam.pixel_size
    else:
        ray = sample - eye
        ray = ray / np.linalg.norm(ray, axis=1, keepdims=True)
        origin = eye + (sample - eye) * (near / depth)[:, None]
        eps = 0.5 * cam.pixel_size * depth / cam.distance
    end = sample - ray * np.broadcast_to(eps, depth.shape)[:, None]

    # occluders: bucket by projected bounding box; triangles crossing the eye plane are tested
    # against every ray; those wholly behind it can hide nothing
    tri_w = hom[triangles, 3]
    front = np.all(tri_w > 0.0, axis=1)
    crossing = ~front & np.any(tri_w > 0.0, axis=1)
    tri_px = np.full((triangles.shape[0], 3, 2), -1e9)  # an empty box: never bucketed
    tri_px[front] = _to_pixels(hom[triangles[front]], width, height)
    size, nx, tile_start, tile_tris = _bin_triangles(tri_px, width, height, sample.shape[0])
    tile = (row // size) * nx + col // size
    v = points[triangles]
    hidden = _occluded(
        np.ascontiguousarray(origin),
        np.ascontiguousarray(end),
        tile.astype(np.int64),
        np.ascontiguousarray(v[:, 0]),
        np.ascontiguousarray(v[:, 1] - v[:, 0]),
        np.ascontiguousarray(v[:, 2] - v[:, 0]),
        tile_start,
        tile_tris,
        np.flatnonzero(crossing).astype(np.int64),
    )
    vis = ~hidden
    for name, bit in (("silhouette", _SIL), ("border", _BORDER), ("crease", _CREASE)):
        sel = vis & ((sflags & bit) != 0)
        out[name][row[sel], col[sel]] = True
    out["all"] = out["silhouette"] | out["border"] | out["crease"]
    return out


# --------------------------------------------------------------------------- scoring
def precision_recall(
    detected: np.ndarray, truth: np.ndarray, tol_px: float = 1.5
) -> tuple[float, float]:
    """Tolerant precision and recall of a detected line image against a truth image.

    precision = fraction of detected pixels within ``tol_px`` (Euclidean, pixel centres) of a
    truth pixel; recall = fraction of truth pixels within ``tol_px`` of a detected pixel.

    Empty inputs follow the "nothing to count, nothing wrong" convention: with no detected
    pixels precision is 1.0 (there are no false positives) and with no truth pixels recall is
    1.0 (nothing was missed); the other number is then 0.0 unless both are empty, giving
    (1.0, 1.0). Look at both numbers: an empty detection has precision 1.0 but recall 0.0.
    """
    detected = np.asarray(detected, dtype=bool)
    truth = np.asarray(truth, dtype=bool)
    if detected.shape != truth.shape:
        raise ValueError(f"shape mismatch: detected {detected.shape} vs truth {truth.shape}")
    n_det, n_true = int(detected.sum()), int(truth.sum())
    if n_det == 0 or n_true == 0:
        return (1.0 if n_det == 0 else 0.0, 1.0 if n_true == 0 else 0.0)
    to_truth = ndimage.distance_transform_edt(~truth)
    to_detected = ndimage.distance_transform_edt(~detected)
    precision = float(np.mean(to_truth[detected] <= tol_px))
    recall = float(np.mean(to_detected[truth] <= tol_px))
    return precision, recall
