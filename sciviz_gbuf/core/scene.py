"""Turn what a user calls a scene into triangle surfaces in world coordinates.

A scene is a PyVista/VTK dataset, a sequence of them, or a ``pyvista.Plotter`` (its visible
actors, with their transforms). Each becomes a :class:`Surface`: triangles, float64 world
points, point normals and a map from each triangle back to the cell of the user's dataset,
so every G-buffer value can be traced to the data it came from.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonCore import vtkSMPTools
from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkDataSet, vtkMultiBlockDataSet
from vtkmodules.vtkFiltersCore import vtkPolyDataNormals, vtkTriangleFilter
from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter, vtkGeometryFilter

from ..errors import InputError
from ..readers.mesh import check_mesh, quiet_vtk, source_name

__all__ = [
    "MAX_COORDINATE",
    "MIN_COORDINATE_STEPS",
    "Surface",
    "collect_surfaces",
    "is_plotter",
    "make_surface",
    "scene_items",
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


def _check_area(name: str, points: np.ndarray, triangles: np.ndarray) -> None:
    """At least one triangle with an area, else there is nothing to draw."""
    pts = np.asarray(points, dtype=np.float64)
    a, b, c = (pts[triangles[:, k]] for k in range(3))
    area2 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                      np.linalg.norm(a - c, axis=1)], axis=0)  # fmt: skip
    extent = float(np.ptp(pts, axis=0).max()) if len(pts) else 0.0
    # A triangle counts if its height is above the rounding of its coordinates, relative to
    # the object's size: a 1e-9 wide part is drawn, float32 points on one line are not.
    rounding = np.finfo(points.dtype).eps if points.dtype == np.float32 else 1e-15
    tol = 1e-6 * extent + 8 * rounding * float(np.abs(pts).max(initial=0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        height = np.where(longest > 0, area2 / longest, 0.0)
    if extent == 0.0 or not (height > tol).any():
        raise InputError(
            f"{name}: all {len(triangles)} triangles have zero area (their points coincide or "
            "lie on one line): nothing to draw"
        )


def _check_resolution(name: str, points: np.ndarray) -> None:
    """Refuse an object whose stored coordinates are too coarse for its size where it is."""
    if not np.issubdtype(points.dtype, np.floating):
        return
    lo, hi = points.min(axis=0), points.max(axis=0)
    step = float(np.finfo(points.dtype).eps) * float(np.abs(points).max())
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
    surface = _make_surface(name, data, transform, feature_angle)
    if surface is None:
        raise InputError(f"{name}: the dataset has no surface (polygon) cells to capture")
    return surface


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
    _check_area(name, np.asarray(poly.points), conn.reshape(-1, 3))
    _check_resolution(name, np.asarray(poly.points))
    normals = _existing_normals(poly)
    if normals is None:
        with quiet_vtk():
            poly = _compute_normals(poly, feature_angle)
        normals = _existing_normals(poly)
        tris = poly.GetPolys()
        conn = np.asarray(pv.convert_array(tris.GetConnectivityArray()), dtype=np.int64)
    triangles = conn.reshape(-1, 3)
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
    surfaces = [_make_surface(n, d, t, feature_angle) for n, d, t in items]
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
