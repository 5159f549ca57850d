"""Bundled sample data: files that ship with PyVista and Matplotlib (nothing is downloaded)."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from .errors import InputError

__all__ = [
    "load_frog_skeleton",
    "load_jacksboro_dem",
    "load_jacksboro_terrain",
    "load_nut",
    "metres_per_degree",
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


def metres_per_degree(latitude: float) -> tuple[float, float]:
    """Lengths of one degree of longitude and of latitude on the WGS84 ellipsoid.

    Uses the standard truncated series for the WGS84 ellipsoid (as tabulated by the U.S.
    National Geospatial-Intelligence Agency), accurate to about a centimetre per degree.

    Parameters
    ----------
    latitude : float
        Geodetic latitude in degrees.

    Returns
    -------
    (float, float)
        Metres per degree of longitude and per degree of latitude at ``latitude``.
    """
    phi = np.radians(latitude)
    lon = 111412.84 * np.cos(phi) - 93.5 * np.cos(3 * phi) + 0.118 * np.cos(5 * phi)
    lat = 111132.92 - 559.82 * np.cos(2 * phi) + 1.175 * np.cos(4 * phi) - 0.0023 * np.cos(6 * phi)
    return float(lon), float(lat)


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

    from .readers import read_dem

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
