"""Web map tiles of a topographic map: an XYZ ("slippy map") pyramid in Web Mercator.

Each zoom level is one map: the DEM's heights resampled onto that level's Web Mercator pixel
grid (EPSG:3857, the pixel grid of the tiles that cover the DEM), mapped whole by
:func:`~.terrain.topographic_map` (lazily on dask, chunk by chunk, bit-identical to the map in
memory) and cut into tiles. A tile is therefore the window of one map, not a map of its own:
contour lines, relief and labels run across tile edges without a seam. Lines and labels keep
their width in pixels at every zoom, and each zoom gets its own contour intervals, as a web
map's style would.

Conventions (the OSM / Google / Leaflet tile scheme): at zoom ``z`` the world
``[-pi R, pi R]^2`` (``R`` = 6 378 137 m) is ``2^z x 2^z`` tiles, ``x`` from the antimeridian
eastwards, ``y`` from the north (85.0511 deg) southwards; tile ``z/x/y`` is written to
``out/z/x/y.png``.
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import _validate
from .._atomic import atomic_folder
from ..errors import InputError
from ..readers import DEM
from ..writers.pmtiles import write_pmtiles
from ..writers.tiles import TILE_FORMATS, encode_tile, write_tile_viewer, write_tilejson
from ._map import as_dem
from .terrain import topographic_map

__all__ = [
    "EARTH_RADIUS",
    "MAX_LATITUDE",
    "TilePyramid",
    "dem_lonlat_bounds",
    "lonlat_to_tile",
    "mercator_dem",
    "native_zoom",
    "tile_bounds",
    "tile_lonlat_bounds",
    "tile_range",
    "write_map_tiles",
]

#: The sphere of Web Mercator (EPSG:3857), metres.
EARTH_RADIUS = 6378137.0
#: Half the world's width in EPSG:3857 metres (pi R).
_HALF = math.pi * EARTH_RADIUS
#: The latitude of the square world's north and south edges, degrees.
MAX_LATITUDE = math.degrees(math.atan(math.sinh(math.pi)))
#: Map chunk side in tiles' pixels: a task maps and writes (CHUNK / tile size)^2 tiles.
CHUNK = 1024
#: Spacing (px) of the pixels whose source coordinates are transformed exactly (the others
#: are bilinear between them) for a DEM in a projected CRS.
CONTROL = 16
#: A level of at most this many pixels is mapped in memory (heights resampled once); larger
#: levels are mapped lazily, chunk by chunk (the same pixels).
IN_MEMORY_PIXELS = 2**24


def tile_bounds(z: int, x: int, y: int) -> tuple[float, float, float, float]:
    """``(west, south, east, north)`` of tile ``z/x/y`` in EPSG:3857 metres."""
    size = 2.0 * _HALF / 2**z
    west = -_HALF + x * size
    north = _HALF - y * size
    return west, north - size, west + size, north


def tile_lonlat_bounds(z: int, x: int, y: int) -> tuple[float, float, float, float]:
    """``(west, south, east, north)`` of tile ``z/x/y`` in degrees of longitude/latitude."""
    w, s, e, n = tile_bounds(z, x, y)
    return _lon(w), _lat(s), _lon(e), _lat(n)


def _lon(x: Any) -> Any:
    return np.degrees(np.asarray(x, np.float64) / EARTH_RADIUS)


def _lat(y: Any) -> Any:
    return np.degrees(np.arctan(np.sinh(np.asarray(y, np.float64) / EARTH_RADIUS)))


def _tile_xy(lon: float, lat: float, z: int) -> tuple[float, float]:
    """Fractional tile coordinates of a point at zoom ``z`` (latitude clamped to the world)."""
    n = 2**z
    lat = min(max(float(lat), -MAX_LATITUDE), MAX_LATITUDE)
    fx = (float(lon) + 180.0) / 360.0 * n
    fy = (1.0 - math.asinh(math.tan(math.radians(lat))) / math.pi) / 2.0 * n
    return fx, fy


def lonlat_to_tile(lon: float, lat: float, z: int) -> tuple[int, int]:
    """The tile ``(x, y)`` at zoom ``z`` holding the point; latitudes beyond
    :data:`MAX_LATITUDE` and longitude 180 are taken at the world's edge."""
    n = 2**z
    fx, fy = _tile_xy(lon, lat, z)
    return min(max(math.floor(fx), 0), n - 1), min(max(math.floor(fy), 0), n - 1)


#: A bound within this many tiles of a tile edge is on it (its degrees are rounded: near the
#: poles at zoom 21 by ~1e-9 tiles).
_EDGE = 1e-6


def tile_range(bounds: Sequence[float], z: int) -> tuple[int, int, int, int]:
    """``(x0, x1, y0, y1)``, inclusive, of the tiles at zoom ``z`` that cover the lon/lat
    ``bounds = (west, south, east, north)``; a bound on a tile edge (within rounding) does not
    pull in the tile beyond it."""
    west, south, east, north = (float(v) for v in bounds)
    n = 2**z
    fx0, fy0 = _tile_xy(west, north, z)
    fx1, fy1 = _tile_xy(east, south, z)
    x0 = min(max(math.floor(fx0 + _EDGE), 0), n - 1)
    y0 = min(max(math.floor(fy0 + _EDGE), 0), n - 1)
    x1 = min(max(math.ceil(fx1 - _EDGE) - 1, x0), n - 1)
    y1 = min(max(math.ceil(fy1 - _EDGE) - 1, y0), n - 1)
    return x0, x1, y0, y1


def _crs_of(d: DEM) -> str:
    if d.crs:
        return d.crs
    if d.geographic:
        return "EPSG:4326"  # a grid in degrees without a CRS: WGS 84 (SRTM, ASCII grids)
    raise InputError(
        f"{d.source or 'dem'}: web tiles need a georeferenced DEM (a CRS, or a grid in "
        "degrees of longitude/latitude); this one has neither"
    )


def _is_lonlat(crs: str) -> bool:
    from rasterio.crs import CRS

    c = CRS.from_user_input(crs)
    return bool(c.is_geographic) and c.to_epsg() in (4326, 4269, 4258, None)


def _to_lonlat(crs: str, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from rasterio.warp import transform

    if _is_lonlat(crs):
        return np.asarray(xs, np.float64), np.asarray(ys, np.float64)
    lon, lat = transform(crs, "EPSG:4326", np.ravel(xs), np.ravel(ys))
    return np.reshape(lon, np.shape(xs)), np.reshape(lat, np.shape(ys))


def _from_lonlat(crs: str, lon: np.ndarray, lat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from rasterio.warp import transform

    if _is_lonlat(crs):
        return lon, lat
    xs, ys = transform("EPSG:4326", crs, np.ravel(lon), np.ravel(lat))
    return np.reshape(xs, lon.shape), np.reshape(ys, lat.shape)


def dem_lonlat_bounds(d: DEM) -> tuple[float, float, float, float]:
    """``(west, south, east, north)`` in degrees of the DEM's extent (its edges sampled at 65
    points each, so a projected grid's curved outline is inside)."""
    h, w = d.shape
    t = np.linspace(0.0, 1.0, 65)
    cols = np.concatenate([t * w, np.full_like(t, w), t[::-1] * w, np.zeros_like(t)])
    rows = np.concatenate([np.zeros_like(t), t * h, np.full_like(t, h), t[::-1] * h])
    x0, dx, rx, y0, ry, dy = d.transform
    xs, ys = x0 + cols * dx + rows * rx, y0 + cols * ry + rows * dy
    lon, lat = _to_lonlat(_crs_of(d), xs, ys)
    if not (np.isfinite(lon).all() and np.isfinite(lat).all()):
        raise InputError(f"{d.source or 'dem'}: its extent has no longitude/latitude in its CRS")
    lat = np.clip(lat, -MAX_LATITUDE, MAX_LATITUDE)
    return float(lon.min()), float(lat.min()), float(lon.max()), float(lat.max())


def _ground_cell(d: DEM) -> float:
    return float(min(d.pixel_size))


def native_zoom(d: DEM, tile_size: int = 256) -> int:
    """The zoom whose pixels are no larger than the DEM's cells at its centre latitude (the
    level beyond which tiles only magnify)."""
    _, south, _, north = dem_lonlat_bounds(d)
    cos_lat = math.cos(math.radians((south + north) / 2.0))
    world = 2.0 * _HALF * cos_lat  # ground metres around the parallel
    return max(0, min(24, math.ceil(math.log2(world / (tile_size * _ground_cell(d))))))


@dataclass(frozen=True)
class _Source:
    """Reads windows of a DEM's heights (rows, cols slices of the full grid) as float32, on
    whichever process runs the task: a numpy array, or a lazy DEM's window reader."""

    heights: Any  # numpy array or a picklable reader with __getitem__
    shape: tuple[int, int]

    def read(self, r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
        part = self.heights[r0:r1, c0:c1]
        if hasattr(part, "compute"):
            part = part.compute()
        return np.asarray(part, np.float32)


def _source_of(d: DEM) -> _Source:
    from .. import _dask as _chunks

    h = d.heights
    if _chunks.is_dask(h):
        reader = _chunks.windows_of(h)
        return _Source(reader if reader is not None else h, tuple(h.shape))
    return _Source(np.asarray(h, np.float32), tuple(h.shape))


def _block_mean(a: np.ndarray, f: int) -> np.ndarray:
    """Means of ``f x f`` blocks of ``a`` (its size a multiple of ``f``), NaN ignored (NaN
    where a block has no data), summed in one fixed order: the same bits for a cell whichever
    window it was read in."""
    h, w = a.shape[0] // f, a.shape[1] // f
    total = np.zeros((h, w), np.float64)
    count = np.zeros((h, w), np.int32)
    for i in range(f):
        for j in range(f):
            v = a[i::f, j::f][:h, :w]
            ok = ~np.isnan(v)
            total += np.where(ok, v, 0.0)
            count += ok
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan).astype(np.float32)


@dataclass(frozen=True)
class _Level:
    """One zoom level's pixel grid and how its heights are sampled from the source."""

    zoom: int
    tile_size: int
    x0: int
    y0: int
    nx: int
    ny: int
    crs: str
    src_transform: tuple[float, ...]
    src_shape: tuple[int, int]
    factor: int  # source cells averaged per coarse cell side (1: none)

    @property
    def res(self) -> float:
        return 2.0 * _HALF / (self.tile_size * 2**self.zoom)

    @property
    def shape(self) -> tuple[int, int]:
        return self.ny * self.tile_size, self.nx * self.tile_size

    @property
    def transform(self) -> tuple[float, ...]:
        west = -_HALF + self.x0 * self.tile_size * self.res
        north = _HALF - self.y0 * self.tile_size * self.res
        return (west, self.res, 0.0, north, 0.0, -self.res)

    def _source_xy(self, rows: slice, cols: slice) -> tuple[np.ndarray, np.ndarray]:
        """The source CRS's coordinates of the centres of the level's pixels ``rows x cols``.
        A grid in degrees: exact (separable). Another CRS: the transform is evaluated at the
        pixels whose global indices are multiples of :data:`CONTROL` and bilinear between
        them (the same control points whatever window is asked for, so every pixel gets the
        same coordinates in a chunk as in the whole level; a projection's curvature over
        ``CONTROL`` pixels moves a point by ``~CONTROL^2 res^2 / (8 R)``: 1/20 px at zoom 5,
        1e-4 px at zoom 13)."""
        west, res, _, north, _, _ = self.transform
        if _is_lonlat(self.crs) or self.zoom < 4:
            xs = west + (np.arange(cols.start, cols.stop) + 0.5) * res
            ys = north - (np.arange(rows.start, rows.stop) + 0.5) * res
            lon = np.broadcast_to(_lon(xs)[None, :], (len(ys), len(xs)))
            lat = np.broadcast_to(_lat(ys)[:, None], (len(ys), len(xs)))
            return _from_lonlat(self.crs, lon, lat)
        k = CONTROL
        r_lo, r_hi = rows.start // k, -(-rows.stop // k)
        c_lo, c_hi = cols.start // k, -(-cols.stop // k)
        cr = np.arange(r_lo, r_hi + 1) * k  # control pixels' global indices
        cc = np.arange(c_lo, c_hi + 1) * k
        lon = np.broadcast_to(_lon(west + (cc + 0.5) * res)[None, :], (len(cr), len(cc)))
        lat = np.broadcast_to(_lat(north - (cr + 0.5) * res)[:, None], (len(cr), len(cc)))
        gx, gy = _from_lonlat(self.crs, lon, lat)
        r = np.arange(rows.start, rows.stop)
        c = np.arange(cols.start, cols.stop)
        i0 = r // k - r_lo
        j0 = c // k - c_lo
        tr = ((r % k) / k)[:, None]
        tc = ((c % k) / k)[None, :]
        out = []
        for g in (gx, gy):
            top = g[i0][:, j0] * (1.0 - tc) + g[i0][:, j0 + 1] * tc
            bottom = g[i0 + 1][:, j0] * (1.0 - tc) + g[i0 + 1][:, j0 + 1] * tc
            out.append(top * (1.0 - tr) + bottom * tr)
        return out[0], out[1]

    def heights(self, source: _Source, rows: slice, cols: slice) -> np.ndarray:
        """Bilinear heights at the centres of the level's pixels ``rows x cols`` (NaN where
        the DEM has no data or does not reach), from the source averaged over ``factor``^2
        cells first where the level's pixels are that much larger than the DEM's cells."""
        sx, sy = self._source_xy(rows, cols)
        # fractional (row, col) of the coarse grid's cell centres
        x0, dx, rx, y0, ry, dy = self.src_transform
        f = self.factor
        det = dx * dy - rx * ry
        u = ((sx - x0) * dy - (sy - y0) * rx) / det / f - 0.5
        v = ((sy - y0) * dx - (sx - x0) * ry) / det / f - 0.5
        ch, cw = self.src_shape[0] // f, self.src_shape[1] // f
        out = np.full(u.shape, np.nan, np.float32)
        # inside the DEM's extent (cells beyond its last whole block, at most f - 1 of them,
        # take the nearest block's height)
        inside = np.isfinite(u) & np.isfinite(v)
        inside &= (u >= -0.5) & (u <= self.src_shape[1] / f - 0.5)
        inside &= (v >= -0.5) & (v <= self.src_shape[0] / f - 0.5)
        if not inside.any():
            return out
        u = np.clip(np.where(inside, u, 0.0), 0.0, cw - 1.0)
        v = np.clip(np.where(inside, v, 0.0), 0.0, ch - 1.0)
        c0 = np.minimum(np.floor(u).astype(np.int64), max(cw - 2, 0))
        r0 = np.minimum(np.floor(v).astype(np.int64), max(ch - 2, 0))
        a0, a1 = int(r0[inside].min()), int(r0[inside].max()) + 2
        b0, b1 = int(c0[inside].min()), int(c0[inside].max()) + 2
        a1, b1 = min(a1, ch), min(b1, cw)
        win = source.read(a0 * f, a1 * f, b0 * f, b1 * f)
        coarse = win if f == 1 else _block_mean(win, f)
        fu = (u - c0).astype(np.float32)
        fv = (v - r0).astype(np.float32)
        i0 = np.where(inside, r0 - a0, 0)  # pixels outside read any cell, then are dropped
        j0 = np.where(inside, c0 - b0, 0)
        i1 = np.minimum(i0 + 1, coarse.shape[0] - 1)
        j1 = np.minimum(j0 + 1, coarse.shape[1] - 1)
        one = np.float32(1.0)
        val = (coarse[i0, j0] * (one - fu) + coarse[i0, j1] * fu) * (one - fv) + (
            coarse[i1, j0] * (one - fu) + coarse[i1, j1] * fu
        ) * fv
        out[inside] = val[inside]
        return out


def _level(d: DEM, zoom: int, tile_size: int, bounds: Sequence[float]) -> _Level:
    x0, x1, y0, y1 = tile_range(bounds, zoom)
    lat0 = math.radians((bounds[1] + bounds[3]) / 2.0)
    ground_res = 2.0 * _HALF / (tile_size * 2**zoom) * math.cos(lat0)
    factor = max(1, math.floor(ground_res / _ground_cell(d)))
    factor = min(factor, max(1, min(d.shape) // 2))
    return _Level(
        zoom, tile_size, x0, y0, x1 - x0 + 1, y1 - y0 + 1, _crs_of(d),
        tuple(float(v) for v in d.transform), tuple(d.shape), factor,
    )  # fmt: skip


def mercator_dem(dem: DEM | str | os.PathLike, zoom: int, *, tile_size: int = 256) -> DEM:
    """The DEM resampled onto the Web Mercator pixels of the tiles that cover it at ``zoom``.

    Parameters
    ----------
    dem : DEM or path
        Georeferenced (a CRS, or a grid in degrees taken as WGS 84); in memory or lazy
        (``read_dem(..., chunks=...)``: windows are read as needed).
    zoom : int in [0, 24]
    tile_size : {256, 512}

    Returns
    -------
    DEM
        Lazy heights (dask, chunks of :data:`CHUNK` pixels aligned to the tiles), CRS
        ``EPSG:3857``, the level's transform, and ``pixel_size`` the ground size of a pixel at
        the DEM's centre latitude (Web Mercator's metres are ``1 / cos(latitude)`` ground
        metres: this is what the relief and the contour spacing see). Heights are bilinear
        between the DEM's cell centres; where a pixel is ``f >= 2`` cells wide, between the
        means of ``f x f`` blocks of cells (anchored at the DEM's corner), so low zooms are not
        aliased.
    """
    import dask.array as da

    d = as_dem(dem)
    zoom = int(_validate.number_in(zoom, "zoom", 0, 24))
    tile_size = _check_tile_size(tile_size)
    bounds = dem_lonlat_bounds(d)
    lvl = _level(d, zoom, tile_size, bounds)
    src = _source_of(d)
    h, w = lvl.shape
    chunk = max(tile_size, CHUNK // tile_size * tile_size)

    def block(block_info=None) -> np.ndarray:
        (r0, r1), (c0, c1) = block_info[None]["array-location"]
        return lvl.heights(src, slice(r0, r1), slice(c0, c1))

    chunks = tuple(tuple(min(chunk, n - i) for i in range(0, n, chunk)) for n in (h, w))
    heights = da.map_blocks(
        block, chunks=chunks, dtype=np.float32, meta=np.empty((0, 0), np.float32),
        name=f"mercator-heights-{zoom}-{tile_size}-{da.core.tokenize(lvl, id(src))}",
    )  # fmt: skip
    lat0 = math.radians((bounds[1] + bounds[3]) / 2.0)
    ground = lvl.res * math.cos(lat0)
    return DEM(
        heights=heights, mask=da.isfinite(heights), crs="EPSG:3857", transform=lvl.transform,
        pixel_size=(ground, ground), geographic=False,
        source=f"{d.source or 'dem'} at zoom {zoom}",
    )  # fmt: skip


def _check_tile_size(tile_size: object) -> int:
    if tile_size not in (256, 512):
        raise InputError(f"tile_size: expected 256 or 512 pixels, got {_validate.brief(tile_size)}")
    return int(tile_size)  # type: ignore[arg-type]


def _check_zooms(zoom: object, d: DEM, tile_size: int) -> tuple[int, int]:
    if zoom is None:
        top = native_zoom(d, tile_size)
        return max(0, top - 4), top
    if isinstance(zoom, (int, np.integer)) and not isinstance(zoom, bool):
        lo = hi = int(zoom)
    else:
        try:
            lo, hi = (int(v) for v in zoom)  # type: ignore[union-attr]
        except (TypeError, ValueError):
            raise InputError(
                f"zoom: expected a zoom level or a (min, max) pair, got {_validate.brief(zoom)}"
            ) from None
    if not 0 <= lo <= hi <= 24:
        raise InputError(f"zoom: expected levels 0 <= min <= max <= 24, got {lo}-{hi}")
    return lo, hi


@dataclass(frozen=True)
class TilePyramid:
    """What :func:`write_map_tiles` wrote.

    Attributes
    ----------
    path : Path
        The pyramid's folder (``z/x/y.<format>``, ``tiles.json``, ``index.html``), or its
        PMTiles archive.
    zooms : (int, int)
        Its first and last zoom level.
    tiles : dict of int to int
        Tiles written per zoom (tiles with no data are not written).
    bounds : (west, south, east, north)
        The DEM's extent in degrees.
    """

    path: Path
    zooms: tuple[int, int]
    tiles: dict[int, int]
    bounds: tuple[float, float, float, float]

    @property
    def count(self) -> int:
        return sum(self.tiles.values())


def _write_block(rgba: np.ndarray, row0: int, col0: int, lvl: _Level, root: str, fmt: str) -> int:
    """Cut a block of a level's map (its top-left pixel at ``row0, col0``) into tiles and
    write those with data; returns how many."""
    t = lvl.tile_size
    n = 0
    for i in range(0, rgba.shape[0], t):
        for j in range(0, rgba.shape[1], t):
            tile = rgba[i : i + t, j : j + t]
            if not tile[..., 3].any():
                continue  # no data: web maps show the layer below
            x = lvl.x0 + (col0 + j) // t
            y = lvl.y0 + (row0 + i) // t
            folder = Path(root) / str(lvl.zoom) / str(x)
            folder.mkdir(parents=True, exist_ok=True)
            (folder / f"{y}.{fmt}").write_bytes(encode_tile(tile, fmt))
            n += 1
    return n


def write_map_tiles(
    dem: DEM | str | os.PathLike,
    path: str | os.PathLike,
    *,
    zoom: int | Sequence[int] | None = None,
    tile_size: int = 256,
    format: str = "png",
    title: str | None = None,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
    **map_options: Any,
) -> TilePyramid:
    """Write a topographic map of ``dem`` as an XYZ web-map tile pyramid with a viewer.

    Parameters
    ----------
    dem : DEM or path
        Georeferenced DEM (any CRS; a grid in degrees without one is taken as WGS 84), in
        memory or read lazily (``read_dem(path, chunks=...)``, for DEMs larger than memory).
    path : str or path-like
        The pyramid's folder: new, or empty. It is written as a whole: into a temporary
        folder beside it, renamed when complete (nothing is left of a failed run). A name
        ending in ``.pmtiles`` writes one PMTiles archive instead
        (:func:`~sciviz_gbuf.writers.pmtiles.write_pmtiles`: the same tiles, for a static web
        server or object store and a PMTiles-aware viewer), from a scratch folder beside it.
    zoom : int or (int, int), optional
        Zoom levels, inclusive (0-24). Default: the DEM's native zoom (pixels no larger than
        its cells, :func:`native_zoom`) and the four below it.
    tile_size : {256, 512}
    format : {"png", "webp"}
        PNG (lossless, with transparency) or lossless WebP (smaller).
    title : str, optional
        The viewer page's title (default: the DEM's file name).
    client : dask.distributed.Client, optional
        Map and write the tiles on its workers (they must see ``path``'s file system);
        default dask's threads in this process.
    progress : callable, optional
        ``progress(done, total)`` after each chunk of each level.
    **map_options
        Options of :func:`~.terrain.topographic_map` (``interval``, ``relief``, ``bands``,
        ``cmap``, ``z_factor``, ``labels``, ...). ``vmin``/``vmax`` default to the DEM's
        height range, so a height has one colour at every zoom; contour intervals are chosen
        per zoom unless given. ``labels=True`` maps each level in memory (labels are placed
        on a whole map), so a level may be at most ``LIMITS["image_side"]`` pixels a side.

    Returns
    -------
    TilePyramid

    Raises
    ------
    InputError
        A DEM without georeference, a bad zoom/tile size/format, a pyramid of more than
        ``LIMITS["tiles"]`` tiles, an existing non-empty folder, map options as
        :func:`~.terrain.topographic_map` refuses them.

    Notes
    -----
    Each level is mapped whole (lazily: chunk by chunk with the halos of its operators,
    bit-identical to the map in memory), then cut: a tile equals the window of the level's
    map, with no seam at its edges. Tiles without data are not written (a viewer shows the
    layers below). The folder also holds ``tiles.json`` (TileJSON 3.0) and ``index.html``,
    a Leaflet viewer (bundled, no network needed) of the pyramid.
    """
    d = as_dem(dem)
    tile_size = _check_tile_size(tile_size)
    fmt = _validate.choice(str(format).lower(), "format", TILE_FORMATS)
    zmin, zmax = _check_zooms(zoom, d, tile_size)
    out = Path(path)
    archive = out.suffix.lower() == ".pmtiles"
    if archive and out.is_dir():
        raise InputError(f"path: {str(out)!r} is a folder; a .pmtiles archive is a file")
    if not archive and out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise InputError(f"path: {str(out)!r} exists and is not an empty folder")
    if not out.parent.is_dir():
        raise InputError(f"path: no such directory {str(out.parent)!r}")
    for key in ("size", "scale", "dpi"):
        if map_options.get(key) is not None:
            raise InputError(f"{key}: a tile's pixel size is its zoom level's; not {key}=")
    bounds = dem_lonlat_bounds(d)
    levels = [_level(d, z, tile_size, bounds) for z in range(zmin, zmax + 1)]
    total = sum(lv.nx * lv.ny for lv in levels)
    limit = int(_validate.LIMITS["tiles"])
    if total > limit:
        raise InputError(
            f"zoom: levels {zmin}-{zmax} need {total:,} tiles of {tile_size} px for this DEM; "
            f"at most {limit:,} (LIMITS['tiles']): lower the last zoom level"
        )
    labels = bool(map_options.get("labels", False))
    if labels:
        side = max(max(lv.shape) for lv in levels)
        _validate.at_most(side, "zoom (a labelled level's map side, px)", "image_side")
    opts = dict(map_options)
    if opts.get("vmin") is None or opts.get("vmax") is None:
        lo, hi = _height_range(d)
        opts["vmin"] = lo if opts.get("vmin") is None else opts["vmin"]
        opts["vmax"] = hi if opts.get("vmax") is None else opts["vmax"]
    # checked once, on a small map, before anything is computed or written
    topographic_map(np.zeros((4, 4), np.float32), **{**opts, "labels": False})
    written: dict[int, int] = {}
    name = title or (Path(d.source).name if d.source else "map")
    if archive:
        # the tiles into a scratch folder beside the archive (workers write there too), then
        # packed into the archive and removed
        with tempfile.TemporaryDirectory(dir=out.parent, prefix=f".{out.name}.") as tmp:
            _map_levels(Path(tmp), levels, d, opts, labels, client, fmt, tile_size,
                        written, progress)  # fmt: skip
            write_pmtiles(_tile_files(Path(tmp), fmt), out, fmt=fmt, bounds=bounds, name=name)
        return TilePyramid(out, (zmin, zmax), written, bounds)
    with atomic_folder(out) as tmp:
        _map_levels(tmp, levels, d, opts, labels, client, fmt, tile_size, written, progress)
        write_tilejson(tmp / "tiles.json", name=name, bounds=bounds, zooms=(zmin, zmax),
                       fmt=fmt, tile_size=tile_size)  # fmt: skip
        write_tile_viewer(tmp, title=name, bounds=bounds, zooms=(zmin, zmax), fmt=fmt,
                          tile_size=tile_size)  # fmt: skip
    return TilePyramid(out, (zmin, zmax), written, bounds)


def _tile_files(root: Path, fmt: str) -> Iterator[tuple[int, int, int, Path]]:
    """``(z, x, y, file)`` of every tile of an XYZ folder ``root/z/x/y.<fmt>``."""
    for zdir in root.iterdir():
        for xdir in zdir.iterdir():
            for f in xdir.glob(f"*.{fmt}"):
                yield int(zdir.name), int(xdir.name), int(f.stem), f


def _map_levels(
    tmp: Path, levels: list, d: DEM, opts: dict, labels: bool, client: Any, fmt: str,
    tile_size: int, written: dict[int, int], progress: Callable[[int, int], None] | None,
) -> None:  # fmt: skip
    """Map every level and write its tiles with data into the folder ``tmp`` (``z/x/y``),
    their count per zoom into ``written``."""
    import dask

    done = 0
    for lv in levels:
        zd = mercator_dem(d, lv.zoom, tile_size=tile_size)
        whole = labels or (client is None and lv.shape[0] * lv.shape[1] <= IN_MEMORY_PIXELS)
        if whole:
            z_mem = np.asarray(zd.heights.compute())
            zd = DEM(
                heights=z_mem, mask=np.isfinite(z_mem), crs=zd.crs,
                transform=zd.transform, pixel_size=zd.pixel_size, geographic=False,
                source=zd.source,
            )  # fmt: skip
        rgba = topographic_map(zd, **opts)
        if whole:
            written[lv.zoom] = _write_block(rgba, 0, 0, lv, str(tmp), fmt)
            done += 1
            if progress is not None:
                progress(done, len(levels))
            continue
        blocks = rgba.to_delayed().reshape(len(rgba.chunks[0]), len(rgba.chunks[1]))
        starts = [np.cumsum((0, *c[:-1])) for c in rgba.chunks[:2]]
        write = dask.delayed(_write_block)
        tasks = [
            write(blocks[i, j], int(starts[0][i]), int(starts[1][j]), lv, str(tmp), fmt)
            for i in range(len(rgba.chunks[0]))
            for j in range(len(rgba.chunks[1]))
        ]
        if client is not None:
            counts = client.gather(client.compute(tasks))
        else:
            counts = dask.compute(*tasks)
        written[lv.zoom] = int(sum(counts))
        done += 1
        if progress is not None:
            progress(done, len(levels))


def _height_range(d: DEM) -> tuple[float, float]:
    from .. import _dask as _chunks

    z = d.heights
    if _chunks.is_dask(z):
        import dask.array as da

        lo, hi = _chunks.reduce(da.nanmin(z), da.nanmax(z))
    else:
        with np.errstate(invalid="ignore"):
            lo, hi = np.nanmin(z), np.nanmax(z)
    lo, hi = float(lo), float(hi)
    if not np.isfinite(lo):
        raise InputError(f"{d.source or 'dem'}: every cell is nodata: nothing to map")
    return lo, hi
