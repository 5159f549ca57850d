"""Digital elevation models (DEM grids) -> :class:`DEM`: heights, validity mask, metres per pixel.

A plan-view topographic map (Saito & Takahashi 1990, §4.3) needs no rendering: the DEM grid is
the G-buffer. What it needs is the heights, where they are valid, and the size of a pixel in
metres, also for grids whose cells are given in degrees.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ._dem_files import GeoTransform, RawDEM, crs_is_geographic
from ._dem_model import (
    DEM,
    dem_meta,
    finish_dem,
    is_dataarray,
    is_path_list,
    read_dataarray,
)
from ._lazy import chunk_dem, parse_chunks, read_dem_lazy, reads_lazily
from .formats import FORMATS, suffixes

__all__ = ["DEM", "read_dem"]


def read_dem(
    source: str | os.PathLike | np.ndarray | Any,
    *,
    spacing: float | tuple[float, float] | None = None,
    nodata: float | None = None,
    transform: GeoTransform | None = None,
    crs: str | None = None,
    geographic: bool | None = None,
    chunks: int | tuple[int, int] | str | None = None,
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

    - ``.dem`` USGS ASCII DEM (Type A header record + one Type B record per south-to-north
      profile) through VTK's ``vtkDEMReader``. Cells outside the profiles (the corners of a
      quadrangle) are nodata. Heights are in metres (feet converted with 0.3048); ground units
      in arc-seconds or radians give a geographic grid in degrees, metres or feet a projected
      one (no CRS: the zone and datum are not read; in feet, :attr:`DEM.pixel_size` is still
      metres). Like VTK, a profile is placed by its row id, not by its first sample's y.

    A 2-D numpy array is read as heights with row 0 north. A 2-D ``xarray.DataArray`` (xarray
    is not needed otherwise) with dims ``x``/``y``, ``lon``/``lat`` or ``longitude``/``latitude``
    (any order) is read with the transform of its evenly spaced pixel-centre coordinates, turned
    north up and east right; lon/lat dims make it geographic. Its CRS comes from rioxarray's
    ``.rio.crs``, an attribute ``crs``, or a ``spatial_ref`` coordinate (``crs_wkt``); its
    nodata from the attributes ``_FillValue`` or ``nodata`` (or ``encoding["_FillValue"]``).

    Geographic grids (a geographic CRS, or explicitly ``geographic=True``) get metres per degree
    from :func:`sciviz_gbuf.datasets.metres_per_degree` (WGS84 ellipsoid series) at the latitude
    of the grid centre: ``dx_m = |dx| * m_lon(lat)``, ``dy_m = |dy| * m_lat(lat)``. This is
    GDAL's ``gdaldem -s 111120`` convention made per axis: ``m_lat`` runs from 110 574 m
    (equator) to 111 694 m (poles), within 0.5 % of 111 120; ``m_lon`` is within 0.35 % of
    ``111 320 * cos(lat)`` up to 80° (about 85 207 m per degree at 40.15° N, 111 037 m in latitude).
    Without a CRS, a grid whose whole extent fits in longitude/latitude range and whose cells
    are at most 0.1 units is taken as degrees, with a :class:`UserWarning` (pass
    ``geographic=False`` if they are metres). Degrees are never silently taken as metres.

    **Out of core** (``chunks=``): the returned DEM's ``heights`` is a lazy float32 dask array
    of the same values, read chunk by chunk when computed (only the metadata is read here), and
    ``mask`` is ``da.isfinite(heights)``; transform, CRS and metres per pixel are the same as in
    memory. Files GDAL opens (GeoTIFF, VRT, ``.hgt``, ``.asc``, any other raster rasterio reads)
    are read by rasterio windows, one per chunk and file, in whichever process computes the
    chunk (the dask graph holds only file names, so it runs on ``dask.distributed`` workers
    too). A list of tiles (e.g. SRTM ``.hgt`` tiles, or GeoTIFFs of one CRS and resolution on
    one pixel grid) becomes one lazy mosaic of their union: overlapping cells (SRTM tiles share
    their edge rows and columns) take any tile's valid value, gaps are NaN. A DataArray backed
    by dask stays lazy. ``.npy``, ``.npz``, ``.dem`` files and numpy arrays have no windowed
    reads: they are read whole, then chunked.

    Parameters
    ----------
    source : str, path-like, sequence of them, numpy.ndarray or xarray.DataArray
        A file (only read, never modified), a list of tiles of one CRS and resolution (read as
        one mosaic; computed into memory without ``chunks``), a 2-D array of heights or a
        georeferenced 2-D DataArray.
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
    chunks : int, (int, int) or "auto", optional
        Read lazily into a dask array of chunks of this many ``(rows, columns)`` (one int:
        square chunks; ``"auto"``: dask's choice), like rioxarray's ``open_rasterio(chunks=)``.
        Default: read into memory.

    Returns
    -------
    DEM

    Raises
    ------
    InputError
        Missing file, unknown extension, a file that does not hold what its format says
        (truncated ``.hgt``, ``.asc`` rows/columns not as its header says, an RGB TIFF, a
        truncated or garbled ``.dem``), an array that is not 2-D and numeric, a DataArray
        without x/y (lon/lat) coordinates or with unevenly spaced ones,
        conflicting/invalid ``spacing``/``transform``, a bad ``chunks`` value, or tiles of
        different CRS, resolution or pixel grids.
    """
    options = {"spacing": spacing, "nodata": nodata, "transform": transform, "crs": crs}
    if chunks is not None or is_path_list(source):
        if not reads_lazily(source):  # nothing to read by windows: read whole, then chunk
            dchunks = "auto" if chunks is None else parse_chunks(chunks)
            return chunk_dem(read_dem(source, geographic=geographic, **options), dchunks)
        dem = read_dem_lazy(source, chunks=chunks, geographic=geographic, **options)
        if chunks is None:  # a list of tiles, wanted in memory
            heights = dem.heights.compute()
            return DEM(heights, np.isfinite(heights), *dem_meta(dem))
        return dem
    name: str | None = None
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        name = str(path)
        if not path.is_file():
            raise InputError(f"{path}: no such DEM file")
        suffix = path.suffix.lower()
        fmt = FORMATS.get(suffix)
        if fmt is None or fmt.kind != "dem":
            raise InputError(
                f"{path}: unknown DEM extension {suffix!r}: expected one of "
                f"{', '.join(suffixes('dem'))}"
            )
        raw = fmt.read_raw(path)
        if raw.transform is not None and (transform is not None or crs is not None):
            raise InputError(f"{path}: transform=/crs= are for sources without a georeference")
    elif is_dataarray(source):
        name = f"DataArray {getattr(source, 'name', None)!r}"
        raw, da_nodata = read_dataarray(source, name)
        if transform is not None or crs is not None:
            raise InputError(f"{name}: transform=/crs= are for sources without a georeference")
        if da_nodata is not None:
            raw.heights = np.where(raw.heights == da_nodata, np.nan, raw.heights)
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
    owned = isinstance(source, (str, os.PathLike))  # a fresh array read from a file
    return finish_dem(raw, name, spacing=spacing, nodata=nodata, geographic=geographic, owned=owned)
