"""Bundled sample data: files that ship with PyVista and Matplotlib (nothing is downloaded)."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from . import _dask
from .errors import InputError
from .readers import DEM, metres_per_degree, read_dem

__all__ = [
    "load_frog_body",
    "load_frog_skeleton",
    "load_jacksboro_dem",
    "load_jacksboro_terrain",
    "load_nut",
    "metres_per_degree",
    "synthetic_dem",
]


def load_nut() -> pv.PolyData:
    """The nut mesh that ships with PyVista (``pyvista/examples/nut.ply``).

    Returns
    -------
    pyvista.PolyData
        A triangulated hexagonal nut, about 46 units across.
    """
    from pyvista import examples

    return examples.load_nut()


def _jacksboro_npz() -> dict[str, np.ndarray]:
    from matplotlib import cbook

    # Matplotlib >= 3.8 returns the loaded NpzFile; older versions a file object.
    data = cbook.get_sample_data("jacksboro_fault_dem.npz")
    if not hasattr(data, "files"):
        data = np.load(data)
    with data:
        return {k: np.asarray(data[k]) for k in data.files}


def load_jacksboro_terrain(*, vert_exag: float = 1.0) -> pv.StructuredGrid:
    """The Jacksboro fault DEM (Tennessee, USA) from Matplotlib's sample data, in metres.

    The DEM is a 344 x 403 grid of elevations in metres on a 3 arc-second geographic grid;
    its rows run north to south. It is mapped to a local plane with an equirectangular
    projection about the grid's mean latitude, using the WGS84 lengths of a degree
    (:func:`metres_per_degree`, about 89 480 m per degree of longitude and 110 960 m per
    degree of latitude there). Grid points are the sample (pixel) centres.

    Parameters
    ----------
    vert_exag : float, default: 1.0
        Vertical exaggeration (matplotlib's name): ``z = elevation * vert_exag``.

    Returns
    -------
    pyvista.StructuredGrid
        A surface of 403 x 344 points: ``x`` eastwards in metres from the westernmost sample,
        ``y`` northwards in metres from the southernmost sample (north is +y), ``z`` the
        exaggerated elevation. Point array ``"elevation"`` (float32) holds the elevation in
        metres, not exaggerated.

    Raises
    ------
    InputError
        If ``vert_exag`` is not a finite positive number.
    """
    if not (np.isfinite(vert_exag) and vert_exag > 0):
        raise InputError(f"vert_exag: expected a finite positive number, got {vert_exag!r}")
    dem = _jacksboro_npz()
    # Flip so row 0 is the southernmost row: y then grows northwards with the row index.
    elev = dem["elevation"][::-1].astype(np.float32)
    rows, cols = elev.shape
    north, south = float(dem["ymin"]), float(dem["ymax"])  # the file's ymin is the north edge
    m_lon, m_lat = metres_per_degree(0.5 * (north + south))
    x = np.arange(cols) * float(dem["dx"]) * m_lon
    y = np.arange(rows) * float(dem["dy"]) * m_lat
    xx, yy = np.meshgrid(x, y)
    zz = elev.astype(np.float64) * float(vert_exag)
    # PyVista reads meshgrid arrays in Fortran order: transposed to (cols, rows), the grid's i
    # index runs east and its points are the C order of the (rows, cols) arrays.
    grid = pv.StructuredGrid(xx.T, yy.T, zz.T)
    grid.point_data["elevation"] = elev.ravel()
    return grid


def load_jacksboro_dem():
    """The Jacksboro fault DEM from Matplotlib's sample data as a
    :class:`~sciviz_gbuf.readers.DEM`: 344 x 403 cells of 3 arc-seconds, WGS84 (``EPSG:4326``).

    The bundled default of the terrain commands; nothing is downloaded.
    """
    import dataclasses

    from matplotlib import cbook

    path = cbook.get_sample_data("jacksboro_fault_dem.npz", asfileobj=False)
    return dataclasses.replace(read_dem(path, geographic=True), crs="EPSG:4326")


#: Label of the skeleton in ``pyvista.examples.load_frog_tissues()``.
FROG_SKELETON = 13


def load_frog_skeleton(*, sigma: float = 1.0) -> pv.ImageData:
    """The frog's skeleton from PyVista's bundled segmented frog MRI (500 x 470 x 136 voxels).

    The label volume is turned into a smooth occupancy field: 1 inside the skeleton label, 0
    outside, blurred by a Gaussian of ``sigma`` voxels so that its 0.5 isosurface is smooth
    instead of following the voxel staircase (the usual way to surface a segmentation).

    Returns
    -------
    pyvista.ImageData
        Point array ``"skeleton"`` (float32 in [0, 1]); cut it at ``iso=0.5``.
    """
    from pyvista import examples
    from scipy.ndimage import gaussian_filter

    tissues = examples.load_frog_tissues()
    labels = np.asarray(tissues.point_data.active_scalars)
    nx, ny, nz = tissues.dimensions
    occupancy = (labels == FROG_SKELETON).astype(np.float32).reshape(nz, ny, nx)
    if sigma > 0:
        # Spacing is anisotropic (1, 1, 1.5): blur by the same physical width in every axis.
        sx, _, sz = tissues.spacing
        occupancy = gaussian_filter(occupancy, sigma=(sigma * sx / sz, sigma, sigma))
    out = pv.ImageData(
        dimensions=tissues.dimensions, spacing=tissues.spacing, origin=tissues.origin
    )
    out.point_data["skeleton"] = occupancy.reshape(-1)
    return out


def load_frog_body(*, flesh: float = 4.0) -> pv.ImageData:
    """An envelope of PyVista's bundled segmented frog: every labelled tissue (organs and
    skeleton) grown by ``flesh`` mm and its cavities filled, blurred: a stand-in for the skin,
    which the segmentation does not label (for translucent-skin views over
    :func:`load_frog_skeleton`). Made on every other voxel in-plane (2 x 2 x 1.5 mm).

    Returns
    -------
    pyvista.ImageData
        Point array ``"body"`` (float32 in [0, 1]); cut it at ``iso=0.5``.
    """
    from pyvista import examples
    from scipy import ndimage

    flesh = float(flesh)
    if not 0.0 <= flesh <= 50.0:
        raise InputError(f"flesh: expected millimetres in [0, 50], got {flesh!r}")
    tissues = examples.load_frog_tissues()
    labels = np.asarray(tissues.point_data.active_scalars)
    nx, ny, nz = tissues.dimensions
    sx, sy, sz = tissues.spacing
    occupied = (labels > 0).reshape(nz, ny, nx)[:, ::2, ::2]
    spacing = (sz, 2 * sy, 2 * sx)
    body = ndimage.distance_transform_edt(~occupied, sampling=spacing) <= flesh
    body = ndimage.binary_fill_holes(body)
    field = ndimage.gaussian_filter(body.astype(np.float32), sigma=(2.0 / sz, 1.0, 1.0))
    out = pv.ImageData(
        dimensions=(field.shape[2], field.shape[1], field.shape[0]),
        spacing=(2 * sx, 2 * sy, sz),
        origin=tissues.origin,
    )
    out.point_data["body"] = field.reshape(-1)
    return out


def synthetic_dem(shape: tuple[int, int], *, chunks: int | tuple[int, int] = 2048, seed: int = 0):
    """A lazy synthetic DEM of any size, generated chunk by chunk and never held whole.

    Ridges and valleys of eight octaves of rotated sine waves (wavelengths 40 cells to 5000
    cells, amplitude falling as the wavelength) plus a little per-cell noise, about 0 to 3000
    m, on 30 m cells. Each cell is a function of its global row and column only, so the heights
    do not depend on the chunking (``synthetic_dem(s, chunks=a).compute()`` equals it with
    ``chunks=b``) and ``numpy.asarray`` of a small one gives the in-memory reference of a large
    one's corner.

    Parameters
    ----------
    shape : (int, int)
        Rows, columns (each >= 1).
    chunks : int or (int, int), default: 2048
    seed : int, default: 0
        Phases and directions of the waves.

    Returns
    -------
    sciviz_gbuf.readers.DEM
        Heights a float32 dask array; 30 m pixels, projected (no CRS), north-up transform with
        the origin at (0, 0).
    """
    import dask.array as da

    try:
        rows, cols = (int(v) for v in shape)
    except (TypeError, ValueError):
        rows = cols = 0
    if rows < 1 or cols < 1:
        raise InputError(f"shape: expected two integers >= 1 (rows, columns), got {shape!r}")
    rng = np.random.default_rng(seed)
    octaves = 8
    wavelengths = np.geomspace(5000.0, 40.0, octaves)
    angles = rng.uniform(0.0, np.pi, (octaves, 2))
    phases = rng.uniform(0.0, 2 * np.pi, (octaves, 2))
    amps = 600.0 * (wavelengths / wavelengths[0]) ** 0.8

    generator = _SyntheticHeights(wavelengths, angles, phases, amps)

    def block(block_info=None) -> np.ndarray:
        (r0, r1), (c0, c1) = block_info[None]["array-location"]
        return generator[r0:r1, c0:c1]

    heights = da.map_blocks(
        block, chunks=da.core.normalize_chunks(chunks, (rows, cols)), dtype=np.float32,
        meta=np.empty((0, 0), np.float32),
    )  # fmt: skip
    _dask.register_windows(heights, generator)  # out-of-core maps read windows with halos
    transform = (0.0, 30.0, 0.0, 30.0 * rows, 0.0, -30.0)
    return DEM(heights, da.isfinite(heights), None, transform, (30.0, 30.0), False, "synthetic")


class _SyntheticHeights:
    """The heights of :func:`synthetic_dem` in any window: ``self[r0:r1, c0:c1]``, a function of
    the global rows and columns only (picklable: numbers only)."""

    def __init__(self, wavelengths, angles, phases, amps) -> None:
        self.wavelengths, self.angles, self.phases, self.amps = wavelengths, angles, phases, amps

    def __getitem__(self, key: tuple[slice, slice]) -> np.ndarray:
        (r0, r1), (c0, c1) = ((k.start or 0, k.stop) for k in key)
        wavelengths, angles, phases, amps = self.wavelengths, self.angles, self.phases, self.amps
        octaves = len(wavelengths)
        r = np.arange(r0, r1, dtype=np.float64)
        c = np.arange(c0, c1, dtype=np.float64)
        z = np.full((r1 - r0, c1 - c0), 1500.0, dtype=np.float32)
        for k in range(octaves):
            # sin(f u + p) cos(g v + q), u and v linear in (c, r), expanded into rank-1 terms
            # of row and column vectors: a few full-size multiply-adds per octave
            f = 2 * np.pi / wavelengths[k]
            (a0, b0), (a1, b1) = np.cos(angles[k]), np.sin(angles[k])
            su_c, cu_c = np.sin(f * a0 * c + phases[k, 0]), np.cos(f * a0 * c + phases[k, 0])
            su_r, cu_r = np.sin(f * a1 * r), np.cos(f * a1 * r)
            sv_c, cv_c = (
                np.sin(0.7 * f * b0 * c + phases[k, 1]),
                np.cos(0.7 * f * b0 * c + phases[k, 1]),
            )
            sv_r, cv_r = np.sin(0.7 * f * b1 * r), np.cos(0.7 * f * b1 * r)
            # sin(U_c + U_r) = su_c cu_r + cu_c su_r; cos(V_c + V_r) = cv_c cv_r - sv_c sv_r
            for col_u, row_u in ((su_c, cu_r), (cu_c, su_r)):
                for col_v, row_v, sign in ((cv_c, cv_r, 1.0), (sv_c, sv_r, -1.0)):
                    rows_ = (amps[k] * sign * row_u * row_v).astype(np.float32)
                    z += rows_[:, None] * (col_u * col_v).astype(np.float32)[None, :]
        # per-cell noise from a hash of the global index (no state shared between chunks)
        h = (r.astype(np.uint64)[:, None] * np.uint64(73856093)) ^ (
            c.astype(np.uint64)[None, :] * np.uint64(19349663)
        )
        h = (h * np.uint64(2654435761)) % np.uint64(1 << 31)
        z += (h * (2.0 / float(1 << 31)) - 1.0).astype(np.float32)
        return z
