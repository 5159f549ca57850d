"""read_dem(..., chunks=): lazy dask heights equal to the in-memory read, read by windows."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest

da = pytest.importorskip("dask.array")
rasterio = pytest.importorskip("rasterio")
from rasterio.transform import Affine  # noqa: E402
from rasterio.windows import Window  # noqa: E402

from sciviz_gbuf.errors import InputError  # noqa: E402
from sciviz_gbuf.readers import _lazy, read_dem  # noqa: E402

#: Odd chunks: every chunk border falls mid-grid, none on a tile or block edge.
ODD = (7, 13)


def _same_dem(lazy, eager) -> None:
    assert isinstance(lazy.heights, da.Array) and isinstance(lazy.mask, da.Array)
    heights = lazy.heights.compute(scheduler="threads")
    assert heights.dtype == np.float32
    np.testing.assert_array_equal(heights, eager.heights)  # NaN == NaN here
    np.testing.assert_array_equal(lazy.mask.compute(), eager.mask)
    assert lazy.transform == eager.transform
    assert lazy.crs == eager.crs
    assert lazy.pixel_size == eager.pixel_size
    assert lazy.geographic == eager.geographic
    assert lazy.shape == eager.shape


@pytest.mark.parametrize(
    ("name", "chunks"),
    [
        ("hugo_site.asc", ODD),
        ("pre_runout_DEM.asc", ODD),
        ("SRTMGL3_40.09_-105.55_40.21_-105.35.asc", ODD),
        ("N10W110.hgt", (157, 301)),  # 1201², odd chunks but not 20 000 of them
    ],
)
def test_lazy_equals_in_memory_on_shared_dems(shared_data, name, chunks):
    path = shared_data / "dem" / name
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the SRTM .asc has no CRS: degrees guessed
        eager = read_dem(path)
        lazy = read_dem(path, chunks=chunks)
    assert lazy.heights.chunksize == chunks
    _same_dem(lazy, eager)


def test_user_nodata_and_geographic_options_like_in_memory(shared_data):
    path = shared_data / "dem" / "hugo_site.asc"
    value = float(np.nanmedian(read_dem(path).heights))
    eager = read_dem(path, nodata=value, geographic=False)
    _same_dem(read_dem(path, nodata=value, geographic=False, chunks=ODD), eager)


def _geotiff(path, heights, transform, *, crs="EPSG:32633", nodata=-9999.0):
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=heights.shape[1],
        height=heights.shape[0],
        count=1,
        dtype=heights.dtype,
        crs=crs,
        transform=Affine.from_gdal(*transform),
        nodata=nodata,
    ) as dst:
        dst.write(heights, 1)
    return path


@pytest.fixture
def big_tif(tmp_path):
    rng = np.random.default_rng(1)
    heights = rng.normal(500, 50, (61, 83)).astype(np.float32)
    heights[5:9, 10:30] = -9999.0
    transform = (500_000.0, 30.0, 0.0, 4_200_000.0, 0.0, -30.0)
    return _geotiff(tmp_path / "big.tif", heights, transform), heights, transform


def test_geotiff_lazy_equals_in_memory(big_tif):
    path, _, _ = big_tif
    _same_dem(read_dem(path, chunks=ODD), read_dem(path))


@pytest.mark.parametrize("chunks", [16, (20, 83), "auto"])
def test_chunks_forms(big_tif, chunks):
    path, _, _ = big_tif
    dem = read_dem(path, chunks=chunks)
    assert dem.shape == (61, 83)
    if chunks == 16:
        assert dem.heights.chunksize == (16, 16)
    np.testing.assert_array_equal(dem.heights.compute(), read_dem(path).heights)


def test_mosaic_of_overlapping_tiles_equals_original(big_tif, tmp_path):
    path, _, _ = big_tif
    original = read_dem(path)
    # 4 tiles overlapping by 3 rows/columns (cut like SRTM tiles sharing edges, but wider).
    tiles = []
    with rasterio.open(path) as src:
        for k, (r0, r1, c0, c1) in enumerate(
            [(0, 33, 0, 45), (30, 61, 0, 45), (0, 33, 42, 83), (30, 61, 42, 83)]
        ):
            win = Window(c0, r0, c1 - c0, r1 - r0)
            tiles.append(
                _geotiff(
                    tmp_path / f"tile{k}.tif",
                    src.read(1, window=win),
                    src.window_transform(win).to_gdal(),
                )
            )
    mosaic = read_dem(tiles[::-1], chunks=ODD)  # order must not matter
    _same_dem(mosaic, original)
    in_memory = read_dem([str(t) for t in tiles])  # no chunks: computed into memory
    assert isinstance(in_memory.heights, np.ndarray)
    np.testing.assert_array_equal(in_memory.heights, original.heights)


def test_mosaic_gap_is_nan_and_srtm_tiles_share_edges(shared_data, tmp_path):
    # Two SRTM-3 tiles side by side as the .hgt format defines them: N10W110 and a copy named
    # N10W109 (one degree east), sharing the column at 109° W.
    src = shared_data / "dem" / "N10W110.hgt"
    east = tmp_path / "N10W109.hgt"
    east.write_bytes(src.read_bytes())
    west = tmp_path / "N10W110.hgt"
    west.write_bytes(src.read_bytes())
    mosaic = read_dem([west, east], chunks=(400, 700))
    assert mosaic.shape == (1201, 2401)
    one = read_dem(src)
    assert mosaic.transform == one.transform
    heights = mosaic.heights[:, 1100:1300].compute()
    np.testing.assert_array_equal(heights[:, :101], one.heights[:, 1100:])
    np.testing.assert_array_equal(heights[:, 100:], one.heights[:, :100])
    # A gap: tiles at 110° W and 108° W leave 107° W..109° W empty (NaN).
    far = tmp_path / "N10W108.hgt"
    far.write_bytes(src.read_bytes())
    gap = read_dem([west, far], chunks=600)
    assert gap.shape == (1201, 3601)
    assert np.isnan(gap.heights[:, 1201:2400].compute()).all()


def test_reader_reads_only_chunk_windows(big_tif, monkeypatch):
    path, _, _ = big_tif
    seen = []
    real = _lazy.read_window

    def spy(p, row0, col0, rows, cols, stamp):
        seen.append((rows, cols))
        return real(p, row0, col0, rows, cols, stamp)

    monkeypatch.setattr(_lazy, "read_window", spy)
    dem = read_dem(path, chunks=(10, 20))
    assert seen == []  # opening reads metadata only
    dem.heights[:10, :20].compute(scheduler="sync")
    assert seen == [(10, 20)]
    dem.heights.compute(scheduler="sync")
    assert max(r * c for r, c in seen) <= 10 * 20
    assert sum(r * c for r, c in seen[1:]) == 61 * 83  # each cell read once


def test_graph_is_picklable(big_tif):
    path, _, _ = big_tif
    dem = read_dem(path, chunks=ODD)
    graph = dict(dem.heights.__dask_graph__())
    pickle.loads(pickle.dumps(graph))  # only paths and numbers: fine for distributed workers


def test_dask_dataarray_stays_lazy():
    xr = pytest.importorskip("xarray")
    values = np.arange(12 * 9, dtype=np.int16).reshape(12, 9)
    values[3, 4] = -1
    arr = xr.DataArray(
        da.from_array(values, chunks=5),
        dims=("y", "x"),
        coords={"y": 100.0 + 10 * np.arange(12), "x": 5.0 + 10 * np.arange(9)},  # y increases
        attrs={"_FillValue": -1, "crs": "EPSG:32633"},
    )
    lazy = read_dem(arr, chunks=(4, 4))
    eager = read_dem(arr.compute())
    _same_dem(lazy, eager)
    assert lazy.heights.chunksize == (4, 4)


def test_numpy_and_npy_sources_are_chunked(tmp_path):
    values = np.random.default_rng(2).normal(size=(20, 30)).astype(np.float32)
    np.save(tmp_path / "a.npy", values)
    for src in (values, tmp_path / "a.npy"):
        dem = read_dem(src, chunks=8, spacing=2.0)
        assert dem.heights.chunksize == (8, 8)
        _same_dem(dem, read_dem(src, spacing=2.0))


@pytest.mark.parametrize("chunks", [0, -5, 2.5, (3,), (3, 0), "big", True, (4, None)])
def test_bad_chunks(big_tif, chunks):
    path, _, _ = big_tif
    with pytest.raises(InputError, match="chunks"):
        read_dem(path, chunks=chunks)


def test_bad_files(tmp_path, big_tif):
    with pytest.raises(InputError, match=r"missing\.tif: no such DEM file"):
        read_dem(tmp_path / "missing.tif", chunks=8)
    junk = tmp_path / "junk.tif"
    junk.write_bytes(b"not a tiff at all")
    with pytest.raises(InputError, match=r"junk\.tif"):
        read_dem(junk, chunks=8)
    rgb = tmp_path / "rgb.tif"
    with rasterio.open(rgb, "w", driver="GTiff", width=4, height=4, count=3, dtype="uint8") as dst:
        dst.write(np.zeros((3, 4, 4), np.uint8))
    with pytest.raises(InputError, match="RGB"):
        read_dem(rgb, chunks=8)
    path, _, _ = big_tif
    with pytest.raises(InputError, match="spacing"):
        read_dem(path, chunks=8, spacing=3.0)


def test_mosaic_mismatch_names_files(big_tif, tmp_path):
    path, heights, transform = big_tif
    other_crs = _geotiff(tmp_path / "crs.tif", heights, transform, crs="EPSG:32632")
    with pytest.raises(InputError, match=r"CRS.*big\.tif.*crs\.tif"):
        read_dem([path, other_crs], chunks=8)
    coarse = (transform[0], 60.0, 0.0, transform[3], 0.0, -60.0)
    other_res = _geotiff(tmp_path / "res.tif", heights, coarse)
    with pytest.raises(InputError, match=r"resolution.*big\.tif.*res\.tif"):
        read_dem([path, other_res], chunks=8)
    shifted = (transform[0] + 7.0, *transform[1:])
    off_grid = _geotiff(tmp_path / "shift.tif", heights, shifted)
    with pytest.raises(InputError, match=r"shift\.tif.*grid"):
        read_dem([path, off_grid], chunks=8)


def test_rewritten_file_is_read_afresh(big_tif):
    path, heights, transform = big_tif
    first = read_dem(path, chunks=ODD).heights.compute(scheduler="sync")
    bumped = np.where(heights == -9999.0, heights, heights + 1)
    _geotiff(path, bumped, transform)  # same path, new contents (and mtime)
    second = read_dem(path, chunks=ODD).heights.compute(scheduler="sync")
    np.testing.assert_array_equal(second[np.isfinite(second)], first[np.isfinite(first)] + 1)
