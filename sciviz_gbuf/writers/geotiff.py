"""Georeferenced GeoTIFF files of images (rasterio), and the georeference checks that the
Cloud-Optimized GeoTIFF writer shares."""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .._atomic import Part, atomic_output
from ..errors import InputError
from .png import LARGE_IMAGE, to_uint8

__all__ = [
    "check_tiff",
    "gdal_writing",
    "georeference",
    "rasterio_crs",
    "uint8_profile",
    "write_geotiff",
]


def georeference(
    dem: object, transform: object, crs: object, who: str, shape: Sequence[int] | None = None
) -> np.ndarray:
    """The checked GDAL geotransform of ``dem=`` or ``transform=`` (exactly one of them).

    ``shape``: the image's ``(rows, columns)``. An image of ``dem=`` on another grid than the
    DEM's (a map drawn at another size, ``topographic_map(size=/scale=)``) covers the DEM's
    extent: its pixel size is the DEM's times ``dem.shape / shape`` (``gdal_translate
    -outsize``), so its transform follows the output pixel."""
    if dem is not None:
        if transform is not None or crs is not None:
            raise InputError(f"{who}: give dem= or transform=/crs=, not both")
        transform = dem.transform
        if shape is not None and tuple(dem.shape) != tuple(shape):
            (h, w), (oh, ow) = dem.shape, shape
            x0, dx, rx, y0, ry, dy = (float(v) for v in transform)
            fx, fy = w / ow, h / oh
            transform = (x0, dx * fx, rx * fy, y0, ry * fx, dy * fy)
    if transform is None:
        raise InputError(f"{who}: a georeference is needed: pass dem= or transform=")
    gt = np.asarray(transform, dtype=np.float64).reshape(-1)
    if gt.size != 6 or not np.isfinite(gt).all() or gt[1] == 0 or gt[5] == 0:
        raise InputError(
            f"transform: expected a GDAL 6-tuple with non-zero pixel size, got {transform!r}"
        )
    return gt


def rasterio_crs(crs: object):
    """``crs`` (EPSG code, WKT, ...) as a rasterio CRS, None as None; InputError if unreadable."""
    from rasterio.crs import CRS

    try:
        return None if crs is None else CRS.from_user_input(crs)
    except Exception as exc:  # rasterio raises its own CRSError family
        raise InputError(f"crs: rasterio cannot read {str(crs)[:80]!r}: {exc}") from exc


@contextmanager
def gdal_writing(part: Part) -> Iterator[None]:
    """Around GDAL calls that write ``part``: what GDAL and libtiff print goes into the
    message (they print to file descriptor 2, not through Python), and rasterio's exceptions
    become the :class:`~sciviz_gbuf.errors.OutputError` naming the output."""
    from rasterio._err import CPLE_BaseError
    from rasterio.errors import RasterioError

    with part.native():
        try:
            yield
        except (RasterioError, CPLE_BaseError) as exc:
            part.fail(exc)


def check_tiff(part: Part, shape: tuple[int, int, int], path: Path | None = None) -> None:
    """Raise the OutputError of ``part`` unless the closed TIFF it holds (or ``path``, a file
    written on its way) is whole.

    rasterio does not report errors of GDAL's close, where the TIFF directory and the last
    cached blocks are written: a full disk there leaves a file that looks written. So the file
    is opened again (the directory is readable), its size and bands are ``shape`` ``(h, w, c)``,
    and every block of the full-resolution image (band 1: the bands are pixel-interleaved)
    has an offset and lies within the file's size. Overviews of a COG come before those
    blocks, so a file cut short loses the last of them first. Only the TIFF directory is read.
    """
    import rasterio

    path = part.path if path is None else path
    size = path.stat().st_size
    with gdal_writing(part), rasterio.open(path) as src:
        got = (src.height, src.width, src.count)
        if got != tuple(shape):
            part.fail(f"GDAL reads an image of (rows, columns, bands) {got}, not {tuple(shape)}")
        bh, bw = src.block_shapes[0]
        end = 0
        for i in range(math.ceil(src.height / bh)):
            for j in range(math.ceil(src.width / bw)):
                offset = src.get_tag_item(f"BLOCK_OFFSET_{j}_{i}", "TIFF", bidx=1)
                nbytes = src.get_tag_item(f"BLOCK_SIZE_{j}_{i}", "TIFF", bidx=1)
                if not offset or not nbytes or int(offset) == 0 or int(nbytes) == 0:
                    part.fail(f"block ({i}, {j}) of the image was not written")
                end = max(end, int(offset) + int(nbytes))
    if end > size:
        part.fail(f"the image's blocks need {end} bytes, the file holds {size}")


def uint8_profile(
    h: int,
    w: int,
    c: int,
    transform: object,
    crs: object,
    *,
    block: int | None,
    zlevel: int,
    predictor: int | None = None,
    bigtiff: bool = False,
) -> dict:
    """The rasterio profile of every 8-bit GeoTIFF written here (:func:`write_geotiff` and the
    tiled intermediate of the Cloud-Optimized GeoTIFF): deflate, pixel-interleaved, RGB(A)
    photometry, the last band of 2 or 4 an unassociated alpha (GIS software shows nodata as
    transparent). ``block``: square tiles of this size (None: strips)."""
    profile = {
        "driver": "GTiff",
        "width": w,
        "height": h,
        "count": c,
        "dtype": "uint8",
        "crs": crs,
        "transform": transform,
        "compress": "deflate",
        "zlevel": zlevel,
        "num_threads": "ALL_CPUS",
        "interleave": "pixel",
    }
    if predictor is not None:
        profile["predictor"] = predictor
    if block is not None:
        profile.update(tiled=True, blockxsize=block, blockysize=block)
    if bigtiff:
        profile["bigtiff"] = "if_safer"
    if c >= 3:
        profile["photometric"] = "RGB"
    if c in (2, 4):
        profile["alpha"] = "unassociated"
    return profile


def write_geotiff(
    path: str | os.PathLike,
    image: np.ndarray,
    *,
    dem: object = None,
    transform: Sequence[float] | None = None,
    crs: str | None = None,
) -> Path:
    """Write an image as a georeferenced, tiled, deflate-compressed GeoTIFF (needs rasterio).

    Parameters
    ----------
    path : str or path-like
        Output file (``.tif``/``.tiff``); its directory must exist.
    image : (H, W), (H, W, 3) or (H, W, 4) array_like
        Float in ``[0, 1]``, uint8 or bool; written as 8-bit grey, RGB or RGBA (the fourth band
        tagged as alpha, so GIS software shows nodata as transparent).
    dem : sciviz_gbuf.readers.DEM, optional
        Take ``transform`` and ``crs`` from this DEM (the grid the image was made on); an
        image of another size covers the DEM's extent (a map at another ``size``/``scale``):
        the pixel size follows the image (see :func:`georeference`).
    transform : 6 floats, optional
        GDAL geotransform of the pixel corners.
    crs : str, optional
        Anything rasterio's ``CRS.from_user_input`` accepts (``"EPSG:4326"``, WKT).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        A bad name, folder, image or georeference.
    OutputError
        The file could not be written completely (disk full, file too large, a GDAL error,
        interrupted): nothing new is left under its name (it is written to a temporary file
        beside it, checked with :func:`check_tiff`, then renamed).
    """
    p = Path(path)
    if p.suffix.lower() not in (".tif", ".tiff"):
        raise InputError(f"path: expected a file name ending in .tif or .tiff, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"path: no such directory {str(p.parent)!r}")
    pixels = to_uint8(image)
    gt = georeference(dem, transform, crs, "write_geotiff", pixels.shape[:2])
    if pixels.ndim == 2:
        pixels = pixels[..., None]
    try:
        import rasterio
        from rasterio.enums import ColorInterp
        from rasterio.transform import Affine
    except ImportError as exc:
        raise InputError(
            f"{p}: writing GeoTIFF needs rasterio: pip install 'sciviz-gbuf[geo]'"
        ) from exc
    h, w, c = pixels.shape
    profile = uint8_profile(
        h,
        w,
        c,
        Affine.from_gdal(*gt),
        rasterio_crs(dem.crs if dem is not None else crs),
        block=256 if h >= 256 and w >= 256 else None,
        zlevel=1 if h * w >= LARGE_IMAGE else 6,
        predictor=2,
    )
    interp = {
        1: [ColorInterp.gray],
        2: [ColorInterp.gray, ColorInterp.alpha],
        3: [ColorInterp.red, ColorInterp.green, ColorInterp.blue],
        4: [ColorInterp.red, ColorInterp.green, ColorInterp.blue, ColorInterp.alpha],
    }[c]
    with atomic_output(path) as part:
        with gdal_writing(part), rasterio.open(part.path, "w", **profile) as dst:
            dst.colorinterp = interp  # before the pixels: GDAL fixes the TIFF's ExtraSamples
            dst.write(np.moveaxis(pixels, 2, 0))
        check_tiff(part, (h, w, c))
    return p
