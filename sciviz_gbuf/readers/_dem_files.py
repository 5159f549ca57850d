"""Parsers of DEM file formats for :func:`sciviz_gbuf.readers.read_dem`.

Each parser returns a :class:`RawDEM`: float32 heights with NaN at the file's own nodata cells,
row 0 on the north (top) edge, and whatever georeference the file holds. Turning that into
metres per pixel is :mod:`sciviz_gbuf.readers.dem`'s job.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["RawDEM", "read_asc", "read_geotiff", "read_hgt", "read_npz"]

GeoTransform = tuple[float, float, float, float, float, float]

#: Edge lengths (samples) of SRTM ``.hgt`` tiles: SRTM-3 (3 arc-seconds) and SRTM-1 (1 arc-second).
HGT_SIZES = (1201, 3601)
#: Void value of SRTM ``.hgt`` tiles.
HGT_VOID = -32768


@dataclass
class RawDEM:
    """What a file says: heights (NaN at nodata) and its georeference, if any."""

    heights: np.ndarray
    transform: GeoTransform | None = None
    crs: str | None = None
    geographic: bool | None = None


def _blank_nodata(values: np.ndarray, nodata: float | None) -> np.ndarray:
    """Float32 copy of ``values`` with NaN where they equal ``nodata``."""
    heights = np.asarray(values, dtype=np.float32).copy()
    if nodata is not None and np.isfinite(nodata):
        heights[np.asarray(values) == nodata] = np.nan
    return heights


def crs_is_geographic(crs: str | None) -> bool | None:
    """Whether a CRS string (``"EPSG:n"``, WKT or an old ESRI ``.prj``) is geographic.

    ``None`` when it cannot tell (then the caller falls back to the cell size).
    """
    if not crs:
        return None
    s = crs.strip().upper()
    if re.search(r"\bPROJ(CS|CRS)\b", s):
        return False
    if re.search(r"\b(GEOGCS|GEOGCRS|GEODCRS)\b", s) or re.search(r"PROJECTION\s+GEOGRAPHIC", s):
        return True
    if s.startswith("PROJECTION"):  # old ESRI .prj naming a projection
        return False
    try:
        from rasterio.crs import CRS
    except ImportError:
        return {"EPSG:4326": True, "EPSG:4269": True, "EPSG:4258": True}.get(s)
    try:
        return bool(CRS.from_user_input(crs).is_geographic)
    except Exception:
        return None


def read_asc(path: Path) -> RawDEM:
    """ESRI ASCII grid (``.asc``), with the WKT of a ``.prj`` beside it as its CRS."""
    words = path.read_text(encoding="latin-1").split()
    header: dict[str, str] = {}
    i = 0
    while i + 1 < len(words) and re.fullmatch(r"[A-Za-z_]+", words[i]):
        header[words[i].lower()] = words[i + 1]
        i += 2
    try:
        ncols, nrows = int(header["ncols"]), int(header["nrows"])
        if "cellsize" in header:
            dx = dy = float(header["cellsize"])
        else:
            dx, dy = float(header["dx"]), float(header["dy"])
        if "xllcorner" in header:
            x0 = float(header["xllcorner"])
        else:
            x0 = float(header["xllcenter"]) - dx / 2
        if "yllcorner" in header:
            y0 = float(header["yllcorner"])
        else:
            y0 = float(header["yllcenter"]) - dy / 2
        nodata = float(header["nodata_value"]) if "nodata_value" in header else None
    except (KeyError, ValueError) as exc:
        raise InputError(
            f"{path}: not an ESRI ASCII grid: expected a header with ncols, nrows, "
            f"xllcorner|xllcenter, yllcorner|yllcenter, cellsize|dx+dy ({exc!r})"
        ) from exc
    try:
        values = np.array(words[i:], dtype=np.float64)
    except ValueError as exc:
        raise InputError(f"{path}: ESRI ASCII grid holds a non-numeric value ({exc})") from exc
    if values.size != nrows * ncols:
        raise InputError(
            f"{path}: header says nrows={nrows} x ncols={ncols} = {nrows * ncols} values, "
            f"the file holds {values.size} ({values.size / max(ncols, 1):.6g} rows of {ncols})"
        )
    heights = _blank_nodata(values.reshape(nrows, ncols), nodata)
    transform = (x0, dx, 0.0, y0 + nrows * dy, 0.0, -dy)  # rows run north to south
    prj = path.with_suffix(".prj")
    crs = (prj.read_text(encoding="latin-1").strip() or None) if prj.is_file() else None
    return RawDEM(heights, transform, crs, crs_is_geographic(crs))


def read_hgt(path: Path) -> RawDEM:
    """SRTM ``.hgt`` tile: big-endian int16, square, georeferenced by its name (``N10W110``)."""
    size = path.stat().st_size
    n = next((n for n in HGT_SIZES if 2 * n * n == size), None)
    if n is None:
        raise InputError(
            f"{path}: {size} bytes is not an SRTM .hgt tile: expected {2 * 1201**2} bytes "
            f"(1201 x 1201 int16, SRTM-3) or {2 * 3601**2} bytes (3601 x 3601, SRTM-1)"
        )
    m = re.search(r"([NS])(\d{1,2})([EW])(\d{1,3})", path.stem, flags=re.IGNORECASE)
    if m is None:
        raise InputError(
            f"{path}: an .hgt tile is georeferenced by its name: expected e.g. N10W110 "
            "(latitude, longitude of its south-west corner)"
        )
    lat = int(m[2]) * (1 if m[1].upper() == "N" else -1)
    lon = int(m[4]) * (1 if m[3].upper() == "E" else -1)
    values = np.fromfile(path, dtype=">i2").reshape(n, n)
    d = 1.0 / (n - 1)  # edge samples are centred on whole degrees: half a pixel outside
    transform = (lon - d / 2, d, 0.0, lat + 1 + d / 2, 0.0, -d)
    return RawDEM(_blank_nodata(values, HGT_VOID), transform, "EPSG:4326", True)


def read_npz(path: Path) -> RawDEM:
    """``.npz`` like Matplotlib's ``jacksboro_fault_dem.npz``, or holding one 2-D array."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: np.asarray(data[k]) for k in data.files}
    if "elevation" not in arrays:
        grids = [a for a in arrays.values() if a.ndim == 2]
        if len(grids) != 1:
            raise InputError(
                f"{path}: expected an 'elevation' array (with dx, dy, xmin, xmax, ymin, ymax) "
                f"or exactly one 2-D array, found {sorted(arrays)}"
            )
        return RawDEM(np.asarray(grids[0]))
    elev = arrays["elevation"]
    keys = ("dx", "dy", "xmin", "xmax", "ymin", "ymax")
    if not all(k in arrays for k in keys):
        return RawDEM(elev)
    dx, dy, xmin, xmax, ymin, ymax = (float(arrays[k]) for k in keys)
    # Rows run north to south; the bounds are pixel edges. Matplotlib's sample stores the north
    # edge as ``ymin`` (ymin > ymax), so take the larger value as north whichever key holds it.
    west, north = min(xmin, xmax), max(ymin, ymax)
    return RawDEM(elev, (west, abs(dx), 0.0, north, 0.0, -abs(dy)))


def read_geotiff(path: Path) -> RawDEM:
    """Band 1 of a GeoTIFF via rasterio (the ``geo`` extra); no transform if not georeferenced."""
    try:
        import rasterio
        from rasterio.errors import NotGeoreferencedWarning
    except ImportError as exc:
        raise InputError(
            f"{path}: reading GeoTIFF needs rasterio: pip install 'sciviz-gbuf[geo]'"
        ) from exc
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            with rasterio.open(path) as src:
                if src.count >= 3 and all(t == "uint8" for t in src.dtypes):
                    raise InputError(
                        f"{path}: {src.count} uint8 bands look like an RGB(A) image, not a DEM: "
                        "expected one band of heights"
                    )
                values = src.read(1)
                nodata = src.nodata
                crs = src.crs.to_string() if src.crs else None
                geographic = bool(src.crs.is_geographic) if src.crs else None
                georeferenced = crs is not None or not src.transform.is_identity
                transform = src.transform.to_gdal() if georeferenced else None
    except rasterio.errors.RasterioError as exc:
        raise InputError(f"{path}: cannot read as a GeoTIFF ({exc})") from exc
    if transform is None:
        warnings.warn(
            f"{path}: TIFF without georeference: pixels taken as spacing= metres (default 1 m)",
            UserWarning,
            stacklevel=3,
        )
    heights = _blank_nodata(values, nodata)
    return RawDEM(heights, tuple(map(float, transform)) if transform else None, crs, geographic)
