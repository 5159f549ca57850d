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

__all__ = ["Surface", "collect_surfaces", "is_plotter", "make_surface", "scene_items"]

_CELL_ID = "__sciviz_gbuf_cell_id"


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
            items.append((f"actor {key!r}", data, None if np.allclose(mat, np.eye(4)) else mat))
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
        items.append((f"dataset {i} ({type(ds).__name__})", ds, None))
    return items


def _surface_polydata(name: str, data: object) -> pv.PolyData:
    """Polygonal surface of any dataset with a cell-id array tracing back to ``data``."""
    ds = pv.wrap(data)
    if isinstance(ds, pv.MultiBlock):
        ds = ds.combine(merge_points=False)
        if ds is None or ds.n_cells == 0:
            raise InputError(f"{name}: the MultiBlock has no cells to capture")
    if ds.n_points == 0 or ds.n_cells == 0:
        raise InputError(f"{name}: the dataset is empty (no points or no cells)")
    pts = np.asarray(ds.points)
    if not np.isfinite(pts).all():
        bad = int(np.count_nonzero(~np.isfinite(pts).all(axis=1)))
        raise InputError(f"{name}: {bad} point(s) have NaN or infinite coordinates")
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
        surf.Update()
        poly = pv.wrap(surf.GetOutput())
    if poly.GetNumberOfPolys() == 0 and poly.GetNumberOfStrips() == 0:
        raise InputError(f"{name}: the dataset has no surface (polygon) cells to capture")
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


def make_surface(
    name: str, data: object, transform: np.ndarray | None, feature_angle: float
) -> Surface:
    """Prepare one dataset (see :class:`Surface`). Never modifies ``data``."""
    poly = _triangulate(_surface_polydata(name, data))
    normals = _existing_normals(poly)
    if normals is None:
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


def collect_surfaces(scene: object, *, feature_angle: float = 30.0) -> list[Surface]:
    """All surfaces of a scene, in scene order (which defines ``object_id``)."""
    return [make_surface(n, d, t, feature_angle) for n, d, t in scene_items(scene)]
