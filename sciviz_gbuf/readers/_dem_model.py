"""The DEM model: :class:`DEM` and the steps every DEM source goes through (height checks,
nodata, georeference and metres per pixel), shared by the in-memory and the lazy readers."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from ._dem_files import GeoTransform, RawDEM, crs_is_geographic

if TYPE_CHECKING:
    import pyvista

__all__ = [
    "DEM",
    "clean_heights",
    "dem_meta",
    "finish_dem",
    "georeference",
    "is_dataarray",
    "is_path_list",
    "metres_per_degree",
    "read_dataarray",
]


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


@dataclass(frozen=True, eq=False)
class DEM:
    """A DEM grid, north up, with its georeference and metres per pixel.

    Attributes
    ----------
    heights : numpy.ndarray or dask.array.Array
        float32 (H, W) heights (in the file's unit, normally metres); NaN at nodata cells.
        Row 0 is the northern (top) row, as in an image. A lazy dask array when the DEM was
        read with ``read_dem(..., chunks=...)``: nothing is read until it is computed.
    mask : numpy.ndarray or dask.array.Array
        bool (H, W), True where the height is valid (finite); lazy (``da.isfinite(heights)``)
        when ``heights`` is.
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

    def to_pyvista(self, *, z_factor: float = 1.0, step: int = 1) -> pyvista.StructuredGrid:
        """The DEM as a PyVista surface in metres, one point per pixel centre.

        Parameters
        ----------
        z_factor : float, optional
            Vertical exaggeration: point z is ``height * z_factor``.
        step : int, optional
            Keep every ``step``-th row and column (from the first), for huge DEMs.

        Returns
        -------
        pyvista.StructuredGrid
            Dimensions ``(W', H', 1)``: i runs east, j north (so the quads face up). x, y are the
            pixel centres' CRS coordinates for projected grids (in the CRS unit); for
            geographic grids a local equirectangular plane in metres about the grid centre,
            scaled like :attr:`pixel_size`. Point array ``"elevation"`` (float32) holds the
            true heights, NaN at nodata. Nodata points are hidden (``vtkGhostType``
            HIDDENPOINT, so every cell touching one is blanked) and get the lowest valid
            height as z: VTK never sees a NaN coordinate. Blanking is honoured by
            ``extract_surface(algorithm=None)`` (vtkGeometryFilter) and by rendering, but not
            by ``extract_surface(algorithm="dataset_surface")``, PyVista 0.49's default, which
            keeps the hidden cells.

        Raises
        ------
        InputError
            ``step`` not a positive integer or ``z_factor`` not finite.
        """
        import pyvista

        if isinstance(step, bool) or not isinstance(step, (int, np.integer)) or step < 1:
            raise InputError(f"{self.source or 'DEM'}: step must be an integer >= 1, got {step!r}")
        if not np.isfinite(z_factor):
            raise InputError(f"{self.source or 'DEM'}: z_factor must be finite, got {z_factor!r}")
        h, w = self.shape
        rows, cols = np.arange(0, h, step), np.arange(0, w, step)
        # np.asarray: a lazy DEM computes only the strided points needed here.
        heights = np.asarray(self.heights[::step, ::step])
        cc, rr = np.meshgrid(cols + 0.5, rows + 0.5)
        x0, dx, rx, y0, ry, dy = self.transform
        x, y = x0 + cc * dx + rr * rx, y0 + cc * ry + rr * dy
        if self.geographic:
            lon_c, lat_c = x0 + w / 2 * dx + h / 2 * rx, y0 + w / 2 * ry + h / 2 * dy
            m_lon, m_lat = metres_per_degree(lat_c)
            x, y = (x - lon_c) * m_lon, (y - lat_c) * m_lat
        valid = np.isfinite(heights)
        floor = float(heights[valid].min()) if valid.any() else 0.0
        z = np.where(valid, heights, floor) * z_factor
        # Rows flipped and transposed: i (fastest) runs east, j north, normals point up.
        grid = pyvista.StructuredGrid(*(a[::-1].T for a in (x, y, z)))
        grid.point_data["elevation"] = heights[::-1].ravel().astype(np.float32)
        if not valid.all():
            grid.hide_points(~valid[::-1].ravel())
        return grid


def is_path_list(obj: Any) -> bool:
    """A list or tuple of file names: tiles of one mosaic."""
    return (
        isinstance(obj, (list, tuple))
        and len(obj) > 0
        and all(isinstance(p, (str, os.PathLike)) for p in obj)
    )


def dem_meta(dem: DEM) -> tuple:
    """Everything of a DEM but its heights and mask, in :class:`DEM` field order."""
    return dem.crs, dem.transform, dem.pixel_size, dem.geographic, dem.source


def is_dataarray(obj: Any) -> bool:
    """Duck-typed xarray.DataArray check; xarray itself is never imported here."""
    return type(obj).__module__.startswith("xarray") and hasattr(obj, "dims")


#: Dimension names read as (x, y) axes; the lon/lat ones make the grid geographic.
_X_DIMS = {"x": False, "lon": True, "longitude": True}
_Y_DIMS = {"y": False, "lat": True, "latitude": True}


def _axis(da: Any, dim: str, name: str) -> tuple[float, float]:
    """First pixel-centre coordinate and step of an evenly spaced 1-D dimension coordinate."""
    if dim not in da.coords:
        raise InputError(f"{name}: dimension {dim!r} has no coordinate values")
    v = np.asarray(da.coords[dim].values, dtype=float)
    if v.size < 2 or not np.isfinite(v).all():
        raise InputError(
            f"{name}: coordinate {dim!r} needs at least 2 finite values to give a spacing, "
            f"got {v.size}"
        )
    d = np.diff(v)
    step = (v[-1] - v[0]) / (v.size - 1)
    # Tolerance relative to the step: float32 or text round trips of coordinates are fine.
    if step == 0 or not np.allclose(d, step, rtol=1e-5, atol=0):
        raise InputError(
            f"{name}: coordinate {dim!r} is not evenly spaced (steps {d.min():g} to {d.max():g})"
        )
    return float(v[0]), float(step)


def _dataarray_crs(da: Any) -> str | None:
    """CRS from rioxarray's ``.rio.crs``, else ``crs`` attrs, else a ``spatial_ref`` coordinate."""
    try:
        rio_crs = da.rio.crs  # AttributeError when rioxarray is not installed
    except Exception:
        rio_crs = None
    if rio_crs is not None:
        return rio_crs.to_string()
    if da.attrs.get("crs"):
        return str(da.attrs["crs"])
    ref = da.coords["spatial_ref"].attrs if "spatial_ref" in da.coords else da.attrs
    for key in ("crs_wkt", "spatial_ref"):
        if isinstance(ref.get(key), str) and ref[key]:
            return ref[key]
    return None


def read_dataarray(da: Any, name: str, *, lazy: bool = False) -> tuple[RawDEM, float | None]:
    """A 2-D DataArray with x/y, lon/lat or longitude/latitude dims -> north-up RawDEM, nodata.

    ``lazy``: the RawDEM's heights are the DataArray's own (dask) data, flipped lazily."""
    if da.ndim != 2:
        raise InputError(f"{name}: expected a 2-D DataArray, got dims {da.dims}")
    dims = {str(d).lower(): d for d in da.dims}
    x_dim = next((dims[k] for k in _X_DIMS if k in dims), None)
    y_dim = next((dims[k] for k in _Y_DIMS if k in dims), None)
    if x_dim is None or y_dim is None:
        raise InputError(
            f"{name}: dims {da.dims}: expected one of x/lon/longitude and one of y/lat/latitude"
        )
    da = da.transpose(y_dim, x_dim)
    (x_first, dx), (y_first, dy) = _axis(da, x_dim, name), _axis(da, y_dim, name)
    values = da.data if lazy else np.asarray(da.values)
    # North up and east right: flip rows if y increases, columns if x decreases.
    if dy > 0:
        values, y_first, dy = values[::-1], y_first + dy * (values.shape[0] - 1), -dy
    if dx < 0:
        values, x_first, dx = values[:, ::-1], x_first + dx * (values.shape[1] - 1), -dx
    transform = (x_first - dx / 2, dx, 0.0, y_first - dy / 2, 0.0, dy)  # centres -> corners
    crs = _dataarray_crs(da)
    lonlat = _X_DIMS[str(x_dim).lower()] or _Y_DIMS[str(y_dim).lower()]
    geographic = True if lonlat else crs_is_geographic(crs)
    nodata = None
    for where, key in ((da.attrs, "_FillValue"), (da.attrs, "nodata"), (da.encoding, "_FillValue")):
        if where.get(key) is not None:
            try:
                nodata = float(where[key])
            except (TypeError, ValueError):
                raise InputError(
                    f"{name}: attribute {key}: expected a number (the nodata value), "
                    f"got {where[key]!r:.60}"
                ) from None
            break
    return RawDEM(values, transform, crs, geographic), nodata


def clean_heights(
    values: np.ndarray, name: str | None, nodata: float | None, owned: bool = False
) -> np.ndarray:
    """Check a 2-D numeric array; float32 with NaN at ``nodata`` and non-finite values: a copy,
    or ``values`` itself when ``owned`` (just read from a file) and already float32."""
    what = name or "array"
    if values.ndim != 2 or min(values.shape) == 0:
        raise InputError(
            f"{what}: expected a non-empty 2-D array of heights, got shape {values.shape}"
        )
    if not (np.issubdtype(values.dtype, np.number) and not np.iscomplexobj(values)):
        raise InputError(f"{what}: expected real numeric heights, got dtype {values.dtype}")
    if values.dtype.itemsize > 4 and np.issubdtype(values.dtype, np.floating):
        # float64 heights beyond float32 would silently become inf, then nodata: an empty map.
        big = np.abs(values[np.isfinite(values)], dtype=np.float64)
        if big.size and big.max() > np.finfo(np.float32).max:
            raise InputError(
                f"{what}: heights up to {big.max():.3g} are beyond float32 "
                f"(+-{np.finfo(np.float32).max:.3g}): expected heights in metres"
            )
    heights = values if owned and values.dtype == np.float32 else values.astype(np.float32)
    if nodata is not None:
        np.putmask(heights, values == nodata, np.float32(np.nan))
    if np.isinf(heights).any():
        np.putmask(heights, np.isinf(heights), np.float32(np.nan))
    return heights


def spacing_transform(spacing, shape: tuple[int, int], name: str | None) -> GeoTransform:
    """Metric transform of a grid without georeference, origin at the south-west corner."""
    dx, dy = np.broadcast_to(np.asarray(1.0 if spacing is None else spacing, float), (2,))
    if not (np.isfinite([dx, dy]).all() and dx > 0 and dy > 0):
        raise InputError(f"{name or 'array'}: spacing must be positive metres, got {spacing!r}")
    return (0.0, float(dx), 0.0, shape[0] * float(dy), 0.0, -float(dy))


def looks_geographic(transform: GeoTransform, shape: tuple[int, int]) -> bool:
    """Cells <= 0.1 units and the whole extent inside longitude/latitude range."""
    x0, dx, rx, y0, ry, dy = transform
    h, w = shape
    xs = [x0 + c * dx + r * rx for c in (0, w) for r in (0, h)]
    ys = [y0 + c * ry + r * dy for c in (0, w) for r in (0, h)]
    small = max(abs(dx), abs(dy)) <= 0.1
    return small and min(xs) >= -180 and max(xs) <= 360 and min(ys) >= -90 and max(ys) <= 90


def finish_dem(raw: RawDEM, name: str | None, *, spacing, nodata, geographic, owned=False) -> DEM:
    heights = clean_heights(np.asarray(raw.heights), name, nodata, owned)
    transform, pixel, geo = georeference(
        raw, heights.shape, name, spacing=spacing, geographic=geographic
    )
    return DEM(heights, np.isfinite(heights), raw.crs, transform, pixel, bool(geo), name)


def georeference(
    raw: RawDEM,
    shape: tuple[int, int],
    name: str | None,
    *,
    spacing,
    geographic: bool | None,
    stacklevel: int = 4,
) -> tuple[GeoTransform, tuple[float, float], bool]:
    """Transform, metres per pixel and geographic flag of a grid of ``shape`` (no pixels read).

    ``stacklevel`` of the degrees warning: 4 points at the caller of :func:`read_dem`.
    """
    if raw.transform is None:
        if geographic:
            raise InputError(f"{name or 'array'}: geographic=True needs a transform= in degrees")
        transform, geo = spacing_transform(spacing, shape, name), False
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
            geo = looks_geographic(transform, shape)
            if geo:
                warnings.warn(
                    f"{name or 'array'}: no CRS, and cells of {transform[1]:g} x "
                    f"{abs(transform[5]):g} units within longitude/latitude range: taken as "
                    "degrees (if they are metres: geographic=False, or --projected on the "
                    "command line)",
                    UserWarning,
                    stacklevel=stacklevel,
                )
    _, dx, rx, y0, ry, dy = transform
    if geo:
        h, w = shape
        lats = [y0 + c * ry + r * dy for c in (0, w) for r in (0, h)]
        if min(lats) < -90.0 - 1e-6 or max(lats) > 90.0 + 1e-6:
            raise InputError(
                f"{name or 'array'}: a geographic grid must lie within latitudes -90..90, "
                f"this one spans {min(lats):.6g}..{max(lats):.6g} (wrong transform, or not "
                "in degrees: pass geographic=False)"
            )
        m_lon, m_lat = metres_per_degree(y0 + ry * w / 2 + dy * h / 2)
        pixel = (float(np.hypot(dx * m_lon, ry * m_lat)), float(np.hypot(rx * m_lon, dy * m_lat)))
    else:
        unit = raw.unit_metres  # a projected grid in feet still gets metres per pixel
        pixel = (float(np.hypot(dx, ry) * unit), float(np.hypot(rx, dy) * unit))
    return transform, pixel, bool(geo)
