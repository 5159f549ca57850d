"""Volumes -> isosurfaces: the surface a G-buffer is captured from (Saito & Takahashi 1990 §4.4).

A CT volume (``read_dicom_series``), a label volume or any PyVista dataset with point scalars is
cut at a threshold with VTK's flying edges (``vtkFlyingEdges3D``: image data, also oblique ones
with a direction matrix) or VTK's contour filter (sheared or unevenly spaced structured grids and
other non-image grids, so every vertex lies on the true patient-space cell edge), then optionally
smoothed, decimated and given point normals.

Thick slices. Marching cubes interpolates linearly between samples, so along an axis sampled
much more coarsely than the others (5 mm CT slices of 0.45 mm pixels) the surface is only C0
at every slice plane: bone surfaces seen along the slices come out as terraces, one kink per
slice, which shading shows as bands and edge detection as creases and short profiles (specks)
along every slice. Mesh smoothing cannot remove them cheaply: a terrace is many triangles wide.
So before contouring, such axes are resampled (``refine``) with Keys' cubic convolution (the
Catmull-Rom spline: it interpolates the slices, is C1 between them and needs no prefilter)
onto a spacing of about twice the finest one; the surface of the refined field bends smoothly
through the slice planes.
"""

from __future__ import annotations

import json

import numpy as np
import pyvista as pv

from .. import _validate
from .._progress import progress
from ..errors import InputError

__all__ = ["ISO_PRESETS", "REFINE_POINTS", "REFINE_RATIO", "isosurface", "refine_factors"]

#: Thresholds in Hounsfield units: cortical and trabecular bone, and the skin / air boundary.
ISO_PRESETS = {"bone": 300.0, "skin": -500.0}
#: An axis is refined when its spacing exceeds this many times the finest spacing, onto a
#: spacing of about this many times the finest (``refine``): kinks of the refined surface at
#: the new samples are then small (measured on the 5 mm Philips phantom: creases of the slice
#: terraces fall from 1.8 to 1.1 per truth pixel at factor 3, little more at 5 to 8).
REFINE_RATIO = 2.0
#: Most bytes of the refined field (and of the points of a refined structured grid): the factor
#: is lowered until the refined volume fits, and an axis that cannot be refined at least twice
#: within it is left as it is.
REFINE_POINTS = 2**28


def _keys_weights(u: float) -> tuple[float, float, float, float]:
    """Keys' cubic convolution (a = -1/2, Catmull-Rom) weights of samples i-1, i, i+1, i+2 at
    the fraction ``u`` in [0, 1) past sample i."""
    u2, u3 = u * u, u * u * u
    return (
        0.5 * (-u3 + 2.0 * u2 - u),
        0.5 * (3.0 * u3 - 5.0 * u2 + 2.0),
        0.5 * (-3.0 * u3 + 4.0 * u2 + u),
        0.5 * (u3 - u2),
    )


def _axis_spacing(volume: pv.DataSet) -> np.ndarray:
    """Sample spacing along each index axis (x, y, z) of an image or structured grid."""
    if isinstance(volume, pv.ImageData):
        return np.abs(np.asarray(volume.spacing, dtype=np.float64))
    nx, ny, nz = volume.dimensions
    pts = np.asarray(volume.points).reshape(nz, ny, nx, 3)
    # The median step between neighbours along each axis, on a sparse subset of the rows.
    steps = []
    for axis in (2, 1, 0):  # x, y, z of the index grid (array axes are z, y, x)
        rows = tuple(
            slice(None) if k == axis else slice(None, None, max(1, pts.shape[k] // 8))
            for k in range(3)
        )
        d = np.diff(pts[rows], axis=axis)
        steps.append(float(np.median(np.linalg.norm(d, axis=-1))) if d.size else 0.0)
    return np.asarray(steps)


def refine_factors(
    spacing, dimensions, *, bytes_per_point: int = 4, budget: int = REFINE_POINTS
) -> tuple[int, int, int]:
    """How many times each axis (x, y, z) of a volume is refined before contouring.

    An axis whose ``spacing`` exceeds :data:`REFINE_RATIO` times the finest is given about
    ``spacing / (REFINE_RATIO * finest)`` samples per original step, lowered until the refined
    volume holds at most ``budget`` bytes at ``bytes_per_point``; 1 leaves an axis as it is.
    """
    h = np.asarray(spacing, dtype=np.float64)
    dims = np.asarray(dimensions, dtype=np.int64)
    positive = h[h > 0]
    if positive.size == 0:
        return (1, 1, 1)
    finest = float(positive.min())
    want = np.where(h > REFINE_RATIO * finest, np.ceil(h / (REFINE_RATIO * finest)), 1.0)
    factors = want.astype(np.int64)

    def size(f: np.ndarray) -> int:
        return int(np.prod((dims - 1) * f + 1)) * int(bytes_per_point)

    # Lower the largest factor first (keeps the refined spacings alike) until it fits.
    while size(factors) > budget and factors.max() > 1:
        factors[int(np.argmax(factors))] -= 1
    factors[factors < 2] = 1
    return tuple(int(f) for f in factors)  # type: ignore[return-value]


def _refine_axis(values: np.ndarray, axis: int, factor: int, *, cubic: bool) -> np.ndarray:
    """``values`` resampled along ``axis`` at ``factor`` samples per step (ends kept): Keys
    cubic (edge samples repeated past the ends) or linear."""
    a = np.moveaxis(values, axis, 0)
    n = a.shape[0]
    m = (n - 1) * factor + 1
    out = np.empty((m, *a.shape[1:]), dtype=a.dtype)
    for j in range(m):
        i, r = divmod(j, factor)
        if r == 0:
            out[j] = a[i]
            continue
        u = r / factor
        if cubic:
            taps = (max(i - 1, 0), i, i + 1, min(i + 2, n - 1))
            w = _keys_weights(u)
        else:
            taps, w = (i, i + 1), (1.0 - u, u)
        acc = np.multiply(a[taps[0]], a.dtype.type(w[0]))
        for t, wt in zip(taps[1:], w[1:], strict=True):
            acc += a.dtype.type(wt) * a[t]
        out[j] = acc
    return np.moveaxis(out, 0, axis)


def _refined(grid: pv.DataSet, field: np.ndarray, factors: tuple[int, int, int]) -> pv.DataSet:
    """A copy of an image / structured grid with ``factors`` more samples along x, y, z: the
    field by Keys cubic convolution, a structured grid's points linearly (exact for the affine
    slice geometry of a tilted or unevenly spaced series)."""
    nx, ny, nz = grid.dimensions
    f = field.reshape(nz, ny, nx)
    pts = None if isinstance(grid, pv.ImageData) else np.asarray(grid.points).reshape(nz, ny, nx, 3)
    for xyz, factor in enumerate(factors):
        if factor > 1:
            axis = 2 - xyz  # array axes are (z, y, x)
            f = _refine_axis(f, axis, factor, cubic=True)
            if pts is not None:
                pts = _refine_axis(pts, axis, factor, cubic=False)
    dims = (f.shape[2], f.shape[1], f.shape[0])
    if isinstance(grid, pv.ImageData):
        out = pv.ImageData(
            dimensions=dims,
            spacing=np.asarray(grid.spacing) / np.asarray(factors, dtype=np.float64),
            origin=grid.origin,
        )
        out.direction_matrix = grid.direction_matrix
    else:
        out = pv.StructuredGrid()
        out.points = pts.reshape(-1, 3)
        out.dimensions = dims
    out.point_data["iso_scalars"] = np.ascontiguousarray(f).reshape(-1)
    return out


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
    smooth: int = 60,
    decimate: float = 0.0,
    largest: bool = False,
    refine: bool = True,
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
    smooth : int >= 0, default: 60
        Iterations of windowed-sinc smoothing (``vtkWindowedSincPolyDataFilter``, pass band
        0.1), which removes the voxel staircase without shrinking the surface; 0: none. More
        iterations cut off sharper at the same pass band: at 60 rather than 15 the 30-degree
        creases the voxel and slice noise leaves on the Philips phantom and the frog skeleton
        fall by 10-45 % (measured against object-space truth), for about 2 s more on 2 M
        triangles.
    decimate : float in [0, 1), default: 0
        Fraction of triangles to remove with quadric decimation; 0: none.
    largest : bool, default: False
        Keep only the largest connected piece (drops CT noise specks and table parts).
    refine : bool, default: True
        Resample axes sampled more than :data:`REFINE_RATIO` times more coarsely than the finest
        (thick slices) by cubic convolution before contouring, so the surface has no terrace
        at every slice (see the module notes; :func:`refine_factors` gives the factors, bounded
        by :data:`REFINE_POINTS` bytes). Images and structured grids only; False: contour the
        samples as they are.
    progress_bar : bool, default: False

    Returns
    -------
    pyvista.PolyData
        Triangles with point ``"Normals"``; NaN scalars (padding read as NaN) count as the
        volume's minimum, i.e. outside any surface of dense matter. ``field_data["isosurface"]``
        records the threshold, the array, the method and the refinement factors as JSON.

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
    refine = _validate.boolean(refine, "refine")
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
    factors = (1, 1, 1)
    if refine and isinstance(grid, (pv.ImageData, pv.StructuredGrid)):
        per_point = 4 + (0 if isinstance(grid, pv.ImageData) else 3 * grid.points.itemsize)
        factors = refine_factors(_axis_spacing(grid), grid.dimensions, bytes_per_point=per_point)
    stages = 1 + (max(factors) > 1) + (smooth > 0) + (decimate > 0) + largest + 1
    with progress(progress_bar, stages, "isosurface") as bar:
        if max(factors) > 1:
            grid = _refined(grid, field, factors)
            bar.step("refine slices")
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
            | {"decimate": float(decimate), "largest": bool(largest), "refine": list(factors)}
        )
    ]
    return surf
