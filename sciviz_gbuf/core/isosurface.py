"""Volumes -> isosurfaces: the surface a G-buffer is captured from (Saito & Takahashi 1990 §4.4).

A CT volume (``read_dicom_series``), a label volume or any PyVista dataset with point scalars is
cut at a threshold with VTK's flying edges (``vtkFlyingEdges3D``: image data, also oblique ones
with a direction matrix) or VTK's contour filter (sheared or unevenly spaced structured grids and
other non-image grids, so every vertex lies on the true patient-space cell edge), then optionally
smoothed, decimated and given point normals.
"""

from __future__ import annotations

import json

import numpy as np
import pyvista as pv

from .._progress import progress
from ..errors import InputError

__all__ = ["ISO_PRESETS", "isosurface"]

#: Thresholds in Hounsfield units: cortical and trabecular bone, and the skin / air boundary.
ISO_PRESETS = {"bone": 300.0, "skin": -500.0}


def _iso_value(iso: str | float, name: str) -> float:
    if isinstance(iso, str):
        key = iso.strip().lower()
        if key in ISO_PRESETS:
            if name != "HU":
                raise InputError(
                    f"iso: the preset {iso!r} is in Hounsfield units, but the scalars are "
                    f"{name!r}; give a number in the units of {name!r}"
                )
            return ISO_PRESETS[key]
        try:
            return float(key)
        except ValueError:
            raise InputError(
                f"iso: expected a number or one of {sorted(ISO_PRESETS)}, got {iso!r}"
            ) from None
    try:
        value = float(iso)
    except (TypeError, ValueError):
        raise InputError(
            f"iso: expected a number or one of {sorted(ISO_PRESETS)}, got {iso!r}"
        ) from None
    if not np.isfinite(value):
        raise InputError(f"iso: expected a finite threshold, got {iso!r}")
    return value


def _scalars_of(volume: pv.DataSet, scalars: str | None) -> tuple[str, np.ndarray]:
    if scalars is None:
        if "HU" in volume.point_data:
            scalars = "HU"
        elif volume.point_data.active_scalars_name is not None:
            scalars = volume.point_data.active_scalars_name
        elif len(volume.point_data.keys()) == 1:
            scalars = volume.point_data.keys()[0]
        else:
            raise InputError(
                "scalars: the volume has no point array 'HU' and no single active point array; "
                f"name one of {list(volume.point_data.keys())}"
            )
    if scalars not in volume.point_data:
        where = " (it is a cell array: use volume.cell_data_to_point_data())" * (
            scalars in volume.cell_data
        )
        raise InputError(
            f"scalars: no point array {scalars!r} in the volume{where}; "
            f"it has {list(volume.point_data.keys())}"
        )
    values = np.asarray(volume.point_data[scalars])
    if values.ndim != 1:
        raise InputError(f"scalars: {scalars!r} must have one component, got {values.shape[1:]}")
    if not np.issubdtype(values.dtype, np.number):
        raise InputError(f"scalars: {scalars!r} is not numeric ({values.dtype})")
    return scalars, values


def isosurface(
    volume: pv.DataSet,
    *,
    iso: str | float = "bone",
    scalars: str | None = None,
    smooth: int = 15,
    decimate: float = 0.0,
    largest: bool = False,
    progress_bar: bool = False,
) -> pv.PolyData:
    """The surface where a volume's scalar crosses ``iso``, with point normals.

    Parameters
    ----------
    volume : pyvista.DataSet
        ``pyvista.ImageData`` (flying edges; a direction matrix is honoured),
        ``pyvista.StructuredGrid`` (a gantry-tilted or unevenly spaced CT series) or any other
        dataset with point scalars (VTK's contour filter).
    iso : float or {"bone", "skin"}, default: "bone"
        The threshold, in the units of ``scalars``; the presets are Hounsfield units (bone
        300 HU, skin -500 HU) and need ``scalars="HU"``.
    scalars : str, optional
        Point array to threshold; default ``"HU"`` if present, else the active point scalars.
    smooth : int >= 0, default: 15
        Iterations of windowed-sinc smoothing (``vtkWindowedSincPolyDataFilter``, pass band
        0.1), which removes the voxel staircase without shrinking the surface; 0: none.
    decimate : float in [0, 1), default: 0
        Fraction of triangles to remove with quadric decimation; 0: none.
    largest : bool, default: False
        Keep only the largest connected piece (drops CT noise specks and table parts).
    progress_bar : bool, default: False

    Returns
    -------
    pyvista.PolyData
        Triangles with point ``"Normals"``; NaN scalars (padding read as NaN) count as the
        volume's minimum, i.e. outside any surface of dense matter. ``field_data["isosurface"]``
        records the threshold, the array and the method as JSON.

    Raises
    ------
    InputError
        For a bad parameter, a missing array, or a threshold outside the data range (the surface
        would be empty).
    """
    if not isinstance(volume, pv.DataSet):
        raise InputError(
            f"volume: expected a PyVista dataset (e.g. read_dicom_series), got {type(volume)!r}"
        )
    dims = getattr(volume, "dimensions", None)
    if dims is not None and min(dims) < 2:
        # One slice is an image, not a volume: marching cubes finds no surface in it.
        raise InputError(
            f"volume: a surface needs at least 2 samples along each axis, got dimensions "
            f"{tuple(dims)} (a single slice? read the whole series)"
        )
    name, values = _scalars_of(volume, scalars)
    level = _iso_value(iso, name)
    if isinstance(smooth, bool) or not isinstance(smooth, (int, np.integer)) or smooth < 0:
        raise InputError(f"smooth: expected an integer >= 0 (iterations), got {smooth!r}")
    if not (isinstance(decimate, (int, float)) and 0.0 <= decimate < 1.0):
        raise InputError(f"decimate: expected a fraction in [0, 1), got {decimate!r}")
    finite = np.isfinite(values)
    if not finite.any():
        raise InputError(f"scalars: {name!r} has no finite value")
    lo, hi = float(values[finite].min()), float(values[finite].max())
    if not lo < level < hi:
        raise InputError(
            f"iso: {level:g} lies outside the range [{lo:g}, {hi:g}] of {name!r}: "
            "the surface would be empty"
        )
    grid = volume.copy(deep=False)
    field = values.astype(np.float32, copy=not finite.all())
    if not finite.all():
        field[~finite] = lo
    grid.point_data.clear()
    grid.point_data["iso_scalars"] = field
    method = "flying_edges" if isinstance(grid, pv.ImageData) else "contour"
    stages = 1 + (smooth > 0) + (decimate > 0) + largest + 1
    with progress(progress_bar, stages, "isosurface") as bar:
        # The volume's own gradient gives the best normals of an isosurface; once the surface
        # is moved (smoothing, decimation) they are recomputed from the triangles instead.
        gradient_normals = smooth == 0 and decimate == 0
        surf = grid.contour(
            [level], scalars="iso_scalars", method=method, compute_normals=gradient_normals
        )
        if not surf.is_all_triangles:
            surf = surf.triangulate()
        bar.step("contour")
        if surf.n_cells == 0:
            raise InputError(f"iso: no surface at {level:g} in {name!r}")
        for key in [k for k in surf.point_data.keys() if k != "Normals"]:
            del surf.point_data[key]
        if largest:
            surf = surf.connectivity("largest")
            del surf.point_data["RegionId"], surf.cell_data["RegionId"]
            bar.step("largest piece")
        if smooth > 0:
            surf = surf.smooth_taubin(n_iter=int(smooth), pass_band=0.1, normalize_coordinates=True)
            bar.step("smoothing")
        if decimate > 0:
            surf = surf.decimate(float(decimate))
            bar.step("decimation")
        if not gradient_normals:
            # Contouring keeps the triangles' orientation consistent, so no reorientation pass.
            surf = surf.compute_normals(
                cell_normals=False, split_vertices=False, consistent_normals=False
            )
        bar.step("normals")
    surf = pv.PolyData(surf) if not isinstance(surf, pv.PolyData) else surf
    surf.field_data["isosurface"] = [
        json.dumps(
            {"iso": level, "scalars": name, "method": method, "smooth": int(smooth)}
            | {"decimate": float(decimate), "largest": bool(largest)}
        )
    ]
    return surf
