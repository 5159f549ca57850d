"""Parsers of DEM file formats for :func:`sciviz_gbuf.readers.read_dem`.

Each parser returns a :class:`RawDEM`: float32 heights with NaN at the file's own nodata cells,
row 0 on the north (top) edge, and whatever georeference the file holds. Turning that into
metres per pixel is :mod:`sciviz_gbuf.readers.dem`'s job.
"""

from __future__ import annotations

import os
import re
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._atomic import one_line
from ..errors import InputError

__all__ = [
    "MAX_CELLS",
    "RawDEM",
    "blank_nodata",
    "crs_is_geographic",
    "raster_georeference",
    "read_asc",
    "read_geotiff",
    "read_hgt",
    "read_npy",
    "read_npz",
    "read_usgs_dem",
]

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
    #: Metres per CRS unit of a projected grid (0.3048 for a grid in feet).
    unit_metres: float = 1.0


def blank_nodata(values: np.ndarray, nodata: float | None, *, owned: bool = False) -> np.ndarray:
    """Float32 ``values`` with NaN where they equal ``nodata``: a copy, or ``values`` itself
    changed in place when ``owned`` (a fresh array of this reader) and already float32."""
    values = np.asarray(values)
    if owned and values.dtype == np.float32:
        heights = values
    else:
        heights = values.astype(np.float32)
    if nodata is not None and np.isfinite(nodata):
        # Compared in the source type: a float32 cast could merge nodata with a close height.
        np.putmask(heights, values == nodata, np.float32(np.nan))
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
    if ncols < 1 or nrows < 1:
        raise InputError(f"{path}: ncols, nrows: expected positive counts, got {ncols}, {nrows}")
    if not (np.isfinite([dx, dy, x0, y0]).all() and dx > 0 and dy > 0):
        raise InputError(
            f"{path}: cellsize: expected a finite cell size > 0 and a finite corner, got "
            f"dx={dx:g}, dy={dy:g}, corner ({x0:g}, {y0:g})"
        )
    _check_cells(path, (nrows, ncols), "its header declares shape")
    try:
        values = np.array(words[i:], dtype=np.float64)
    except ValueError as exc:
        raise InputError(f"{path}: ESRI ASCII grid holds a non-numeric value ({exc})") from exc
    if values.size != nrows * ncols:
        raise InputError(
            f"{path}: header says nrows={nrows} x ncols={ncols} = {nrows * ncols} values, "
            f"the file holds {values.size} ({values.size / max(ncols, 1):.6g} rows of {ncols})"
        )
    heights = blank_nodata(values.reshape(nrows, ncols), nodata)
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
    if not (-90 <= lat <= 89 and -180 <= lon <= 179):
        raise InputError(
            f"{path}: tile name {m[0]!r}: expected the south-west corner of a 1-degree tile, "
            "latitude N89..S90, longitude W180..E179"
        )
    values = np.fromfile(path, dtype=">i2").reshape(n, n)
    d = 1.0 / (n - 1)  # edge samples are centred on whole degrees: half a pixel outside
    transform = (lon - d / 2, d, 0.0, lat + 1 + d / 2, 0.0, -d)
    return RawDEM(blank_nodata(values, HGT_VOID), transform, "EPSG:4326", True)


#: Largest DEM a file may declare, in cells (a 64k x 64k grid is 16 GiB of float32): beyond it the
#: out-of-core reader (``read_dem(chunks=)``) is the way, and a lying header is refused before
#: anything is allocated.
MAX_CELLS = 2**32


def _check_cells(who: object, shape: tuple[int, ...], what: str) -> None:
    """A declared array shape: 2-D, positive, not absurdly large (before any allocation)."""
    if len(shape) != 2 or min(shape, default=0) < 1:
        raise InputError(f"{who}: expected a non-empty 2-D array of heights, {what} {shape}")
    if shape[0] * shape[1] > MAX_CELLS:
        raise InputError(
            f"{who}: {what} {shape} ({shape[0] * shape[1]:.3g} cells) is larger than the "
            f"{MAX_CELLS:.3g} cells read into memory: use read_dem(..., chunks=) or a GeoTIFF"
        )


def _npy_header(
    f, path: Path, where: str = "", *, grid: bool = True
) -> tuple[tuple[int, ...], np.dtype, int]:
    """Shape, dtype and data offset of a ``.npy`` stream, checked (nothing else is read):
    real numeric, at most :data:`MAX_CELLS` values, and 2-D if ``grid``."""
    fmt = np.lib.format
    try:
        version = fmt.read_magic(f)
        if version == (1, 0):
            shape, _, dtype = fmt.read_array_header_1_0(f)
        else:
            shape, _, dtype = fmt.read_array_header_2_0(f)
    except Exception as exc:  # numpy's header parser raises many types on damaged bytes
        why = one_line(str(exc)) or type(exc).__name__
        raise InputError(f"{path}{where}: not a NumPy .npy array ({why})") from exc
    if dtype.hasobject or not (
        np.issubdtype(dtype, np.integer)
        or np.issubdtype(dtype, np.floating)
        or np.issubdtype(dtype, np.bool_)
    ):
        raise InputError(f"{path}{where}: expected real numeric heights, got dtype {dtype}")
    shape = tuple(shape)
    if grid:
        _check_cells(f"{path}{where}", shape, "its header declares shape")
    elif int(np.prod(shape, dtype=np.float64)) > MAX_CELLS:
        raise InputError(f"{path}{where}: its header declares {shape}: too large to read")
    return shape, dtype, f.tell()


def read_npy(path: Path) -> RawDEM:
    """A ``.npy`` file holding one 2-D array of heights (no georeference; pickles refused).

    The header is checked first (2-D, real numeric dtype, a size the file can hold), so a
    truncated or lying file is an InputError, not a MemoryError or a partial read."""
    with open(path, "rb") as f:
        shape, dtype, offset = _npy_header(f, path)
    need = offset + int(np.prod(shape)) * dtype.itemsize
    size = path.stat().st_size
    if size < need:
        raise InputError(
            f"{path}: truncated .npy: its header declares {shape} {dtype} ({need} bytes), "
            f"the file has {size}"
        )
    try:
        return RawDEM(np.load(path, allow_pickle=False))
    except (ValueError, EOFError, OSError) as exc:
        raise InputError(f"{path}: cannot read as a NumPy .npy array ({exc})") from exc


def _scalar(value: np.ndarray, path: Path, key: str) -> float:
    v = np.asarray(value)
    try:
        x = float(v) if v.ndim == 0 or v.size == 1 else float("nan")
    except (TypeError, ValueError):
        x = float("nan")
    if not np.isfinite(x):
        raise InputError(f"{path}: {key}: expected a finite number, got {value!r:.60}")
    return x


def read_npz(path: Path) -> RawDEM:
    """``.npz`` like Matplotlib's ``jacksboro_fault_dem.npz``, or holding one 2-D array.

    Every member's ``.npy`` header is checked before it is decompressed; a damaged archive
    (not a zip, a CRC or deflate error, a truncated member) is an InputError naming the file."""
    import zipfile
    import zlib

    try:
        with zipfile.ZipFile(path) as zf:
            for info in zf.infolist():
                with zf.open(info) as f:
                    _npy_header(f, path, f": member {info.filename!r}", grid=False)
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in data.files}
    except InputError:
        raise
    except (zipfile.BadZipFile, zlib.error, ValueError, EOFError, OSError, KeyError) as exc:
        raise InputError(f"{path}: not a readable NumPy .npz archive ({exc})") from exc
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
    dx, dy, xmin, xmax, ymin, ymax = (_scalar(arrays[k], path, k) for k in keys)
    if dx == 0 or dy == 0:
        raise InputError(f"{path}: dx, dy: expected non-zero cell sizes, got {dx}, {dy}")
    # Rows run north to south; the bounds are pixel edges. Matplotlib's sample stores the north
    # edge as ``ymin`` (ymin > ymax), so take the larger value as north whichever key holds it.
    west, north = min(xmin, xmax), max(ymin, ymax)
    return RawDEM(elev, (west, abs(dx), 0.0, north, 0.0, -abs(dy)))


def raster_georeference(src, path: Path) -> tuple[str | None, bool | None, tuple | None]:
    """``(crs, geographic, GDAL transform or None)`` of an open rasterio dataset that holds a
    DEM; InputError for an RGB(A) image (three or more uint8 bands)."""
    dtype = np.dtype(src.dtypes[0])
    if not np.issubdtype(dtype, np.number) or np.issubdtype(dtype, np.complexfloating):
        raise InputError(f"{path}: expected real numeric heights, got a {dtype} band")
    if src.count >= 3 and all(t == "uint8" for t in src.dtypes):
        raise InputError(
            f"{path}: {src.count} uint8 bands look like an RGB(A) image, not a DEM: "
            "expected one band of heights"
        )
    crs = src.crs.to_string() if src.crs else None
    geographic = bool(src.crs.is_geographic) if src.crs else None
    georeferenced = crs is not None or not src.transform.is_identity
    return crs, geographic, src.transform.to_gdal() if georeferenced else None


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
                crs, geographic, transform = raster_georeference(src, path)
                _check_cells(path, tuple(src.shape), "it holds a raster of shape")
                nodata = src.nodata
                values, blanked = _read_band(src, path, nodata)
    except rasterio.errors.RasterioError as exc:
        raise InputError(f"{path}: cannot read as a GeoTIFF ({one_line(str(exc))})") from exc
    except UnicodeError as exc:  # GDAL takes UTF-8 file names only
        raise InputError(
            f"{path}: GDAL cannot open a file whose name is not UTF-8: rename it"
        ) from exc
    if transform is None:
        warnings.warn(
            f"{path}: TIFF without georeference: pixels taken as spacing= metres (default 1 m)",
            UserWarning,
            stacklevel=3,
        )
    # a float32 band read by windows had its nodata blanked by the readers' threads
    heights = values if blanked else blank_nodata(values, nodata, owned=True)
    return RawDEM(heights, tuple(map(float, transform)) if transform else None, crs, geographic)


#: Cells from which a GeoTIFF is read by row windows on several threads.
PARALLEL_READ_CELLS = 4_000_000


def _read_threads() -> int:
    """Threads reading a large raster: ``NUMBA_NUM_THREADS`` if set (a dask worker's share of
    the cores, as the kernels use), else the cores this process may run on; at most 8."""
    try:
        n = int(os.environ.get("NUMBA_NUM_THREADS", "0"))
    except ValueError:
        n = 0
    if n < 1:
        n = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, min(int(n or 1), 8))


def _read_band(src, path: Path, nodata: float | None) -> tuple[np.ndarray, bool]:
    """Band 1 of an open rasterio dataset, and True if its nodata is already NaN.

    A large band is read as row windows aligned to its blocks, one dataset handle per thread:
    GDAL decodes and copies on each at once (a whole-band read of an uncompressed 8192^2
    float32 tiled file went through the block cache at a fifth of the speed), and a float32
    band's nodata is blanked there too (:func:`blank_nodata`)."""
    import rasterio
    from rasterio.windows import Window

    h, w = src.shape
    n = _read_threads()
    if h * w < PARALLEL_READ_CELLS or n == 1 or h < 2 * n:
        return src.read(1), False
    step = max(1, int(src.block_shapes[0][0]))
    rows = -(-h // n)
    rows = -(-rows // step) * step  # whole blocks: no block decoded twice
    out = np.empty((h, w), dtype=np.dtype(src.dtypes[0]))
    blank = out.dtype == np.float32 and nodata is not None

    def part(r0: int) -> None:
        r1 = min(h, r0 + rows)
        # each thread's own handle (GDAL datasets are not shared across threads); direct I/O
        # skips the block cache for uncompressed files
        with rasterio.Env(GTIFF_DIRECT_IO="YES"), rasterio.open(path) as own:
            own.read(1, window=Window(0, r0, w, r1 - r0), out=out[r0:r1])
        if blank:
            blank_nodata(out[r0:r1], nodata, owned=True)

    with ThreadPoolExecutor(max_workers=n) as pool:
        for f in [pool.submit(part, r0) for r0 in range(0, h, rows)]:
            f.result()
    return out, blank


# --- USGS ASCII DEM ---------------------------------------------------------------------------

#: vtkDEMReader's own feet-to-metres factor (VTK_METERS_PER_FEET); the international foot is
#: 0.3048 m, so its heights in feet are rescaled by 0.3048 / 0.305.
METRES_PER_FOOT = 0.3048
#: The USGS DEM's elevation of a void post (no data).
USGS_VOID = -32767

_A_FIELDS = {
    "system": (156, 12),  # ground reference system (0 geographic, 1 UTM, 2 state plane), zone
    "units": (528, 18),  # ground (plane) unit, elevation unit, polygon sides, 3 x 6
    "resolution": (816, 36),  # x, y, z, 3 x 12
    "profiles": (852, 12),  # rows, columns, 2 x 6
}
#: Horizontal datum code (type A record, bytes 891-892 of the 1992 format) -> (name, EPSG of
#: its geographic CRS, EPSG of UTM zone 1 north, of zone 1 south, last UTM zone in EPSG).
_DATUMS = {
    1: ("NAD27", 4267, 26701, None, 22),
    2: ("WGS72", 4322, 32201, 32301, 60),
    3: ("WGS84", 4326, 32601, 32701, 60),
    4: ("NAD83", 4269, 26901, None, 23),
}
#: One ``%6d`` of C's fscanf: skip white space, then at most 6 characters of sign and digits.
_INT6 = re.compile(rb"[ \t\r\n\v\f]*([+-]\d{1,5}|\d{1,6})")


def _a_numbers(record: bytes, key: str, width: int, path: Path) -> list[float]:
    start, size = _A_FIELDS[key]
    text = record[start : start + size].decode("latin-1").upper().replace("D", "E")
    try:
        return [float(text[i : i + width]) for i in range(0, size, width)]
    except ValueError as exc:
        raise InputError(
            f"{path}: not a USGS ASCII DEM: type A record field {key} at bytes "
            f"{start}-{start + size} is {text!r}"
        ) from exc


@dataclass(frozen=True)
class _Profile:
    """One type B record: the ground coordinates of its first post, its local datum elevation
    and its elevations (integers in units of the z resolution)."""

    x: float
    y: float
    datum: float
    elevations: np.ndarray


def _profiles(data: bytes, n_profiles: int, path: Path) -> list[_Profile]:
    """Every type B record: four ``%6d`` (row and column ids, count, 1), five D24.15 (x, y of
    the first post, local datum elevation, min, max), then ``count`` ``%6d`` elevations."""
    pos, out = 1024, []
    for p in range(n_profiles):
        head = []
        for _ in range(4):
            m = _INT6.match(data, pos)
            if m is None:
                break
            head.append(int(m[1]))
            pos = m.end()
        if not head and not data[pos:].strip():
            raise InputError(
                f"{path}: USGS DEM header says {n_profiles} profiles, the file ends after {p} "
                "(truncated?)"
            )
        if len(head) < 4 or len(data) < pos + 120:
            raise InputError(
                f"{path}: USGS DEM profile {p + 1} of {n_profiles}: truncated or garbled type B "
                f"record header at byte {pos}"
            )
        text = data[pos : pos + 120].decode("latin-1").upper().replace("D", "E")
        try:
            x, y, datum = (float(text[i : i + 24]) for i in (0, 24, 48))
        except ValueError:
            raise InputError(
                f"{path}: USGS DEM profile {p + 1}: the first post's coordinates and datum "
                f"elevation at byte {pos} are not numbers ({text[:72].strip()!r})"
            ) from None
        pos += 120
        _, column_id, count, _ = head
        if not 0 <= count <= len(data):  # an elevation takes at least one byte
            raise InputError(f"{path}: USGS DEM profile {p + 1}: {count} elevations")
        elevations = np.empty(count, dtype=np.int64)
        for k in range(count):
            m = _INT6.match(data, pos)
            if m is None:
                raise InputError(
                    f"{path}: USGS DEM profile {p + 1} (column {column_id}): expected {count} "
                    f"elevations, elevation {k + 1} at byte {pos} is missing or not an integer"
                )
            elevations[k] = int(m[1])
            pos = m.end()
        out.append(_Profile(x, y, datum, elevations))
    return out


def _usgs_crs(record: bytes, path: Path) -> str | None:
    """The CRS the type A record names, as ``"EPSG:n"``: geographic or UTM (negative zone:
    south) on its horizontal datum (blank: NAD27, as in the files before 1992 and as GDAL
    reads them); None for state plane, local systems and unknown codes."""
    system, zone = (int(v) for v in _a_numbers(record, "system", 6, path))
    text = record[890:892].decode("latin-1").strip()
    code = int(text) if text.isdigit() else 1
    if code not in _DATUMS:
        return None
    _, geographic, north, south, last = _DATUMS[code]
    if system == 0:
        return f"EPSG:{geographic}"
    if system == 1 and 1 <= abs(zone) <= last:
        if zone > 0:
            return f"EPSG:{north + zone - 1}"
        return f"EPSG:{south - zone - 1}" if south is not None else None
    return None


def read_usgs_dem(path: Path) -> RawDEM:
    """USGS ASCII DEM (``.dem``), heights in metres, parsed here (not by ``vtkDEMReader``).

    Each profile (type B record) is placed by the ground coordinates of its first post, as the
    format defines it: in the 7.5-minute quads every profile has row id 1 but starts at its
    own northing, because the quad's edges are not grid lines. vtkDEMReader places them by the
    ids (every profile from the south edge, the rest of each column filled with the minimum
    elevation) and drops each profile's local datum elevation: wrong heights along the quad's
    edges. Here a height is ``(datum + e * z_resolution) * unit``, and void posts (-32767)
    are nodata. The grid is the posts' own: x of the westmost profile, y of the southmost
    first post, steps of the resolution. Ground coordinates in arc-seconds or radians become
    degrees; a grid in feet stays in feet with :attr:`RawDEM.unit_metres` 0.3048. The CRS
    comes from the header's reference system, zone and horizontal datum (:func:`_usgs_crs`).
    """
    data = path.read_bytes()
    if len(data) < 1024:
        raise InputError(
            f"{path}: {len(data)} bytes is too short for a USGS ASCII DEM (type A record: 1024)"
        )
    record = data[:1024]
    plane_unit, elevation_unit, _ = _a_numbers(record, "units", 6, path)
    res_x, res_y, res_z = _a_numbers(record, "resolution", 12, path)
    _, n_profiles = (int(v) for v in _a_numbers(record, "profiles", 6, path))
    if not (res_x > 0 and res_y > 0 and res_z > 0 and 0 < n_profiles <= len(data) // 6):
        raise InputError(
            f"{path}: not a USGS ASCII DEM: spatial resolution {res_x:g}, {res_y:g}, {res_z:g} "
            f"and {n_profiles} profiles must be positive (and fit in the file)"
        )
    if plane_unit not in (0, 1, 2, 3) or elevation_unit not in (1, 2):
        raise InputError(
            f"{path}: USGS DEM ground unit code {plane_unit:g} (expected 0-3) or elevation unit "
            f"code {elevation_unit:g} (expected 1 feet, 2 metres) not understood"
        )
    profiles = _profiles(data, n_profiles, path)
    xs = np.array([pr.x for pr in profiles])
    ys = np.array([pr.y for pr in profiles])
    if not (np.isfinite(xs).all() and np.isfinite(ys).all()):
        raise InputError(f"{path}: USGS DEM profile coordinates are not finite")
    west, south = float(xs.min()), float(ys.min())
    columns = np.rint((xs - west) / res_x).astype(np.int64)
    rows0 = np.rint((ys - south) / res_y).astype(np.int64)
    counts = np.array([pr.elevations.size for pr in profiles], dtype=np.int64)
    ncols = int(columns.max()) + 1
    nrows = max(int((rows0 + counts).max()), 1)
    if ncols * nrows > MAX_CELLS or np.unique(columns).size != len(profiles):
        raise InputError(
            f"{path}: USGS DEM profiles do not form a grid ({len(profiles)} profiles over "
            f"{ncols} columns of {res_x:g} and {nrows} rows of {res_y:g} ground units)"
        )
    unit = METRES_PER_FOOT if elevation_unit == 1 else 1.0
    heights = np.full((nrows, ncols), np.nan, dtype=np.float64)  # row 0 south here
    for pr, column, row0 in zip(profiles, columns, rows0, strict=True):
        e = pr.elevations
        z = (pr.datum + e * res_z) * unit
        heights[row0 : row0 + e.size, column] = np.where(e == USGS_VOID, np.nan, z)
    heights = heights[::-1].astype(np.float32)  # north row first
    to_crs = {0: 180 / np.pi, 3: 1 / 3600}.get(int(plane_unit), 1.0)  # radians, arc-s -> deg
    dx, dy = res_x * to_crs, res_y * to_crs
    transform = (west * to_crs - dx / 2, dx, 0.0, south * to_crs + (nrows - 0.5) * dy, 0.0, -dy)
    plane_metres = METRES_PER_FOOT if plane_unit == 1 else 1.0
    return RawDEM(heights, transform, _usgs_crs(record, path), plane_unit in (0, 3), plane_metres)
