"""Web map tiles: the tile scheme against known tile bounds, heights resampled onto Web
Mercator against analytic planes, a pyramid's tiles against the whole map of each level (no
seams), the viewer in a real browser, bad input."""

from __future__ import annotations

import io
import math
import shutil
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from sciviz_gbuf import _validate
from sciviz_gbuf.datasets import load_jacksboro_dem
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import DEM, read_dem
from sciviz_gbuf.recipes import mercator_dem, topographic_map, write_map_tiles
from sciviz_gbuf.recipes.tiles import (
    EARTH_RADIUS,
    lonlat_to_tile,
    native_zoom,
    tile_bounds,
    tile_lonlat_bounds,
    tile_range,
)
from tests.helpers.cli import assert_clean_failure, run_cli

rasterio = pytest.importorskip("rasterio")

# ------------------------------------------------------------------------ the tile scheme


def test_tile_bounds_match_mercantile():
    """mercantile's documented tile 10/486/332 (its README and test suite)."""
    west, south, east, north = tile_lonlat_bounds(10, 486, 332)
    expected = (-9.140625, 53.12040528310657, -8.7890625, 53.33087298301705)
    np.testing.assert_allclose((west, south, east, north), expected, rtol=0, atol=1e-9)
    x0, _, _, y1 = tile_bounds(10, 486, 332)  # its upper-left corner in EPSG:3857 metres
    np.testing.assert_allclose((x0, y1), (-1017529.7205322663, 7044436.526761846), atol=1e-6)
    half = math.pi * EARTH_RADIUS
    np.testing.assert_allclose(tile_bounds(0, 0, 0), (-half, -half, half, half))
    np.testing.assert_allclose(tile_lonlat_bounds(0, 0, 0), (-180, -85.0511287798, 180,
                                                            85.0511287798), atol=1e-9)  # fmt: skip


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 22), st.data())
def test_a_tile_holds_its_own_points(z, data):
    x = data.draw(st.integers(0, 2**z - 1))
    y = data.draw(st.integers(0, 2**z - 1))
    west, south, east, north = tile_lonlat_bounds(z, x, y)
    assert west < east and south < north
    u, v = data.draw(st.floats(0.05, 0.95)), data.draw(st.floats(0.05, 0.95))
    lon = west + u * (east - west)
    lat = south + v * (north - south)
    assert lonlat_to_tile(lon, lat, z) == (x, y)
    # the tiles covering a tile's own bounds are that tile alone
    assert tile_range((west, south, east, north), z) == (x, x, y, y)


def test_tile_range_of_a_region():
    x0, x1, y0, y1 = tile_range((-105.55, 40.09, -105.35, 40.21), 12)
    for x, y in ((x0, y0), (x1, y1)):
        w, s, e, n = tile_lonlat_bounds(12, x, y)
        assert w < e and s < n
    assert tile_lonlat_bounds(12, x0, y0)[0] <= -105.55 < tile_lonlat_bounds(12, x0, y0)[2]
    assert tile_lonlat_bounds(12, x1, y1)[1] <= 40.09 < tile_lonlat_bounds(12, x1, y1)[3]


# -------------------------------------------------------------------- heights on Web Mercator


def _geotiff(path: Path, z: np.ndarray, crs: str, west: float, north: float, cell: float):
    from rasterio.transform import from_origin

    with rasterio.open(
        path, "w", driver="GTiff", width=z.shape[1], height=z.shape[0], count=1,
        dtype="float32", crs=crs, transform=from_origin(west, north, cell, cell), nodata=-9999,
    ) as f:  # fmt: skip
        f.write(np.where(np.isnan(z), -9999, z).astype(np.float32), 1)
    return path


def _pixel_lonlat(zd: DEM) -> tuple[np.ndarray, np.ndarray]:
    west, res, _, north, _, _ = zd.transform
    h, w = zd.shape
    xs = west + (np.arange(w) + 0.5) * res
    ys = north - (np.arange(h) + 0.5) * res
    lon = np.degrees(xs / EARTH_RADIUS)[None, :].repeat(h, 0)
    lat = np.degrees(np.arctan(np.sinh(ys / EARTH_RADIUS)))[:, None].repeat(w, 1)
    return lon, lat


def test_heights_of_a_plane_in_utm(tmp_path):
    """A plane in UTM metres, resampled onto Web Mercator: each pixel's height is the plane at
    the pixel centre's own easting/northing (bilinear is exact on a plane); outside the grid,
    nodata; at a low zoom (block means first) still the plane."""
    from rasterio.warp import transform

    west, north, cell = 440000.0, 4440000.0, 30.0
    rows, cols = np.mgrid[0:200, 0:300]
    e = west + (cols + 0.5) * cell
    n = north - (rows + 0.5) * cell
    plane = (2000.0 + 0.01 * (e - west) - 0.02 * (north - n)).astype(np.float32)
    d = read_dem(_geotiff(tmp_path / "utm.tif", plane, "EPSG:32613", west, north, cell))
    for zoom in (native_zoom(d), native_zoom(d) - 3):
        zd = mercator_dem(d, zoom)
        assert zd.crs == "EPSG:3857" and zd.heights.chunksize[0] % 256 == 0
        got = np.asarray(zd.heights.compute())
        lon, lat = _pixel_lonlat(zd)
        ex, ny = transform("EPSG:4326", "EPSG:32613", lon.ravel(), lat.ravel())
        ex, ny = np.reshape(ex, lon.shape), np.reshape(ny, lon.shape)
        expected = 2000.0 + 0.01 * (ex - west) - 0.02 * (north - ny)
        # away from the edges by a pixel and a block of cells (where a pixel spans f >= 2
        # cells, the last f - 1 cells take the nearest whole block's height)
        m = 2.0 * zd.pixel_size[0] + cell
        inside = (ex > west + m) & (ex < west + 300 * cell - m)
        inside &= (ny < north - m) & (ny > north - 200 * cell + m)
        assert inside.sum() > 100
        # float32 at 2 km (2e-3), and the source positions bilinear between exact ones every
        # CONTROL px: within 1/500 px (the plane's gradient is 0.0224 m/m)
        tol = 2e-3 + 0.0224 * zd.pixel_size[0] / 500.0
        np.testing.assert_allclose(got[inside], expected[inside], atol=tol)
        outside = (ex < west - 1) | (ex > west + 300 * cell + 1)
        outside |= (ny > north + 1) | (ny < north - 200 * cell - 1)
        assert np.isnan(got[outside]).all() and outside.any()


def test_heights_of_a_geographic_grid_follow_latitude_not_y():
    """A grid in degrees (no CRS: WGS 84) whose heights are its latitude: on Web Mercator the
    heights are the latitude of each pixel centre (rows are not evenly spaced in latitude)."""
    cy, cx = 0.2 / 240, 0.0005
    lat = (40.2 - np.arange(241) * cy)[:, None].repeat(361, 1)
    d = DEM(heights=(lat * 100.0).astype(np.float32), mask=np.ones(lat.shape, bool), crs=None,
            transform=(-105.5 - cx / 2, cx, 0.0, 40.2 + cy / 2, 0.0, -cy),
            pixel_size=(42.6, 92.6), geographic=True)  # fmt: skip
    zd = mercator_dem(d, 12)
    got = np.asarray(zd.heights.compute())
    plon, plat = _pixel_lonlat(zd)
    ok = np.isfinite(got)
    ok &= (plat < 40.2 - cy) & (plat > 40.0 + cy)  # not within a cell of the edge
    assert ok.sum() > 1000
    # float32 heights of ~4000: a few 1e-4
    np.testing.assert_allclose(got[ok], plat[ok] * 100.0, atol=1e-3)
    outside = (plat > 40.2 + cy) | (plat < 40.0 - cy) | (plon < -105.5 - cx) | (plon > -105.32 + cx)
    assert np.isnan(got[outside]).all() and outside.any()


# ------------------------------------------------------------------------ the pyramid


@pytest.fixture(scope="module")
def rough_tif(tmp_path_factory):
    """Rough fractal terrain in UTM with a nodata lake: contours everywhere, lines crossing
    every tile edge."""
    rng = np.random.default_rng(3)
    n = 256
    f = np.hypot(np.fft.fftfreq(n)[:, None], np.fft.rfftfreq(n)[None, :])
    f[0, 0] = 1.0
    spec = (rng.standard_normal(f.shape) + 1j * rng.standard_normal(f.shape)) / f**1.6
    z = np.fft.irfft2(spec, s=(n, n)).astype(np.float32)
    z = (z - z.min()) / np.ptp(z) * 900.0 + 1500.0
    z[40:70, 150:200] = np.nan
    path = tmp_path_factory.mktemp("tiles") / "rough.tif"
    return _geotiff(path, z, "EPSG:32613", 440000.0, 4440000.0, 30.0)


def _tile(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGBA"))


@pytest.mark.parametrize(("tile_size", "fmt"), [(256, "png"), (512, "webp")])
def test_every_tile_is_the_window_of_its_level_map(rough_tif, tmp_path, tile_size, fmt):
    d = read_dem(rough_tif)
    top = native_zoom(d, tile_size)
    out = tmp_path / "pyr"
    pyr = write_map_tiles(d, out, zoom=(top - 2, top), tile_size=tile_size, format=fmt)
    assert pyr.zooms == (top - 2, top) and pyr.count == len(list(out.rglob(f"*.{fmt}")))
    lo, hi = float(np.nanmin(d.heights)), float(np.nanmax(d.heights))
    for zoom in range(top - 2, top + 1):
        zd = mercator_dem(d, zoom, tile_size=tile_size)
        z_mem = np.asarray(zd.heights.compute())
        whole = topographic_map(
            DEM(heights=z_mem, mask=np.isfinite(z_mem), crs=zd.crs, transform=zd.transform,
                pixel_size=zd.pixel_size, geographic=False), vmin=lo, vmax=hi,
        )  # fmt: skip
        west, res, _, north, _, _ = zd.transform
        x0 = round((west + math.pi * EARTH_RADIUS) / res / tile_size)
        y0 = round((math.pi * EARTH_RADIUS - north) / res / tile_size)
        ny, nx = whole.shape[0] // tile_size, whole.shape[1] // tile_size
        seen = 0
        for ty in range(ny):
            for tx in range(nx):
                window = whole[ty * tile_size : (ty + 1) * tile_size,
                               tx * tile_size : (tx + 1) * tile_size]  # fmt: skip
                f = out / str(zoom) / str(x0 + tx) / f"{y0 + ty}.{fmt}"
                if not window[..., 3].any():
                    assert not f.exists()  # no data: no tile
                    continue
                np.testing.assert_array_equal(_tile(f), window)
                seen += 1
                # its place on Earth: the tile's bounds from the scheme are the window's
                b = tile_bounds(zoom, x0 + tx, y0 + ty)
                np.testing.assert_allclose(
                    (b[0], b[3]),
                    (west + tx * tile_size * res, north - ty * tile_size * res),
                    atol=1e-6,
                )
        assert seen == pyr.tiles[zoom] and seen >= 1
    assert seen >= 4  # the last level spans several tiles: their edges are inside the map
    js = (out / "tiles.json").read_text()
    assert '"tilejson": "3.0.0"' in js and f"{{z}}/{{x}}/{{y}}.{fmt}" in js
    assert (out / "index.html").is_file() and (out / "leaflet" / "leaflet.js").is_file()
    assert not list(tmp_path.glob(".*part"))


def test_labels_run_across_tile_edges(tmp_path):
    """The bundled DEM with labels at zoom 11 (768 px, 9 tiles): the tiles are the windows of
    the labelled map of the level, which has labels, some across tile edges."""
    d = load_jacksboro_dem()
    pyr = write_map_tiles(d, tmp_path / "lab", zoom=11, labels=True)
    zd = mercator_dem(d, 11)
    z_mem = np.asarray(zd.heights.compute())
    level = DEM(heights=z_mem, mask=np.isfinite(z_mem), crs=zd.crs, transform=zd.transform,
                pixel_size=zd.pixel_size, geographic=False)  # fmt: skip
    lo, hi = float(np.nanmin(d.heights)), float(np.nanmax(d.heights))
    whole = topographic_map(level, labels=True, vmin=lo, vmax=hi)
    plain = topographic_map(level, vmin=lo, vmax=hi)
    labelled = np.any(whole != plain, axis=2)
    assert labelled.sum() > 500  # text drawn
    west, res, _, north, _, _ = zd.transform
    x0 = round((west + math.pi * EARTH_RADIUS) / res / 256)
    y0 = round((math.pi * EARTH_RADIUS - north) / res / 256)
    across = 0
    for f in (tmp_path / "lab" / "11").rglob("*.png"):
        tx, ty = int(f.parent.name) - x0, int(f.stem) - y0
        window = (slice(ty * 256, (ty + 1) * 256), slice(tx * 256, (tx + 1) * 256))
        np.testing.assert_array_equal(_tile(f), whole[window])
        rim = labelled[window]
        across += int(rim[0].any() or rim[-1].any() or rim[:, 0].any() or rim[:, -1].any())
    assert pyr.count == 9 and across >= 1


def test_bad_input_is_one_error_and_leaves_nothing(rough_tif, tmp_path, monkeypatch):
    d = read_dem(rough_tif)
    with pytest.raises(InputError, match="georeferenced"):
        write_map_tiles(np.zeros((50, 50), np.float32) + 1, tmp_path / "a", zoom=3)
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("mine")
    with pytest.raises(InputError, match="not an empty folder"):
        write_map_tiles(d, tmp_path / "full", zoom=10)
    assert (tmp_path / "full" / "x").read_text() == "mine"
    for bad in ((5, 3), (-1, 2), (3, 25), "x"):
        with pytest.raises(InputError, match="zoom"):
            write_map_tiles(d, tmp_path / "b", zoom=bad)
    with pytest.raises(InputError, match="tile_size"):
        write_map_tiles(d, tmp_path / "b", zoom=10, tile_size=300)
    with pytest.raises(InputError, match="format"):
        write_map_tiles(d, tmp_path / "b", zoom=10, format="jpeg")
    with pytest.raises(InputError, match="size"):
        write_map_tiles(d, tmp_path / "b", zoom=10, size=400)
    monkeypatch.setitem(_validate.LIMITS, "tiles", 10)
    with pytest.raises(InputError, match="LIMITS"):
        write_map_tiles(d, tmp_path / "b", zoom=(10, 16))
    monkeypatch.undo()
    with pytest.raises(InputError, match="interval"):
        write_map_tiles(d, tmp_path / "b", zoom=10, interval=-5.0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["full"]


def test_cli_tiles(rough_tif, tmp_path):
    out = tmp_path / "web"
    r = run_cli(["topo", rough_tif, "--tiles", out, "--zoom", "11-12", "--contours", "10,50"])
    assert r.returncode == 0, r.stderr
    assert "tiles, zoom 11-12" in r.stdout and (out / "index.html").is_file()
    assert len(list((out / "12").rglob("*.png"))) >= 2
    bad = tmp_path / "bad"
    for args, name in ((["--zoom", "12-30"], "--zoom"), (["-o", tmp_path / "m.png"], "-o"),
                       (["--page", "A4"], "--page"), (["--size", "300"], "--size")):  # fmt: skip
        r = run_cli(["topo", rough_tif, "--tiles", bad, *args])
        assert_clean_failure(r, names=name, outputs=[bad])
    r = run_cli(["topo", rough_tif, "--tiles", out])
    assert_clean_failure(r, names="--tiles", outputs=[])
    r = run_cli(["topo", rough_tif, "-o", tmp_path / "m.png", "--zoom", "3"])
    assert_clean_failure(r, names="--zoom", outputs=[tmp_path / "m.png"])


# ------------------------------------------------------------------------ the viewer

_CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
_CHROMEDRIVER = shutil.which("chromedriver")


@pytest.mark.skipif(
    _CHROMIUM is None or _CHROMEDRIVER is None,
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver)",
)
def test_viewer_shows_the_tiles_in_a_real_browser(rough_tif, tmp_path):
    """index.html opened from the file system, no network: Leaflet loads the pyramid's tiles
    and the screenshot shows the map's colours where the tiles are."""
    pytest.importorskip("selenium")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    d = read_dem(rough_tif)
    top = native_zoom(d)
    out = tmp_path / "web"
    write_map_tiles(d, out, zoom=(top - 1, top))
    opts = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              "--force-device-scale-factor=1", "--window-size=900,700",
              "--disable-background-networking"):  # fmt: skip
        opts.add_argument(a)
    opts.binary_location = _CHROMIUM
    driver = webdriver.Chrome(options=opts, service=Service(_CHROMEDRIVER))
    try:
        driver.get((out / "index.html").as_uri())
        loaded = 0
        for _ in range(100):
            loaded = driver.execute_script(
                "return document.querySelectorAll('img.leaflet-tile-loaded').length"
            )
            pending = driver.execute_script(
                "return document.querySelectorAll('img.leaflet-tile:not(.leaflet-tile-loaded)')"
                ".length"
            )
            if loaded and not pending:
                break
            time.sleep(0.1)
        zoom = driver.execute_script("return map.getZoom()")
        srcs = driver.execute_script(
            "return Array.from(document.querySelectorAll('img.leaflet-tile-loaded'))"
            ".map(i => i.getAttribute('src'))"
        )
        shot = np.asarray(Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB"))
    finally:
        driver.quit()
    # fitted to the DEM; beyond the last level (up to 2 zooms) the viewer magnifies its tiles
    assert loaded >= 1 and top - 1 <= zoom <= top + 2
    level = min(zoom, top)
    for s in srcs:  # relative URLs of written tiles of the right level, nothing from the network
        assert not s.startswith("http") and (out / s).is_file() and s.startswith(f"{level}/")
    # the map's band colours (not white, not grey UI) cover a good part of the window
    r, g, b = (shot[..., k].astype(int) for k in range(3))
    coloured = (np.abs(r - g) + np.abs(g - b) > 30).mean()
    assert coloured > 0.05, coloured
