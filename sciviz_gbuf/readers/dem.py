"""Digital elevation models (DEM grids) -> :class:`DEM`: heights, validity mask, metres per pixel.

A plan-view topographic map (Saito & Takahashi 1990, §4.3) needs no rendering: the DEM grid is
the G-buffer. What it needs is the heights, where they are valid, and the size of a pixel in
metres, also for grids whose cells are given in degrees.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..datasets import metres_per_degree
from ..errors import InputError
from ._dem_files import (
    GeoTransform,
    RawDEM,
    crs_is_geographic,
    read_asc,
    read_geotiff,
    read_hgt,
    read_npz,
)

__all__ = ["DEM", "read_dem"]

_READERS = {
    ".asc": read_asc,
    ".hgt": read_hgt,
    ".npz": read_npz,
    ".tif": read_geotiff,
    ".tiff": read_geotiff,
}


@dataclass(frozen=True, eq=False)
class DEM:
    """A DEM grid, north up, with its georeference and metres per pixel.

    Attributes
    ----------
    heights : numpy.ndarray
        float32 (H, W) heights (in the file's unit, normally metres); NaN at nodata cells.
        Row 0 is the northern (top) row, as in an image.
    mask : numpy.ndarray
        bool (H, W), True where the height is valid (finite).
    crs : str or None
        The coordinate reference system as the source gives it (``"EPSG:4326"``, WKT), if any.
    transform : tuple of 6 float
        GDAL geotransform ``(x0, dx, rx, y0, ry, dy)`` of the pixel *corners*: the corner of
        column ``c``, row ``r`` lies at ``(x0 + c*dx + r*rx, y0 + c*ry + r*dy)`` in CRS units
        (degrees for geographic grids); ``dy`` is negative for north-up grids.
    pixel_size : (float, float)
        Metres per pixel ``(dx_m, dy_m)`` along a row and down a column, both positive.
    geographic : bool
        True if the grid's cells are in degrees of longitude and latitude.
    source : str or None
        The file read, or None for an in-memory array.
    """

    heights: np.ndarray
    mask: np.ndarray
    crs: str | None
    transform: GeoTransform
    pixel_size: tuple[float, float]
    geographic: bool
    source: str | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)``: rows, columns."""
        return self.heights.shape

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(west, east, south, north)`` pixel-edge extent in CRS units (unrotated grids)."""
        x0, dx, _, y0, _, dy = self.transform
        h, w = self.shape
        xs, ys = (x0, x0 + w * dx), (y0, y0 + h * dy)
        return min(xs), max(xs), min(ys), max(ys)


def read_dem(
    source: str | os.PathLike | np.ndarray,
    *,
    spacing: float | tuple[float, float] | None = None,
    nodata: float | None = None,
    transform: GeoTransform | None = None,
    crs: str | None = None,
    geographic: bool | None = None,
) -> DEM:
    """Read a DEM file or array into a north-up :class:`DEM` with metres per pixel.

    Formats, by the file's extension:

    - ``.asc`` ESRI ASCII grid (case-insensitive header ``ncols``, ``nrows``,
      ``xllcorner|xllcenter``, ``yllcorner|yllcenter``, ``cellsize`` or ``dx`` + ``dy``,
      ``NODATA_value``); the WKT of a ``.prj`` file beside it becomes :attr:`DEM.crs`.
    - ``.hgt`` SRTM tile: big-endian int16, 1201² (SRTM-3) or 3601² (SRTM-1) samples, voids
      -32768; georeferenced by its name (``N10W110``: south-west corner at 10° N, 110° W; the
      edge samples are centred on whole degrees), CRS ``"EPSG:4326"``.
    - ``.npy`` one 2-D array without georeference (see ``spacing``).
    - ``.npz`` like Matplotlib's ``jacksboro_fault_dem.npz`` (``elevation``, ``dx``, ``dy``,
      ``xmin``, ``xmax``, ``ymin``, ``ymax`` as pixel-edge bounds, rows north to south; the larger
      of ``ymin``/``ymax`` is taken as north since that file stores them swapped), or one 2-D array.
    - ``.tif``/``.tiff`` GeoTIFF, band 1, with its nodata, CRS and transform; needs rasterio
      (``pip install 'sciviz-gbuf[geo]'``). Three or more uint8 bands (an RGB image) are an
      error; a TIFF without georeference is read like an array with a :class:`UserWarning`.

    A 2-D numpy array is read as heights with row 0 north.

    Geographic grids (a geographic CRS, or explicitly ``geographic=True``) get metres per degree
    from :func:`sciviz_gbuf.datasets.metres_per_degree` (WGS84 ellipsoid series) at the latitude
    of the grid centre: ``dx_m = |dx| * m_lon(lat)``, ``dy_m = |dy| * m_lat(lat)``. This is
    GDAL's ``gdaldem -s 111120`` convention made per axis: ``m_lat`` runs from 110 574 m
    (equator) to 111 694 m (poles), within 0.5 % of 111 120; ``m_lon`` is within 0.35 % of
    ``111 320 * cos(lat)`` up to 80° (about 85 207 m per degree at 40.15° N, 111 037 m in latitude).
    Without a CRS, a grid whose whole extent fits in longitude/latitude range and whose cells
    are at most 0.1 units is taken as degrees, with a :class:`UserWarning` (pass
    ``geographic=False`` if they are metres). Degrees are never silently taken as metres.

    Parameters
    ----------
    source : str, path-like or numpy.ndarray
        A file (only read, never modified) or a 2-D array of heights.
    spacing : float or (float, float), optional
        Metres per pixel ``(dx, dy)`` (one number for square pixels) for sources without a
        georeference (arrays, ``.npy``, plain TIFF). **Default 1 m**, the pixel grid. An error
        for georeferenced sources or together with ``transform``.
    nodata : float, optional
        A further value to mask (NaN), besides the file's own nodata and non-finite values.
    transform : tuple of 6 float, optional
        GDAL geotransform for an array or ``.npy`` source (see :attr:`DEM.transform`).
    crs : str, optional
        CRS of an array or ``.npy`` source, e.g. ``"EPSG:4326"``.
    geographic : bool, optional
        Whether the georeference is in degrees; default: from the CRS, else from the cell size.

    Returns
    -------
    DEM

    Raises
    ------
    InputError
        Missing file, unknown extension, a file that does not hold what its format says
        (truncated ``.hgt``, ``.asc`` rows/columns not as its header says, an RGB TIFF), an array
        that is not 2-D and numeric, or conflicting/invalid ``spacing``/``transform``.
    """
    name: str | None = None
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        name = str(path)
        if not path.is_file():
            raise InputError(f"{path}: no such DEM file")
        suffix = path.suffix.lower()
        if suffix == ".npy":
            raw = RawDEM(np.load(path, allow_pickle=False))
        elif suffix in _READERS:
            raw = _READERS[suffix](path)
        else:
            raise InputError(
                f"{path}: unknown DEM extension {suffix!r}: expected one of "
                f"{', '.join(sorted([*_READERS, '.npy']))}"
            )
        if raw.transform is not None and (transform is not None or crs is not None):
            raise InputError(f"{path}: transform=/crs= are for sources without a georeference")
    else:
        raw = RawDEM(np.asarray(source))
    if raw.transform is None:
        raw.transform, raw.crs = transform, crs
        raw.geographic = crs_is_geographic(crs)
    elif spacing is not None:
        raise InputError(
            f"{name}: spacing= is for sources without a georeference; this one has "
            f"transform {raw.transform}"
        )
    return _finish(raw, name, spacing=spacing, nodata=nodata, geographic=geographic)


def _heights(values: np.ndarray, name: str | None, nodata: float | None) -> np.ndarray:
    """Check a 2-D numeric array; float32 copy with NaN at ``nodata`` and non-finite values."""
    what = name or "array"
    if values.ndim != 2 or min(values.shape) == 0:
        raise InputError(
            f"{what}: expected a non-empty 2-D array of heights, got shape {values.shape}"
        )
    if not (np.issubdtype(values.dtype, np.number) and not np.iscomplexobj(values)):
        raise InputError(f"{what}: expected real numeric heights, got dtype {values.dtype}")
    heights = np.array(values, dtype=np.float32)
    if nodata is not None:
        heights[np.asarray(values) == nodata] = np.nan
    heights[~np.isfinite(heights)] = np.nan
    return heights


def _spacing_transform(spacing, shape: tuple[int, int], name: str | None) -> GeoTransform:
    """Metric transform of a grid without georeference, origin at the south-west corner."""
    dx, dy = np.broadcast_to(np.asarray(1.0 if spacing is None else spacing, float), (2,))
    if not (np.isfinite([dx, dy]).all() and dx > 0 and dy > 0):
        raise InputError(f"{name or 'array'}: spacing must be positive metres, got {spacing!r}")
    return (0.0, float(dx), 0.0, shape[0] * float(dy), 0.0, -float(dy))


def _looks_geographic(transform: GeoTransform, shape: tuple[int, int]) -> bool:
    """Cells <= 0.1 units and the whole extent inside longitude/latitude range."""
    x0, dx, rx, y0, ry, dy = transform
    h, w = shape
    xs = [x0 + c * dx + r * rx for c in (0, w) for r in (0, h)]
    ys = [y0 + c * ry + r * dy for c in (0, w) for r in (0, h)]
    small = max(abs(dx), abs(dy)) <= 0.1
    return small and min(xs) >= -180 and max(xs) <= 360 and min(ys) >= -90 and max(ys) <= 90


def _finish(raw: RawDEM, name: str | None, *, spacing, nodata, geographic) -> DEM:
    heights = _heights(np.asarray(raw.heights), name, nodata)
    shape = heights.shape
    if raw.transform is None:
        if geographic:
            raise InputError(f"{name or 'array'}: geographic=True needs a transform= in degrees")
        transform, geo = _spacing_transform(spacing, shape, name), False
    else:
        if spacing is not None:
            raise InputError(f"{name or 'array'}: give either spacing= or transform=, not both")
        transform = tuple(float(v) for v in raw.transform)
        if len(transform) != 6 or not np.isfinite(transform).all() or transform[1] == 0:
            raise InputError(
                f"{name or 'array'}: expected a GDAL 6-tuple transform, got {transform}"
            )
        geo = geographic if geographic is not None else raw.geographic
        if geo is None:
            geo = _looks_geographic(transform, shape)
            if geo:
                warnings.warn(
                    f"{name or 'array'}: no CRS, and cells of {transform[1]:g} x "
                    f"{abs(transform[5]):g} units within longitude/latitude range: taken as "
                    "degrees (pass geographic=False if they are metres)",
                    UserWarning,
                    stacklevel=3,
                )
    _, dx, rx, y0, ry, dy = transform
    if geo:
        h, w = shape
        m_lon, m_lat = metres_per_degree(y0 + ry * w / 2 + dy * h / 2)
        pixel = (float(np.hypot(dx * m_lon, ry * m_lat)), float(np.hypot(rx * m_lon, dy * m_lat)))
    else:
        pixel = (float(np.hypot(dx, ry)), float(np.hypot(rx, dy)))
    return DEM(heights, np.isfinite(heights), raw.crs, transform, pixel, bool(geo), name)
