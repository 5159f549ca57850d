"""Lazy (dask) DEM reading for :func:`sciviz_gbuf.readers.read_dem` with ``chunks=``.

Only metadata is read eagerly. Pixels are read when a chunk is computed, by rasterio windows,
in the process (and thread) computing it: the dask graph holds a small picklable
:class:`WindowReader` (file names, offsets, nodata), never an open dataset, so it runs on
``dask.distributed`` workers as well as on the local threaded scheduler. Each chunk goes through
the same nodata/float32 steps as the in-memory readers, so the values are identical.
"""

from __future__ import annotations

import os
import threading
import warnings
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import _dask
from ..errors import InputError
from ._dem_files import GeoTransform, RawDEM, blank_nodata, crs_is_geographic, raster_georeference
from ._dem_model import (
    DEM,
    clean_heights,
    dem_meta,
    georeference,
    is_dataarray,
    is_path_list,
    read_dataarray,
)
from .formats import FORMATS

__all__ = ["WindowReader", "chunk_dem", "parse_chunks", "read_dem_lazy", "reads_lazily"]

#: Formats without windowed reads (or read by our own parser, not GDAL): read whole, then chunked.
#: Open datasets kept per thread; a mosaic chunk touches a few tiles, so a small LRU suffices.
_CACHE_SIZE = 16
_local = threading.local()


def parse_chunks(chunks: Any) -> tuple[int, int] | str:
    """``chunks=``: a positive int, a pair of them, or ``"auto"`` -> dask's 2-D chunks."""
    if isinstance(chunks, str) and chunks == "auto":
        return chunks
    ok_int = lambda v: isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v > 0  # noqa: E731
    if ok_int(chunks):
        return int(chunks), int(chunks)
    if isinstance(chunks, (tuple, list)) and len(chunks) == 2 and all(map(ok_int, chunks)):
        return int(chunks[0]), int(chunks[1])
    raise InputError(
        f"chunks: expected a positive int, (rows, columns) of positive ints or 'auto', "
        f"got {chunks!r}"
    )


@dataclass(frozen=True)
class Tile:
    """One file of a lazy DEM and where it sits on the DEM's grid."""

    path: str
    shape: tuple[int, int]
    row_off: int
    col_off: int
    nodata: float | None
    #: (mtime_ns, size) when opened: a file rewritten in place is not served from a stale handle.
    stamp: tuple[int, int] = (0, 0)


def _open(path: str, stamp: tuple[int, int] = (0, 0)):
    """The dataset of ``path`` opened in this process and thread (GDAL handles are neither
    thread-safe nor fork-safe, so the cache is keyed by both) at version ``stamp``."""
    import rasterio

    cache = getattr(_local, "datasets", None)
    if cache is None or getattr(_local, "pid", None) != os.getpid():
        cache = _local.datasets = OrderedDict()
        _local.pid = os.getpid()
    key = (path, stamp)
    ds = cache.get(key)
    if ds is None:
        ds = cache[key] = rasterio.open(path)
        if len(cache) > _CACHE_SIZE:
            cache.popitem(last=False)[1].close()
    else:
        cache.move_to_end(key)
    return ds


def read_window(
    path: str, row0: int, col0: int, rows: int, cols: int, stamp: tuple[int, int] = (0, 0)
) -> np.ndarray:
    """Band 1 of ``path`` in the window ``rows`` x ``cols`` at ``(row0, col0)``, source dtype."""
    from rasterio.windows import Window

    try:
        return _open(path, stamp).read(1, window=Window(col0, row0, cols, rows))
    except Exception as exc:  # rasterio's error family, or an OSError of a vanished file
        raise InputError(f"{path}: cannot read rows {row0}-{row0 + rows} ({exc})") from exc


class WindowReader:
    """A (H, W) float32 array-like for ``dask.array.from_array``: slicing reads windows.

    Picklable (paths and numbers only) so a distributed worker opens the files itself.
    """

    def __init__(
        self, tiles: tuple[Tile, ...], shape: tuple[int, int], nodata: float | None, name: str
    ) -> None:
        self.tiles, self.shape, self.nodata, self.name = tiles, shape, nodata, name
        self.dtype, self.ndim = np.dtype(np.float32), 2

    def __getitem__(self, key: tuple[slice, slice]) -> np.ndarray:
        (r0, r1, _), (c0, c1, _) = (k.indices(n) for k, n in zip(key, self.shape, strict=True))
        single = len(self.tiles) == 1
        out = None if single else np.full((r1 - r0, c1 - c0), np.nan, np.float32)
        for t in self.tiles:
            tr0, tr1 = max(r0, t.row_off), min(r1, t.row_off + t.shape[0])
            tc0, tc1 = max(c0, t.col_off), min(c1, t.col_off + t.shape[1])
            if tr0 >= tr1 or tc0 >= tc1:
                continue
            raw = read_window(
                t.path, tr0 - t.row_off, tc0 - t.col_off, tr1 - tr0, tc1 - tc0, t.stamp
            )
            # The in-memory steps: file nodata (compared in the file's dtype), then nodata=.
            h = clean_heights(blank_nodata(raw, t.nodata, owned=True), self.name, self.nodata, True)
            if single:
                return h
            # Tiles sharing edge cells (SRTM) agree there; a void in one is filled by another.
            view = out[tr0 - r0 : tr1 - r0, tc0 - c0 : tc1 - c0]
            np.copyto(view, h, where=np.isfinite(h))
        return out if out is not None else np.full((r1 - r0, c1 - c0), np.nan, np.float32)


@dataclass
class _FileMeta:
    path: str
    shape: tuple[int, int]
    transform: GeoTransform | None
    crs: str | None
    geographic: bool | None
    nodata: float | None
    stamp: tuple[int, int] = (0, 0)


def _file_meta(path: Path) -> _FileMeta:
    """Shape, georeference and nodata of a raster file, without reading its pixels."""
    try:
        import rasterio
        from rasterio.errors import NotGeoreferencedWarning
    except ImportError as exc:
        raise InputError(
            f"{path}: reading a DEM with chunks= needs rasterio: pip install 'sciviz-gbuf[dask]'"
        ) from exc
    if not path.is_file():
        raise InputError(f"{path}: no such DEM file")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            with rasterio.open(path) as src:
                crs, geographic, transform = raster_georeference(src, path)
                dtype = np.dtype(src.dtypes[0])
                stat = path.stat()
                stamp = (stat.st_mtime_ns, stat.st_size)
                meta = _FileMeta(
                    str(path), src.shape, transform, crs, geographic, src.nodata, stamp
                )
    except rasterio.errors.RasterioError as exc:
        raise InputError(
            f"{path}: rasterio cannot read this DEM file ({' '.join(str(exc).split())})"
        ) from exc
    except UnicodeError as exc:  # GDAL takes UTF-8 file names only
        raise InputError(
            f"{path}: GDAL cannot open a file whose name is not UTF-8: rename it"
        ) from exc
    if not np.issubdtype(dtype, np.number) or np.issubdtype(dtype, np.complexfloating):
        raise InputError(f"{path}: expected real numeric heights, got dtype {dtype}")
    if meta.transform is not None:
        meta.transform = tuple(map(float, meta.transform))
    if path.suffix.lower() == ".asc":
        # As read_asc: the CRS is the .prj text as written (GDAL would rewrite its WKT).
        prj = path.with_suffix(".prj")
        meta.crs = (prj.read_text(encoding="latin-1").strip() or None) if prj.is_file() else None
        meta.geographic = crs_is_geographic(meta.crs)
    return meta


def _mosaic(metas: list[_FileMeta]) -> tuple[tuple[Tile, ...], tuple[int, int], GeoTransform]:
    """Tiles placed on the union grid of their transforms; InputError naming odd tiles."""
    first = metas[0]
    for m in metas:
        if m.transform is None:
            raise InputError(f"{m.path}: a mosaic tile needs a georeference, this file has none")
        if m.transform[2] != 0 or m.transform[4] != 0:
            raise InputError(f"{m.path}: rotated grids cannot be mosaicked ({m.transform})")
    _, dx, _, _, _, dy = first.transform
    for m in metas[1:]:
        if m.crs != first.crs:
            raise InputError(
                f"tiles of different CRS: {first.path} has {str(first.crs)[:60]!r}, "
                f"{m.path} has {str(m.crs)[:60]!r}"
            )
        if not np.allclose(m.transform[1::4], (dx, dy), rtol=1e-9, atol=0):
            raise InputError(
                f"tiles of different resolution: {first.path} has {dx:g} x {dy:g}, "
                f"{m.path} has {m.transform[1]:g} x {m.transform[5]:g}"
            )
    # Union grid: the north-west-most tile corner; dy < 0 (north up) or > 0 both handled.
    x0 = min(m.transform[0] for m in metas) if dx > 0 else max(m.transform[0] for m in metas)
    y0 = max(m.transform[3] for m in metas) if dy < 0 else min(m.transform[3] for m in metas)
    tiles = []
    for m in metas:
        col, row = (m.transform[0] - x0) / dx, (m.transform[3] - y0) / dy
        # 1e-3 pixel: transforms printed to ~12 digits (SRTM names, .asc headers) still align.
        if abs(col - round(col)) > 1e-3 or abs(row - round(row)) > 1e-3:
            raise InputError(
                f"{m.path}: not on the pixel grid of {first.path} (offset {col:.4f}, {row:.4f} "
                "pixels): tiles must share one grid"
            )
        tiles.append(Tile(m.path, m.shape, round(row), round(col), m.nodata, m.stamp))
    shape = (
        max(t.row_off + t.shape[0] for t in tiles),
        max(t.col_off + t.shape[1] for t in tiles),
    )
    return tuple(tiles), shape, (x0, dx, 0.0, y0, 0.0, dy)


def _token(tiles: tuple[Tile, ...], nodata: float | None) -> str:
    """Stable per file version (a rewritten file gets new dask keys)."""
    from dask.base import tokenize

    return tokenize([(t.path, t.stamp, t.row_off, t.col_off) for t in tiles], nodata)


def read_dem_lazy(
    source: Any,
    *,
    chunks: Any,
    spacing: Any = None,
    nodata: float | None = None,
    transform: GeoTransform | None = None,
    crs: str | None = None,
    geographic: bool | None = None,
):
    """:func:`~sciviz_gbuf.readers.read_dem` with dask heights (see its ``chunks``)."""
    import dask.array as da

    dchunks = "auto" if chunks is None else parse_chunks(chunks)
    if is_path_list(source) or isinstance(source, (str, os.PathLike)):
        paths = [Path(p) for p in (source if is_path_list(source) else [source])]
        bad = [p for p in paths if not _windowed(p)]
        if bad:
            raise InputError(
                f"{bad[0]}: mosaic tiles must be rasters GDAL reads, not {bad[0].suffix}"
            )
        metas = [_file_meta(p) for p in paths]
        name = (
            str(paths[0]) if len(paths) == 1 else f"mosaic of {len(paths)} tiles ({paths[0]}, ...)"
        )
        if len(metas) == 1:
            m = metas[0]
            tiles, shape = (Tile(m.path, m.shape, 0, 0, m.nodata, m.stamp),), m.shape
            raw = RawDEM(None, m.transform, m.crs, m.geographic)  # type: ignore[arg-type]
            if m.transform is None:
                warnings.warn(
                    f"{m.path}: raster without georeference: pixels taken as spacing= metres "
                    "(default 1 m)",
                    UserWarning,
                    stacklevel=3,
                )
        else:
            tiles, shape, union = _mosaic(metas)
            raw = RawDEM(None, union, metas[0].crs, metas[0].geographic)  # type: ignore[arg-type]
        if raw.transform is not None and (transform is not None or crs is not None):
            raise InputError(f"{name}: transform=/crs= are for sources without a georeference")
        if raw.transform is None:
            raw.transform, raw.crs, raw.geographic = transform, crs, crs_is_geographic(crs)
        elif spacing is not None:
            raise InputError(
                f"{name}: spacing= is for sources without a georeference; this one has "
                f"transform {raw.transform}"
            )
        reader = WindowReader(tiles, shape, nodata, name)
        heights = da.from_array(
            reader,
            chunks=dchunks,
            name=f"read_dem-{_token(tiles, nodata)}",
            meta=np.empty((0, 0), np.float32),
            asarray=False,
        )
        # Window reads of their own for out-of-core maps (memory independent of the size).
        _dask.register_windows(heights, reader)
        geo = georeference(raw, shape, name, spacing=spacing, geographic=geographic)
        return DEM(heights, da.isfinite(heights), raw.crs, *geo, name)
    if is_dataarray(source) and _dask.is_dask(getattr(source, "data", None)):
        name = f"DataArray {getattr(source, 'name', None)!r}"
        if transform is not None or crs is not None:
            raise InputError(f"{name}: transform=/crs= are for sources without a georeference")
        if spacing is not None:
            raise InputError(f"{name}: spacing= is for sources without a georeference")
        raw, da_nodata = read_dataarray(source, name, lazy=True)
        values = raw.heights
        if min(values.shape) == 0:
            raise InputError(f"{name}: expected a non-empty 2-D array, got shape {values.shape}")
        if not np.issubdtype(values.dtype, np.number) or np.iscomplexobj(values):
            raise InputError(f"{name}: expected real numeric heights, got dtype {values.dtype}")
        heights = values.map_blocks(
            _dataarray_block,
            da_nodata,
            nodata,
            name,
            dtype=np.float32,
            meta=np.empty((0, 0), np.float32),
        )
        if chunks is not None:
            heights = heights.rechunk(dchunks)
        geo = georeference(raw, heights.shape, name, spacing=None, geographic=geographic)
        return DEM(heights, da.isfinite(heights), raw.crs, *geo, name)
    raise InputError(f"{type(source).__name__}: nothing to read lazily (see reads_lazily)")


def _windowed(path: Path) -> bool:
    """GDAL reads it in windows: a listed windowed format, or any raster not listed (VRT...)."""
    fmt = FORMATS.get(path.suffix.lower())
    return fmt is None or fmt.windowed


def reads_lazily(source: Any) -> bool:
    """Whether :func:`read_dem_lazy` reads ``source`` by windows or blocks: tile lists, files
    GDAL reads in windows, dask-backed DataArrays. Arrays, in-memory DataArrays and files
    parsed whole (``.npy``, ``.npz``, ``.dem``) are read into memory, then chunked."""
    if is_path_list(source):
        return True
    if isinstance(source, (str, os.PathLike)):
        return _windowed(Path(source))
    return is_dataarray(source) and _dask.is_dask(getattr(source, "data", None))


def _dataarray_block(
    values: np.ndarray, da_nodata: float | None, nodata: float | None, name: str
) -> np.ndarray:
    """One block of a dask DataArray through read_dem's in-memory nodata steps."""
    if da_nodata is not None:
        values = np.where(values == da_nodata, np.nan, values)
    return clean_heights(np.asarray(values), name, nodata)


def chunk_dem(dem, chunks: tuple[int, int] | str):
    """An in-memory DEM with its heights wrapped as a dask array of ``chunks``."""
    import dask.array as da

    heights = da.from_array(dem.heights, chunks=chunks)
    return DEM(heights, da.isfinite(heights), *dem_meta(dem))
