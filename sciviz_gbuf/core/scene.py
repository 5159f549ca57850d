"""Turn what a user calls a scene into triangle surfaces in world coordinates.

A scene is a PyVista/VTK dataset, a sequence of them, or a ``pyvista.Plotter`` (its visible
actors, with their transforms). Each becomes a :class:`Surface`: triangles, float64 world
points, point normals and a map from each triangle back to the cell of the user's dataset,
so every G-buffer value can be traced to the data it came from.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonCore import vtkSMPTools
from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkDataSet, vtkMultiBlockDataSet
from vtkmodules.vtkFiltersCore import vtkPolyDataNormals, vtkTriangleFilter
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter, vtkGeometryFilter

from ..errors import InputError
from ..readers.mesh import check_mesh, quiet_vtk, source_name
from . import _scene_kernels

__all__ = [
    "MAX_COORDINATE",
    "MIN_COORDINATE_STEPS",
    "PREPARED_ENTRIES",
    "Surface",
    "collect_surfaces",
    "forget_prepared",
    "is_plotter",
    "make_surface",
    "scene_items",
    "split_normals",
]

_CELL_ID = "__sciviz_gbuf_cell_id"

#: Largest coordinate magnitude the float32 rasteriser handles (its squares still fit).
MAX_COORDINATE = 1e30
#: Fewest coordinate steps an object must span: float32 points 1e7 from the origin step by 1,
#: so a unit sphere there is a few lattice points (a blank or garbled picture).
MIN_COORDINATE_STEPS = 1000


@dataclass
class Surface:
    """One object of a scene, ready for capture.

    Attributes
    ----------
    name : str
        Human-readable label used in error messages (``"dataset 1 (PolyData)"``).
    mesh : pyvista.PolyData
        Triangulated surface (points possibly split at sharp edges), world coordinates; its point
        and cell arrays are the user's arrays carried through triangulation.
    points : ndarray (n, 3) float64
        World coordinates of ``mesh`` points (actor transform applied).
    triangles : ndarray (m, 3) int64
        Point indices of each triangle.
    cell_ids : ndarray (m,) int64
        Cell of the user's dataset each triangle comes from.
    normals : ndarray (n, 3) float32
        Unit point normals in world coordinates.
    """

    name: str
    mesh: pv.PolyData
    points: np.ndarray
    triangles: np.ndarray
    cell_ids: np.ndarray
    normals: np.ndarray

    def array(self, name: str) -> tuple[str, np.ndarray] | None:
        """``("point"|"cell", values)`` of the user's array ``name``, or None if absent."""
        if name in self.mesh.point_data:
            return "point", np.asarray(self.mesh.point_data[name])
        if name in self.mesh.cell_data and name != _CELL_ID:
            return "cell", np.asarray(self.mesh.cell_data[name])
        return None

    def texture_coordinates(self) -> np.ndarray | None:
        """Active (u, v) point texture coordinates, or None."""
        tc = self.mesh.GetPointData().GetTCoords()
        if tc is None:
            return None
        return np.asarray(pv.convert_array(tc))[:, :2]


def is_plotter(scene: object) -> bool:
    return isinstance(scene, pv.BasePlotter)


def scene_items(scene: object) -> list[tuple[str, object, np.ndarray | None]]:
    """List ``(name, dataset, 4x4 transform or None)`` for a scene.

    Raises
    ------
    InputError
        If the scene is empty or holds something that is not a dataset.
    """
    if is_plotter(scene):
        items = []
        for key, actor in scene.renderer.actors.items():
            if not actor.GetVisibility() or not hasattr(actor, "GetMapper"):
                continue
            mapper = actor.GetMapper()
            if mapper is None:
                continue
            data = mapper.GetInputDataObject(0, 0)
            if not isinstance(data, (vtkDataSet, vtkMultiBlockDataSet)):
                continue
            m = actor.GetMatrix()
            mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
            name = source_name(data) or f"actor {key!r}"
            items.append((name, data, None if np.allclose(mat, np.eye(4)) else mat))
        if not items:
            raise InputError("scene: the Plotter has no visible actor with a dataset to capture")
        return items
    if isinstance(scene, (vtkDataObject, pv.DataObject)):
        seq: Sequence[object] = [scene]
    elif isinstance(scene, Sequence) and not isinstance(scene, (str, bytes)):
        seq = scene
    else:
        raise InputError(
            f"scene: expected a PyVista/VTK dataset, a sequence of them or a pyvista.Plotter, "
            f"got {type(scene).__name__}"
        )
    if len(seq) == 0:
        raise InputError("scene: empty scene (no datasets given)")
    items = []
    for i, ds in enumerate(seq):
        if not isinstance(ds, (vtkDataSet, vtkMultiBlockDataSet)):
            raise InputError(f"scene[{i}]: expected a PyVista/VTK dataset, got {type(ds).__name__}")
        items.append((source_name(ds) or f"dataset {i} ({type(ds).__name__})", ds, None))
    return items


def _surface_polydata(name: str, data: object) -> pv.PolyData | None:
    """Polygonal surface of any dataset with a cell-id array tracing back to ``data``; None
    if it has cells but no surface (only lines or vertices: left out of the picture)."""
    # Before any VTK filter: they index the points with whatever the connectivity holds.
    check_mesh(data, name)
    ds = pv.wrap(data)
    if isinstance(ds, pv.MultiBlock):
        with quiet_vtk():
            ds = ds.combine(merge_points=False)
        if ds is None or ds.n_cells == 0:
            raise InputError(f"{name}: the MultiBlock has no cells to capture")
    if ds.n_points == 0 or ds.n_cells == 0:
        raise InputError(f"{name}: the dataset is empty (no points or no cells)")
    if isinstance(ds, pv.PolyData):
        poly = ds.copy(deep=False)
        poly.cell_data[_CELL_ID] = np.arange(ds.n_cells, dtype=np.int64)
    else:
        src = ds.copy(deep=False)
        src.cell_data[_CELL_ID] = np.arange(ds.n_cells, dtype=np.int64)
        # Blanked (hidden) points or cells, e.g. a DEM's nodata, are dropped only by
        # vtkGeometryFilter; vtkDataSetSurfaceFilter would keep them.
        blanked = "vtkGhostType" in ds.point_data or "vtkGhostType" in ds.cell_data
        surf = vtkGeometryFilter() if blanked else vtkDataSetSurfaceFilter()
        surf.SetInputData(src)
        with quiet_vtk() as msgs:
            surf.Update()
        if msgs.first_error():
            raise InputError(f"{name}: VTK could not extract the surface ({msgs.first_error()})")
        poly = pv.wrap(surf.GetOutput())
    if poly.GetNumberOfPolys() == 0 and poly.GetNumberOfStrips() == 0:
        return None
    return poly


def _triangulate(poly: pv.PolyData) -> pv.PolyData:
    if poly.is_all_triangles and poly.n_verts == 0 and poly.n_lines == 0:
        return poly
    tri = vtkTriangleFilter()
    tri.PassVertsOff()
    tri.PassLinesOff()
    tri.SetInputData(poly)
    tri.Update()
    return pv.wrap(tri.GetOutput())


def _existing_normals(poly: pv.PolyData) -> np.ndarray | None:
    n = poly.GetPointData().GetNormals()
    if n is None and "Normals" in poly.point_data:
        n = poly.GetPointData().GetArray("Normals")
    if n is None or n.GetNumberOfComponents() != 3:
        return None
    return np.asarray(pv.convert_array(n), dtype=np.float64)


@contextmanager
def _smp_threads() -> Iterator[None]:
    """Run VTK's SMP-parallel filters on threads for a moment (the wheels default to
    sequential), restoring the caller's backend afterwards."""
    before = vtkSMPTools.GetBackend()
    changed = before == "Sequential" and vtkSMPTools.SetBackend("STDThread")
    try:
        yield
    finally:
        if changed:
            vtkSMPTools.SetBackend(before)


def _compute_normals(poly: pv.PolyData, feature_angle: float) -> pv.PolyData:
    alg = vtkPolyDataNormals()
    alg.SetInputData(poly)
    alg.SetFeatureAngle(feature_angle)
    alg.SetSplitting(feature_angle < 180.0)
    alg.ConsistencyOn()
    alg.AutoOrientNormalsOff()
    alg.ComputeCellNormalsOff()
    alg.ComputePointNormalsOn()
    with _smp_threads():
        alg.Update()
    return pv.wrap(alg.GetOutput())


def split_normals(
    poly: pv.PolyData, normals: np.ndarray, triangles: np.ndarray, feature_angle: float
) -> tuple[pv.PolyData, np.ndarray, np.ndarray]:
    """Fit a file's point normals to its faces: stale ones replaced, shared ones split where
    they disagree with a face by more than ``feature_angle`` degrees.

    - **Stale normals.** At a smooth point (every two triangles around it within
      ``feature_angle`` of each other) a normal more than half the feature angle away from
      the area-weighted mean of its faces no longer fits them (the points were moved after
      the normals were computed: ``mesh.points = ...`` and plot). It is replaced by that
      mean, on its own side.
    - **Normals shared across sharp edges.** A file's point normals are often averaged
      across the sharp edges of a CAD part (every point is shared by all faces it touches),
      so a flat face near an edge would shade with normals tilted towards its neighbour:
      streaks. Each corner whose point is shared across an edge sharper than
      ``feature_angle``, or whose normal makes an angle of more than ``feature_angle`` with
      its triangle's normal (orientation ignored: some files wind the other way), gets a
      point of its own, with the area-weighted average of the normals of the triangles
      around the point that lie within ``feature_angle`` of its own (the smoothing
      ``vtkPolyDataNormals`` does with splitting on): the faces of a crease shade flat, a
      smooth region beside it stays smooth. Point data of a split point is copied to its new
      points.

    Agreeing corners keep the file's normals. Compiled (:mod:`._scene_kernels`; the numpy
    statement of the method is ``tests/helpers/split_reference.py``). Returns ``(poly,
    normals, triangles)``, the inputs themselves when nothing changes; ``poly`` is never
    modified.
    """
    if feature_angle >= 180.0 or triangles.shape[0] == 0:
        return poly, normals, triangles
    points = np.ascontiguousarray(poly.points, dtype=np.float64)
    tris = np.ascontiguousarray(triangles, dtype=np.int64)
    m, n = tris.shape[0], points.shape[0]
    face = np.empty((m, 3))
    area2 = np.empty(m)
    _scene_kernels.face_normals_into(points, tris, face, area2)
    cos_limit = float(np.cos(np.radians(feature_angle)))
    cos_half = float(np.cos(np.radians(feature_angle / 2.0)))
    nrm64 = np.asarray(normals, dtype=np.float64)
    unit = nrm64 / np.maximum(np.linalg.norm(nrm64, axis=1, keepdims=True), 1e-300)
    start = np.empty(n + 1, np.int64)
    adj = np.empty(3 * m, np.int64)
    if not _scene_kernels.corner_adjacency(tris, n, start, adj):
        raise InputError("split_normals: a triangle names a point the surface does not have")
    fitted = unit.copy()
    sharp = np.empty(n, np.bool_)
    n_stale = _scene_kernels.stale_point_normals(
        unit, face, area2, start, adj, cos_limit, cos_half, sharp, fitted
    )
    bad = np.empty(3 * m, np.bool_)
    n_bad = _scene_kernels.split_corners(
        fitted, face, area2, tris, start, adj, cos_limit, sharp, bad
    )
    if n_stale == 0 and n_bad == 0:
        return poly, normals, triangles
    if n_stale:
        normals = fitted.astype(normals.dtype)  # the unit file normals where not replaced
    name = poly.GetPointData().GetNormals()
    normals_name = name.GetName() if name is not None and name.GetName() else "Normals"
    if n_bad == 0:  # only stale normals replaced: the same points and triangles
        out = poly.copy(deep=False)
        out.point_data[normals_name] = normals
        out.point_data.active_normals_name = normals_name  # type: ignore[attr-defined]
        return out, normals, triangles
    corners = np.flatnonzero(bad)
    new_normals = np.empty((corners.size, 3))
    _scene_kernels.split_normals_into(
        fitted, face, area2, tris, start, adj, cos_limit, corners, new_normals
    )
    bt, bk = np.divmod(corners, 3)
    bp = tris[bt, bk]
    n0 = poly.n_points
    out = pv.PolyData()
    out.points = np.concatenate([np.asarray(poly.points), np.asarray(poly.points)[bp]])
    new_tris = tris.copy()
    new_tris[bt, bk] = n0 + np.arange(bp.size)
    out.faces = np.hstack([np.full((new_tris.shape[0], 1), 3), new_tris]).ravel()
    for key in poly.point_data.keys():
        arr = np.asarray(poly.point_data[key])
        out.point_data[key] = np.concatenate([arr, arr[bp]]) if bp.size else arr.copy()
    for key in poly.cell_data.keys():
        out.cell_data[key] = np.asarray(poly.cell_data[key])
    all_normals = np.concatenate([normals, new_normals.astype(normals.dtype)])
    out.point_data[normals_name] = all_normals
    out.point_data.active_normals_name = normals_name  # type: ignore[attr-defined]
    tc = poly.GetPointData().GetTCoords()
    if tc is not None and tc.GetName():
        out.GetPointData().SetActiveTCoords(tc.GetName())
    return out, all_normals, new_tris


def _empty_surface(name: str) -> Surface:
    """The place of a dataset without surface cells: keeps ``object_id`` in scene order."""
    mesh = pv.PolyData()
    mesh.cell_data[_CELL_ID] = np.zeros(0, dtype=np.int64)
    return Surface(
        name=name,
        mesh=mesh,
        points=np.zeros((0, 3)),
        triangles=np.zeros((0, 3), dtype=np.int64),
        cell_ids=np.zeros(0, dtype=np.int64),
        normals=np.zeros((0, 3), dtype=np.float32),
    )


def _check_area(
    name: str, points: np.ndarray, triangles: np.ndarray, bounds: tuple[np.ndarray, ...]
) -> None:
    """At least one triangle with an area, else there is nothing to draw. ``bounds``: the
    float64 points, their per-axis minimum and maximum and largest magnitude
    (:func:`_bounds`)."""
    pts, lo, hi, far = bounds
    extent = float((hi - lo).max()) if len(pts) else 0.0
    # A triangle counts if its height is above the rounding of its coordinates, relative to
    # the object's size: a 1e-9 wide part is drawn, float32 points on one line are not.
    rounding = np.finfo(points.dtype).eps if points.dtype == np.float32 else 1e-15
    tol = 1e-6 * extent + 8 * rounding * float(far)
    tris = np.ascontiguousarray(triangles, dtype=np.int64)
    height = _scene_kernels.triangle_heights(pts, tris) if len(pts) else 0.0
    if extent == 0.0 or not height > tol:
        raise InputError(
            f"{name}: all {len(triangles)} triangles have zero area (their points coincide or "
            "lie on one line): nothing to draw"
        )


def _bounds(points: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(float64 points, per-axis minimum, maximum, largest magnitude)`` in one pass."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    lo, hi = np.zeros(3), np.zeros(3)
    far = _scene_kernels.point_bounds(pts, lo, hi) if len(pts) else 0.0
    return pts, lo, hi, np.float64(far)


def _check_resolution(name: str, points: np.ndarray, bounds: tuple[np.ndarray, ...]) -> None:
    """Refuse an object whose stored coordinates are too coarse for its size where it is."""
    if not np.issubdtype(points.dtype, np.floating) or len(points) == 0:
        return
    _, lo, hi, far = bounds  # float64 of the stored values: the same extremes
    step = float(np.finfo(points.dtype).eps) * float(far)
    extent = float((hi - lo).max())
    if extent < MIN_COORDINATE_STEPS * step:
        raise InputError(
            f"{name}: the object is {extent:.3g} across but {float(np.abs(lo + hi).max()) / 2:.3g} "
            f"from the origin, where its {points.dtype} coordinates step by {step:.3g}: too "
            "coarse to draw (store the points as float64, or translate them towards the origin)"
        )


def make_surface(
    name: str, data: object, transform: np.ndarray | None, feature_angle: float
) -> Surface:
    """Prepare one dataset (see :class:`Surface`). Never modifies ``data``.

    Raises
    ------
    InputError
        If ``data`` has bad connectivity or points, or no surface cells (only lines or
        vertices), or only zero-area triangles.
    """
    surface = _prepared_surface(name, data, transform, feature_angle)
    if surface is None:
        raise InputError(f"{name}: the dataset has no surface (polygon) cells to capture")
    return surface


#: Prepared surfaces of the datasets captured last (surface extraction, triangulation, the
#: checks, the fitted normals), so a capture of an unchanged scene does no mesh work. Keyed by
#: the VTK object's address; valid while the dataset's VTK modification time (the largest of
#: its points', cells', point and cell data's and its own) and the options are the same. A new
#: object at a freed address has a later modification time (VTK's clock only runs forward), so
#: an entry never answers for another dataset.
_PREPARED: OrderedDict[str, tuple[tuple, Surface | None]] = OrderedDict()
_PREPARED_LOCK = threading.Lock()
#: Datasets remembered; the oldest is forgotten first (each entry holds about a copy of its
#: dataset's points, triangles and normals).
PREPARED_ENTRIES = 8


def _prepared_surface(
    name: str, data: object, transform: np.ndarray | None, feature_angle: float
) -> Surface | None:
    """:func:`_make_surface`, remembered per dataset while the dataset is unchanged.

    A dataset changed through VTK or PyVista (``mesh.points = ...``, ``mesh.points[i] = ...``,
    a new array, ``Modified()``) is prepared afresh; one written through a raw numpy view of
    its memory without ``Modified()`` is not seen (VTK's own renderer does not see it either).
    """
    if not isinstance(data, vtkDataSet):
        return _make_surface(name, data, transform, feature_angle)
    key = str(data.__this__)
    stamp = (
        int(data.GetMTime()),
        float(feature_angle),
        None if transform is None else np.asarray(transform, dtype=np.float64).tobytes(),
    )
    with _PREPARED_LOCK:
        hit = _PREPARED.get(key)
        if hit is not None and hit[0] == stamp:
            _PREPARED.move_to_end(key)
            return None if hit[1] is None else replace(hit[1], name=name)
    surface = _make_surface(name, data, transform, feature_angle)
    with _PREPARED_LOCK:
        _PREPARED[key] = (stamp, surface)
        _PREPARED.move_to_end(key)
        while len(_PREPARED) > PREPARED_ENTRIES:
            _PREPARED.popitem(last=False)
    return surface


def forget_prepared() -> None:
    """Drop every remembered prepared surface (their memory; the next capture prepares anew)."""
    with _PREPARED_LOCK:
        _PREPARED.clear()


def _make_surface(
    name: str, data: object, transform: np.ndarray | None, feature_angle: float
) -> Surface | None:
    poly = _surface_polydata(name, data)
    if poly is None:
        return None
    with quiet_vtk():
        poly = _triangulate(poly)
    if poly.GetNumberOfPolys() == 0:
        return None
    tris = poly.GetPolys()
    conn = np.asarray(pv.convert_array(tris.GetConnectivityArray()), dtype=np.int64)
    raw = np.asarray(poly.points)
    bounds = _bounds(raw)
    _check_area(name, raw, conn.reshape(-1, 3), bounds)
    _check_resolution(name, raw, bounds)
    normals = _existing_normals(poly)
    if normals is None:
        with quiet_vtk():
            poly = _compute_normals(poly, feature_angle)
        normals = _existing_normals(poly)
        tris = poly.GetPolys()
        conn = np.asarray(pv.convert_array(tris.GetConnectivityArray()), dtype=np.int64)
        triangles = conn.reshape(-1, 3)
    elif "isosurface" in poly.field_data:
        # Our own isosurface: its normals are the smoothed surface's, better than the faces'
        # of marching cubes (splitting them would facet an organic surface), and smooth.
        triangles = conn.reshape(-1, 3)
    else:
        # The file's normals may be smoothed across the edges the feature angle calls sharp.
        poly, normals, triangles = split_normals(poly, normals, conn.reshape(-1, 3), feature_angle)
    cell_ids = np.asarray(poly.cell_data[_CELL_ID], dtype=np.int64)
    points = np.asarray(poly.points, dtype=np.float64)
    if transform is not None:
        points = points @ transform[:3, :3].T + transform[:3, 3]
        normals = normals @ np.linalg.inv(transform[:3, :3])  # inverse transpose, row vectors
    norm = np.linalg.norm(normals, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        normals = np.where(norm > 0, normals / norm, 0.0)
    return Surface(
        name=name,
        mesh=poly,
        points=points,
        triangles=triangles,
        cell_ids=cell_ids,
        normals=normals.astype(np.float32),
    )


def _check_range(surfaces: list[Surface]) -> None:
    """Refuse coordinates beyond :data:`MAX_COORDINATE` (the float32 rasteriser overflows)."""
    points = np.concatenate([s.points for s in surfaces])
    far = float(np.abs(points).max())
    if far > MAX_COORDINATE:
        raise InputError(
            f"scene: coordinates reach {far:.3g}, beyond the {MAX_COORDINATE:g} the renderer "
            "handles (a corrupt file?)"
        )


def collect_surfaces(scene: object, *, feature_angle: float = 30.0) -> list[Surface]:
    """All surfaces of a scene, in scene order (which defines ``object_id``).

    Datasets with only lines or vertices are left out (an object without triangles keeps its
    place, so ``object_id`` is still the index in the scene); a scene with no surface at all
    is an InputError, as are bad connectivity, NaN points, zero-area-only objects and
    coordinates the renderer cannot resolve.
    """
    items = scene_items(scene)
    surfaces = [_prepared_surface(n, d, t, feature_angle) for n, d, t in items]
    if all(s is None for s in surfaces):
        if len(items) == 1:
            raise InputError(
                f"{items[0][0]}: the dataset has no surface (polygon) cells to capture"
            )
        raise InputError(
            "scene: no dataset has surface (polygon) cells to capture (lines and vertices are "
            "left out)"
        )
    out = [
        s if s is not None else _empty_surface(n)
        for s, (n, _, _) in zip(surfaces, items, strict=True)
    ]
    _check_range(out)
    return out
