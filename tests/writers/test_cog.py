"""write_cog: Cloud-Optimised GeoTIFF from numpy or dask images, on threads and distributed."""

from __future__ import annotations

import os

import numpy as np
import pytest

da = pytest.importorskip("dask.array")
rasterio = pytest.importorskip("rasterio")
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from PIL import Image  # noqa: E402

from sciviz_gbuf.cli import main  # noqa: E402
from sciviz_gbuf.errors import InputError  # noqa: E402
from sciviz_gbuf.writers.cog import check_cog, write_cog  # noqa: E402

TRANSFORM = (500_000.0, 10.0, 0.0, 4_200_000.0, 0.0, -10.0)
CRS = "EPSG:32633"


def _rgba(shape=(1100, 1300), chunks=(300, 700)):
    return da.random.default_rng(3).integers(
        0, 256, size=(*shape, 4), chunks=(*chunks, 4), dtype=np.uint8
    )


def _read(path) -> np.ndarray:
    with rasterio.open(path) as src:
        return np.moveaxis(src.read(), 0, 2)


def _assert_cog(path, image, transform=TRANSFORM, crs=CRS) -> None:
    check_cog(path)
    with rasterio.open(path) as src:
        assert src.tags(ns="IMAGE_STRUCTURE")["LAYOUT"] == "COG"
        assert src.profile["tiled"] and src.block_shapes[0] == (512, 512)
        assert src.overviews(1)  # > 512 px: at least one level
        assert src.compression.name.lower() == "deflate"
        assert src.transform.to_gdal() == transform
        assert src.crs == rasterio.crs.CRS.from_user_input(crs)
        if src.count == 4:
            assert src.colorinterp[3] == rasterio.enums.ColorInterp.alpha
    np.testing.assert_array_equal(_read(path), np.asarray(image))


def test_dask_rgba_round_trip_threads(tmp_path):
    image = _rgba()
    out = write_cog(image, tmp_path / "map.tif", transform=TRANSFORM, crs=CRS)
    assert out == tmp_path / "map.tif"
    _assert_cog(out, image.compute())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.tif"]  # temp files removed


def test_numpy_rgb_and_grey(tmp_path):
    rgb = np.random.default_rng(4).integers(0, 256, (600, 700, 3), dtype=np.uint8)
    _assert_cog(write_cog(rgb, tmp_path / "rgb.tif", transform=TRANSFORM, crs=CRS), rgb)
    grey = rgb[..., 0]
    out = write_cog(grey, tmp_path / "grey.tif", transform=TRANSFORM, crs=CRS)
    _assert_cog(out, grey[..., None])


def test_dem_georeference_and_float_dask(tmp_path):
    from sciviz_gbuf.readers import read_dem

    dem = read_dem(np.zeros((520, 530), np.float32), transform=TRANSFORM, crs=CRS)
    image = da.linspace(0, 1, 520 * 530 * 3, chunks=-1).reshape(520, 530, 3).rechunk(256)
    out = write_cog(image, tmp_path / "f.tiff", dem=dem)
    expected = np.rint(image.compute() * 255).astype(np.uint8)
    _assert_cog(out, expected)


def test_overview_png_size(tmp_path):
    image = _rgba((1100, 1300))
    png = tmp_path / "small.png"
    write_cog(image, tmp_path / "m.tif", transform=TRANSFORM, overview_png=png, overview_size=200)
    with Image.open(png) as im:
        assert im.size == (200, round(1100 * 200 / 1300)) and im.mode == "RGBA"
    big = tmp_path / "big.png"
    write_cog(image[:300, :400], tmp_path / "n.tif", transform=TRANSFORM, overview_png=big)
    with Image.open(big) as im:
        assert im.size == (400, 300)  # smaller than overview_size: full size


def test_sync_scheduler_and_bounded_batches(tmp_path):
    import dask
    from dask.local import get_sync

    image = _rgba((700, 600), (512, 512))
    with dask.config.set(scheduler="sync"):
        out = write_cog(image, tmp_path / "s.tif", transform=TRANSFORM)
    np.testing.assert_array_equal(_read(out), image.compute())

    # The path of process pools and other schedulers that return results to this process:
    # any scheduler dask's threads and local schedulers are not.
    def elsewhere(dsk, keys, **kwargs):
        return get_sync(dsk, keys, **kwargs)

    calls = []

    def counting(dsk, keys, **kwargs):
        calls.append(len(keys))
        return elsewhere(dsk, keys, **kwargs)

    with dask.config.set(scheduler=counting):
        out = write_cog(image, tmp_path / "b.tif", transform=TRANSFORM)
    np.testing.assert_array_equal(_read(out), image.compute())
    assert calls and all(n <= 2 * (os.cpu_count() or 1) for n in calls)
    assert sum(calls) == 4  # 2 x 2 blocks, in batches


def test_local_cluster_two_worker_processes(tmp_path):
    distributed = pytest.importorskip("distributed")
    image = _rgba((1100, 1300), (512, 512))
    expected = image.compute()
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        out = write_cog(image, tmp_path / "d.tif", transform=TRANSFORM, crs=CRS, client=client)
    _assert_cog(out, expected)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"path": "x.png"}, "path: expected a file name ending in .tif"),
        ({"path": "nodir/x.tif"}, "no such directory"),
        ({"transform": None}, "georeference is needed"),
        ({"transform": (0, 0, 0, 0, 0, -1)}, "transform"),
        ({"crs": "EPSG:nonsense"}, "crs"),
        ({"image": np.zeros((5, 5, 2), np.uint8)}, "shape"),
        ({"image": da.zeros((5, 5, 2), dtype=np.uint8)}, "shape"),
        ({"image": da.zeros((5, 5), dtype=np.int16)}, "dtype"),
        ({"overview_png": "x.jpg"}, "overview_png"),
        ({"overview_size": 0}, "overview_size"),
        ({"client": 42}, "client"),
    ],
)
def test_bad_inputs(tmp_path, kwargs, message):
    args = {"image": da.zeros((8, 8, 4), dtype=np.uint8), "path": "x.tif", "transform": TRANSFORM}
    args.update(kwargs)
    for key in ("path", "overview_png"):
        if isinstance(args.get(key), str):
            args[key] = tmp_path / args[key]
    with pytest.raises(InputError, match=message):
        write_cog(args.pop("image"), args.pop("path"), **args)


def test_image_of_another_size_covers_the_dems_extent(tmp_path):
    """A map drawn at another size (topographic_map(size=/scale=)) keeps the DEM's extent:
    the COG's pixel size follows the image (gdal_translate -outsize)."""
    import rasterio

    from sciviz_gbuf.readers import read_dem

    dem = read_dem(np.zeros((9, 12), np.float32), spacing=10.0)
    write_cog(np.zeros((18, 30, 4), np.uint8), tmp_path / "x.tif", dem=dem)
    with rasterio.open(tmp_path / "x.tif") as src:
        gt = src.transform.to_gdal()
        assert (src.height, src.width) == (18, 30)
    x0, dx, _, y0, _, dy = dem.transform
    assert gt == pytest.approx((x0, dx * 12 / 30, 0.0, y0, 0.0, dy * 9 / 18))


# --- command line ------------------------------------------------------------------------------


@pytest.fixture
def dem_tif(tmp_path):
    from rasterio.transform import Affine

    y, x = np.mgrid[0:90, 0:110]
    heights = (200 + 40 * np.sin(x / 9.0) * np.cos(y / 7.0) + y).astype(np.float32)
    heights[:4, :6] = np.nan
    path = tmp_path / "dem.tif"
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=110,
        height=90,
        count=1,
        dtype="float32",
        crs=CRS,
        transform=Affine.from_gdal(*TRANSFORM),
        nodata=np.nan,
    ) as dst:
        dst.write(heights, 1)
    return path


def test_cli_topo_chunks_matches_in_memory(dem_tif, tmp_path, capsys):
    lazy, eager = tmp_path / "lazy.tif", tmp_path / "eager.tif"
    common = ["--contours", "20,100", "--no-progress"]
    assert main(["topo", str(dem_tif), "-o", str(eager), *common]) == 0
    argv = ["topo", str(dem_tif), "-o", str(lazy), "--chunks", "37,41", "--overview"]
    assert main([*argv, str(tmp_path / "o.png"), "--overview-size", "55", *common]) == 0
    assert "chunks (37, 41)" in capsys.readouterr().out
    check_cog(lazy)
    np.testing.assert_array_equal(_read(lazy), _read(eager))
    with rasterio.open(lazy) as src:
        assert src.transform.to_gdal() == TRANSFORM
    with Image.open(tmp_path / "o.png") as im:
        assert im.size == (55, 45)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["-o", "{tmp}/m.png", "--chunks", "64"], "expected a .tif"),
        (["-o", "{tmp}/m.jpg"], "ending in .png, .tif, .svg or .pdf"),
        (["-o", "{tmp}/m.png", "--overview", "{tmp}/o.png"], "--overview"),
        (["-o", "{tmp}/m.tif", "--dask", "tcp://x:1", "--workers", "3"], "--workers"),
    ],
)
def test_cli_topo_bad_out_of_core_arguments(dem_tif, tmp_path, capsys, argv, message):
    argv = [a.format(tmp=tmp_path) for a in argv]
    assert main(["topo", str(dem_tif), *argv]) == 2
    assert message in capsys.readouterr().err


def test_cli_topo_missing_tile(dem_tif, tmp_path, capsys):
    argv = ["topo", str(dem_tif), str(tmp_path / "missing.tif"), "-o", str(tmp_path / "m.tif")]
    assert main([*argv, "--chunks", "64"]) == 2
    assert "missing.tif: no such DEM file" in capsys.readouterr().err


def test_cli_topo_bad_chunks(dem_tif, tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["topo", str(dem_tif), "-o", str(tmp_path / "m.tif"), "--chunks", "0"])
    assert "chunk size" in capsys.readouterr().err


# ------------------------------------------------------------------ the COG layout itself
def _map_like(h: int, w: int) -> np.ndarray:
    """An RGBA map-like image: smooth colours (they compress, as maps do), a transparent
    (nodata) disc and a few noisy tiles (they do not)."""
    y, x = np.mgrid[0:h, 0:w]
    rgba = np.stack(
        [
            x * 255 // max(w - 1, 1),
            y * 255 // max(h - 1, 1),
            (x + y) // 7 % 256,
            np.full_like(x, 255),
        ],
        axis=-1,
    ).astype(np.uint8)
    rgba[(x - w // 3) ** 2 + (y - h // 2) ** 2 < (min(h, w) // 4) ** 2, 3] = 0
    rgba[: h // 5, w // 2 :] = np.random.default_rng(1).integers(
        0, 256, rgba[: h // 5, w // 2 :].shape
    )
    return rgba


def _mean_level(a: np.ndarray) -> np.ndarray:
    """The next overview level by float arithmetic (an independent statement of the
    writer's integer one): the mean of the 2 x 2 pixels present; colour weighted by alpha."""
    h, w, c = a.shape
    f = np.zeros((h + h % 2, w + w % 2, c))
    f[:h, :w] = a
    n = np.zeros((h + h % 2, w + w % 2))
    n[:h, :w] = 1.0

    def s(v):
        return v[0::2, 0::2] + v[1::2, 0::2] + v[0::2, 1::2] + v[1::2, 1::2]

    out = np.empty((f.shape[0] // 2, f.shape[1] // 2, c))
    if c == 4:
        alpha = s(f[..., 3])
        for b in range(3):
            with np.errstate(invalid="ignore", divide="ignore"):
                out[..., b] = np.where(alpha > 0, s(f[..., b] * f[..., 3]) / alpha, 0.0)
        out[..., 3] = alpha / s(n)
    else:
        for b in range(c):
            out[..., b] = s(f[..., b]) / s(n)
    return np.floor(out + 0.5).astype(np.uint8)


@pytest.mark.parametrize("shape", [(1300, 2100, 4), (1025, 513, 3), (700, 1500, 1)])
def test_overview_levels_are_the_means_of_the_level_below(tmp_path, shape):
    image = _map_like(*shape[:2])[..., : shape[2]]
    written = image[..., 0] if shape[2] == 1 else image  # grey goes in as (H, W)
    out = write_cog(written, tmp_path / "o.tif", transform=TRANSFORM, crs=CRS)
    level = image
    with rasterio.open(out) as src:
        n_overviews = len(src.overviews(1))
    assert n_overviews >= 1
    for k in range(n_overviews):
        level = _mean_level(level)
        with rasterio.open(out, overview_level=k) as src:
            got = np.moveaxis(src.read(), 0, 2)
        np.testing.assert_array_equal(got, level, err_msg=f"overview {k}")
    assert max(level.shape[:2]) <= 512 < max(level.shape[0] * 2, level.shape[1] * 2)


@pytest.mark.parametrize("chunks", [(512, 512), (1024, 2048), (700, 1300), (2048, 512)])
def test_the_file_does_not_depend_on_the_chunks(tmp_path, chunks):
    """Where a tile is encoded (a chunk of any size, or the in-memory path) does not change a
    byte of the file."""
    image = _map_like(2300, 2700)
    whole = write_cog(image, tmp_path / "whole.tif", transform=TRANSFORM, crs=CRS)
    lazy = da.from_array(image, chunks=(*chunks, 4))
    part = write_cog(lazy, tmp_path / "lazy.tif", transform=TRANSFORM, crs=CRS)
    assert whole.read_bytes() == part.read_bytes()


def test_an_independent_tiff_reader_agrees(tmp_path):
    """tifffile (its own TIFF decoder) reads every level's pixels, and finds GDAL's COG
    layout: directories before the data, the smallest level's tiles first, each level's
    tiles in row-major order with GDAL's size leader and repeated-last-4-bytes trailer."""
    tifffile = pytest.importorskip("tifffile")
    image = _map_like(1900, 2600)
    out = write_cog(image, tmp_path / "t.tif", transform=TRANSFORM, crs=CRS)
    raw = out.read_bytes()
    assert b"LAYOUT=IFDS_BEFORE_DATA" in raw[:200]
    level = image
    with tifffile.TiffFile(out) as tif:
        pages = tif.pages
        assert len(pages) == 4  # 2600 -> 1300 -> 650 -> 325
        last_ifd = max(p.offset for p in pages)
        first_tile = []
        for k, page in enumerate(pages):
            if k:
                level = _mean_level(level)
            np.testing.assert_array_equal(page.asarray(), level, err_msg=f"level {k}")
            assert (page.tilewidth, page.tilelength, page.predictor) == (512, 512, 2)
            offsets, counts = page.dataoffsets, page.databytecounts
            assert list(offsets) == sorted(offsets) and offsets[0] > last_ifd
            first_tile.append(offsets[0])
            for off, n in zip(offsets, counts, strict=True):
                assert int.from_bytes(raw[off - 4 : off], "little") == n
                assert raw[off + n - 4 : off + n] == raw[off + n : off + n + 4]
        assert first_tile == sorted(first_tile, reverse=True)  # smallest level first


def test_gdal_cog_validator(tmp_path):
    """GDAL's own validate_cloud_optimized_geotiff.py, full check (leaders and trailers), if
    a Python with GDAL's bindings is on this machine."""
    import shutil
    import subprocess

    script = None
    for python in ("/usr/bin/python3", shutil.which("python3")):
        if not python:
            continue
        found = subprocess.run(
            [
                python,
                "-c",
                "import osgeo_utils.samples.validate_cloud_optimized_geotiff as v; "
                "print(v.__file__)",
            ],
            capture_output=True,
            text=True,
        )
        if found.returncode == 0:
            script = (python, found.stdout.strip())
            break
    if script is None:
        pytest.skip("no Python with GDAL's bindings (osgeo_utils) on this machine")
    out = write_cog(_map_like(1300, 1700), tmp_path / "v.tif", transform=TRANSFORM, crs=CRS)
    run = subprocess.run([*script, "--full-check=yes", str(out)], capture_output=True, text=True)
    assert run.returncode == 0 and "is a valid cloud optimized GeoTIFF" in run.stdout, (
        run.stdout + run.stderr
    )


def test_bigtiff_when_classic_offsets_cannot_reach(tmp_path, monkeypatch):
    from sciviz_gbuf.writers import _cog_layout

    image = _map_like(900, 1100)
    monkeypatch.setattr(_cog_layout, "CLASSIC_LIMIT", 1000)
    out = write_cog(image, tmp_path / "big.tif", transform=TRANSFORM, crs=CRS)
    assert out.read_bytes()[:4] == b"II+\x00"
    _assert_cog(out, image)


def test_one_tile_and_one_pixel(tmp_path):
    for shape in [(512, 512, 4), (1, 1, 3), (1, 600, 1)]:
        image = _map_like(*shape[:2])[..., : shape[2]]
        written = image[..., 0] if shape[2] == 1 else image
        out = write_cog(written, tmp_path / f"s{shape[0]}x{shape[1]}.tif", transform=TRANSFORM)
        check_cog(out)
        np.testing.assert_array_equal(_read(out), image)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 23), st.integers(1, 23), st.sampled_from([1, 3, 4]), st.integers(0, 2**31),
    st.floats(0.0, 1.0),
)  # fmt: skip
def test_overview_kernel_equals_the_numpy_statement(h, w, c, seed, clear):
    """The kernel that halves a level (odd edges, transparent pixels, any band count) writes
    the bytes of the numpy statement it replaced."""
    from sciviz_gbuf.writers import _cog_layout

    rng = np.random.default_rng(seed)
    a = rng.integers(0, 256, (h, w, c), dtype=np.uint8)
    if c == 4:
        a[..., 3][rng.random((h, w)) < clear] = 0
    np.testing.assert_array_equal(_cog_layout.halve(a), _cog_layout.halve_reference(a))


def test_uint8_image_is_not_copied_or_changed(tmp_path):
    """A uint8 map is read as it is (no copy of the whole image) and left unchanged."""
    rng = np.random.default_rng(2)
    img = rng.integers(0, 256, (600, 700, 4), dtype=np.uint8)
    before = img.copy()
    write_cog(img, tmp_path / "m.tif", transform=(400000.0, 10.0, 0.0, 4.5e6, 0.0, -10.0),
              crs="EPSG:32613")  # fmt: skip
    np.testing.assert_array_equal(img, before)
