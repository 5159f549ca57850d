"""Topographic and bird's-eye maps: nodata handling, georeference, CLI, G-buffer reuse."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.cli import main
from sciviz_gbuf.compose import write_geotiff
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes import birdseye_gbuffer, birdseye_layers, nice_intervals

rasterio = pytest.importorskip("rasterio")

FIXED = {"interval": 5.0, "major_interval": 25.0, "vmin": 0.0, "vmax": 200.0}


def plane_dem(shape=(80, 90), east=0.4, north=-0.25, spacing=10.0):
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float32)
    z = 100.0 + east * cols * spacing + north * (-rows * spacing)
    return z.astype(np.float32)


def blob_hole(shape, seed=3):
    """An irregular nodata region touching nothing but itself (a random blob)."""
    rng = np.random.default_rng(seed)
    noise = ndimage.gaussian_filter(rng.standard_normal(shape), 6)
    return noise > np.quantile(noise, 0.7)


# ------------------------------------------------------------------------- plan-view map


@pytest.mark.parametrize("generalize", [False, True])
def test_nodata_hole_changes_nothing_outside_itself(generalize):
    """A plane with an irregular hole: every valid pixel is as without the hole (relief,
    bands and contours), so the hole leaves no line, edge or terrace at its border. With
    generalisation, line stubs the hole cuts to at most one line width (2 px) go as specks
    do: changes stay within 3 px of the hole."""
    z = plane_dem()
    hole = blob_hole(z.shape)
    holed = z.copy()
    holed[hole] = np.nan
    full = sg.topographic_map(read_dem(z, spacing=10.0), generalize=generalize, **FIXED)
    cut = sg.topographic_map(read_dem(holed, spacing=10.0), generalize=generalize, **FIXED)
    assert (cut[hole] == 0).all()  # transparent black
    assert (cut[~hole, 3] == 255).all()
    far = ~hole
    if generalize:
        far = ~ndimage.binary_dilation(hole, np.ones((3, 3), bool), iterations=3)
    diff = np.abs(full[far].astype(int) - cut[far].astype(int))
    assert diff.max() <= 1, diff.max()
    # and the plane did get contour lines (the test is not vacuous)
    no_lines = sg.topographic_map(read_dem(z, spacing=10.0), contours=False, **FIXED)
    assert (np.abs(full.astype(int) - no_lines.astype(int)).max(axis=-1) > 40).mean() > 0.05


def test_plane_without_levels_is_one_colour_up_to_the_hole():
    """Between two levels a plane is a single band, a single relief shade and no ink."""
    z = plane_dem(east=0.001, north=0.0005) + 1.0  # 101.0 .. 101.9: between two levels
    z[blob_hole(z.shape)] = np.nan
    # z = 1: the automatic factor of this 0.06 degree plane (20) would lift the float32
    # rounding of its heights to a grey level
    m = sg.topographic_map(read_dem(z, spacing=10.0), **FIXED, z_factor=1.0)
    valid = m[..., 3] == 255
    colours = np.unique(m[valid], axis=0)
    assert len(colours) == 1, colours


def test_hugo_nodata_transparent(shared_data):
    dem = read_dem(shared_data / "dem" / "hugo_site.asc")
    m = sg.topographic_map(dem)
    assert m.shape == (*dem.shape, 4)
    np.testing.assert_array_equal(m[..., 3] == 0, ~dem.mask)
    assert (m[~dem.mask] == 0).all()


def test_srtm_flat_sea_has_no_noise(shared_data):
    """N10W110: the open sea (exactly 0 m) is one colour; lines only near the atoll."""
    from scipy import ndimage

    dem = read_dem(shared_data / "dem" / "N10W110.hgt")
    m = sg.topographic_map(dem, interval=1.0, major_interval=5.0, sea_level=0.5)
    land = dem.heights != 0
    far = ~ndimage.binary_dilation(land, iterations=4)
    assert far.mean() > 0.9
    assert len(np.unique(m[far], axis=0)) == 1
    assert not (m[land] == m[far][0]).all(axis=-1).all()  # the atoll is drawn


def test_relief_agrees_with_hillshade_on_interior():
    """On open terrain without bands and contours the map is grey relief: monotone in GDAL's
    hillshade (the same shade drives both)."""
    rng = np.random.default_rng(0)
    from scipy import ndimage

    z = ndimage.gaussian_filter(rng.standard_normal((64, 64)), 4).astype(np.float32) * 400
    dem = read_dem(z, spacing=10.0)
    m = sg.topographic_map(dem, contours=False, bands=False)
    sh = sg.filters.hillshade(z, dx=10.0, dy=10.0)
    grey = m[..., 0].astype(float)
    order = np.argsort(sh.ravel())
    assert np.all(np.diff(grey.ravel()[order]) >= -1)
    flat = math.sin(math.radians(45))
    # darker than flat ground -> darker than paper; flat -> paper white
    assert grey.ravel()[sh.ravel() < 0.5 * flat].max() < 255 * 0.85


@pytest.mark.parametrize(
    ("lo", "hi", "expected"),
    [
        (250.0, 1150.0, (20.0, 100.0)),
        (0.0, 9.0, (0.2, 1.0)),
        (0.0, 3.0, (0.1, 0.5)),
        (1660.0, 1711.0, (1.0, 5.0)),
    ],
)
def test_nice_intervals(lo, hi, expected):
    assert nice_intervals(lo, hi) == pytest.approx(expected)


@given(st.floats(-1e4, 1e4), st.floats(1e-3, 1e5))
@settings(max_examples=60, deadline=None)
def test_nice_intervals_are_round(lo, span):
    minor, major = nice_intervals(lo, lo + span)
    mant = major / 10 ** math.floor(math.log10(major))
    assert any(math.isclose(mant, m, rel_tol=1e-9) for m in (1, 2, 2.5, 5, 10))
    assert 8 / math.sqrt(2) - 1e-9 <= span / major <= 8 * math.sqrt(2) + 1e-9
    assert minor == pytest.approx(major / 5)


def test_bad_parameters():
    z = plane_dem()
    for bad in ("rainbow", [1, "x"], [], [0, np.inf], object()):
        with pytest.raises(InputError, match="bands"):
            sg.topographic_map(z, bands=bad)
    with pytest.raises(InputError, match="cmap"):
        sg.topographic_map(z, cmap="no-such-map")
    with pytest.raises(InputError, match="contour_color"):
        sg.topographic_map(z, contour_color=(2, 0, 0))
    with pytest.raises(InputError, match="interval"):
        sg.topographic_map(z, interval=-1.0)


def test_input_not_modified():
    z = plane_dem()
    z[5:9, 5:9] = np.nan
    before = z.copy()
    sg.topographic_map(z)
    np.testing.assert_array_equal(z, before)


# ------------------------------------------------------------------------- GeoTIFF


def test_geotiff_keeps_crs_and_transform(tmp_path):
    """A projected GeoTIFF DEM in, the map's GeoTIFF out with the same CRS and transform."""
    from rasterio.transform import from_origin

    z = plane_dem((50, 70))
    z[:4, :6] = -9999
    src = tmp_path / "dem.tif"
    transform = from_origin(500000.0, 4200000.0, 10.0, 10.0)
    with rasterio.open(
        src, "w", driver="GTiff", width=70, height=50, count=1, dtype="float32",
        crs="EPSG:32617", transform=transform, nodata=-9999,
    ) as f:  # fmt: skip
        f.write(z, 1)
    out = tmp_path / "map.tif"
    argv = ["topo", str(src), "-o", str(tmp_path / "map.png"), "--geotiff", str(out)]
    assert main([*argv, "--no-progress"]) == 0
    with rasterio.open(out) as f, rasterio.open(src) as g:
        assert f.crs == g.crs
        assert f.transform == g.transform
        assert f.count == 4 and f.colorinterp[3].name == "alpha"
        rgba = np.moveaxis(f.read(), 0, 2)
    png = np.asarray(Image.open(tmp_path / "map.png"))
    np.testing.assert_array_equal(rgba, png)
    assert (rgba[:4, :6, 3] == 0).all() and (rgba[10:, 10:, 3] == 255).all()


def test_geotiff_of_geographic_hgt(tmp_path, shared_data):
    dem = read_dem(shared_data / "dem" / "N10W110.hgt")
    m = sg.topographic_map(dem)
    out = write_geotiff(tmp_path / "n10.tif", m, dem=dem)
    with rasterio.open(out) as f:
        assert f.crs.to_epsg() == 4326
        np.testing.assert_allclose(f.transform.to_gdal(), dem.transform, rtol=0, atol=1e-12)


def test_write_geotiff_errors(tmp_path):
    img = np.zeros((8, 8, 4), np.uint8)
    with pytest.raises(InputError, match="georeference"):
        write_geotiff(tmp_path / "a.tif", img)
    with pytest.raises(InputError, match=r"\.tif"):
        write_geotiff(tmp_path / "a.png", img, transform=(0, 1, 0, 0, 0, -1))
    with pytest.raises(InputError, match="crs"):
        write_geotiff(tmp_path / "a.tif", img, transform=(0, 1, 0, 0, 0, -1), crs="EPSG:-5")
    with pytest.raises(InputError, match="directory"):
        write_geotiff(tmp_path / "no" / "a.tif", img, transform=(0, 1, 0, 0, 0, -1))


# ------------------------------------------------------------------------- CLI


def test_cli_topo_bundled_default(tmp_path, capsys):
    out = tmp_path / "t.png"
    assert main(["topo", "-o", str(out), "--contours", "20,100", "--no-progress"]) == 0
    img = np.asarray(Image.open(out))
    assert img.shape == (344, 403, 4)
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--contours", "20,x"], "MINOR,MAJOR"),
        (["--contours", "100,20"], "MINOR <= MAJOR"),
        (["--bands", "-3"], "interval > 0"),
        (["--altitude", "0"], "degrees"),
    ],
)
def test_cli_topo_bad_arguments(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as exc:
        main(["topo", "-o", str(tmp_path / "t.png"), *argv])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_cli_topo_bad_file(tmp_path, capsys):
    bad = tmp_path / "bad.asc"
    bad.write_text("ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n")
    assert main(["topo", str(bad), "-o", str(tmp_path / "t.png")]) == 2
    err = capsys.readouterr().err
    assert "bad.asc" in err and "error" in err
    assert not (tmp_path / "t.png").exists()


# ------------------------------------------------------------------------- bird's-eye


@pytest.fixture(scope="module")
def ramp_gbuffer():
    """A plane falling 0.5 m per metre eastwards (facing the eye), seen from the south-east."""
    z = plane_dem((120, 120), east=-0.5, north=0.0, spacing=1.0)
    return birdseye_gbuffer(read_dem(z, spacing=1.0), window_size=(320, 240))


def test_birdseye_contours_sit_on_their_levels(ramp_gbuffer):
    """Ink in the bird's-eye contour image lies where the captured height is near a level."""
    lay = birdseye_layers(ramp_gbuffer, interval=10.0, major_interval=50.0)
    cn, wz = lay["cn"], lay["wz"]
    inked = (cn > 0.9) & np.isfinite(wz)
    assert inked.sum() > 200
    off = np.abs(wz[inked] - 10.0 * np.round(wz[inked] / 10.0))
    # the ramp climbs well under 1 m per output pixel here; a 2 px major line spans < 2 m
    assert np.quantile(off, 0.99) < 2.0
    blank = (cn == 0) & np.isfinite(wz)
    off_blank = np.abs(wz[blank] - 10.0 * np.round(wz[blank] / 10.0))
    assert np.median(off_blank) > 2.0


def test_birdseye_map_reuses_gbuffer(ramp_gbuffer):
    """The G-buffer passed back in gives the map without rendering, identically."""
    a = sg.birdseye_map(ramp_gbuffer, interval=10.0, major_interval=50.0)
    b = sg.birdseye_map(ramp_gbuffer, interval=10.0, major_interval=50.0)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (240, 320, 4)
    assert a[0, 0, 3] == 0 and a[120, 160, 3] == 255  # sky transparent, ground opaque
    c = sg.birdseye_map(ramp_gbuffer, interval=5.0, major_interval=25.0)
    assert (a != c).any()


def test_birdseye_nodata_is_transparent(shared_data):
    dem = read_dem(shared_data / "dem" / "hugo_site.asc")
    gb = birdseye_gbuffer(dem, window_size=(320, 240), vert_exag=2.0)
    assert not np.isnan(gb.scalars["elevation"][gb.mask]).any()
    m = sg.birdseye_map(gb)
    lay = birdseye_layers(gb)
    np.testing.assert_array_equal(m[..., 3] == 0, lay["alpha"] == 0)
    # the framing follows the valid data: it fills a fair part of the image
    assert (m[..., 3] > 0).mean() > 0.2


def test_birdseye_wrong_gbuffer(ramp_gbuffer):
    gb = sg.capture(sg.datasets.load_nut(), window_size=(64, 48))
    with pytest.raises(InputError, match="elevation"):
        sg.birdseye_map(gb)


def test_cli_birdseye_and_sumi_e(tmp_path, shared_data):
    src = shared_data / "dem" / "pre_runout_DEM.asc"
    for style in ("mx4", "sumi-e"):
        out = tmp_path / f"{style}.png"
        args = ["birdseye", str(src), "-o", str(out), "--size", "200x150", "--style", style]
        assert main([*args, "--elevation-angle", "30", "--no-progress"]) == 0
        img = np.asarray(Image.open(out))
        assert img.shape == (150, 200, 4)
        assert img[..., 3].max() == 255
    with pytest.raises(SystemExit):
        main(["birdseye", str(src), "-o", str(tmp_path / "x.png"), "--elevation-angle", "95"])


def test_large_png_encoder_round_trip(tmp_path):
    import zlib

    from sciviz_gbuf.writers._png_encoder import _adler32_combine, encode_png, write_png_fast

    a, b = b"sciviz" * 9999, bytes(range(256)) * 77
    assert _adler32_combine(zlib.adler32(a), zlib.adler32(b), len(b)) == zlib.adler32(a + b)

    rng = np.random.default_rng(1)
    for shape in [(700, 33, 4), (513, 300, 3), (300, 257)]:
        a = rng.integers(0, 256, shape, dtype=np.uint8)
        a[::7] = a[0]  # some repeated rows
        back = np.asarray(Image.open(io.BytesIO(encode_png(a))))
        np.testing.assert_array_equal(back, a)
        path = write_png_fast(tmp_path / "a.png", a)
        np.testing.assert_array_equal(np.asarray(Image.open(path)), a)


def test_auto_intervals_follow_the_slope():
    """Majors at least 6 px apart on the median slope: a steep small grid gets few lines."""
    from sciviz_gbuf.recipes.terrain import typical_slope

    z = plane_dem((60, 80), east=0.3, north=0.4, spacing=10.0)  # 5 m per pixel
    assert typical_slope(z) == pytest.approx(5.0, rel=1e-5)
    lo, hi = float(z.min()), float(z.max())
    assert nice_intervals(lo, hi) == (10.0, 50.0)  # by the range alone: lines 10 px apart
    assert nice_intervals(lo, hi, slope=typical_slope(z)) == (10.0, 50.0)
    # 20 m per pixel: 6 px is 120 m, rounded up to 200
    assert nice_intervals(lo, hi, slope=20.0) == (40.0, 200.0)
    m = sg.topographic_map(read_dem(z * 4, spacing=10.0), bands=False, relief=False)
    inked = (m[..., :3] < 200).any(axis=-1).mean()
    assert 0.02 < inked < 0.5  # lines, not solid ink


@given(
    st.integers(1, 12),
    st.integers(1, 12),
    st.floats(-1e4, 1e4),
    st.floats(1e-3, 1e3),
    st.integers(0, 2**32 - 1),
)
@settings(max_examples=40, deadline=None)
def test_odd_grids_give_a_map(h, w, offset, scale, seed):
    """Tiny, flat, noisy grids with NaN and inf: always an (H, W, 4) map, transparent exactly
    at the non-finite cells, never an exception from deep inside."""
    rng = np.random.default_rng(seed)
    z = (offset + scale * rng.standard_normal((h, w))).astype(np.float32)
    z[rng.random((h, w)) < 0.2] = np.nan
    z[rng.random((h, w)) < 0.05] = np.inf
    if not np.isfinite(z).any():  # nothing to map: refused, not a blank picture
        with pytest.raises(sg.InputError, match="every cell is nodata"):
            sg.topographic_map(read_dem(z, spacing=5.0), shadows=True)
        return
    m = sg.topographic_map(read_dem(z, spacing=5.0), shadows=True)
    assert m.shape == (h, w, 4) and m.dtype == np.uint8
    np.testing.assert_array_equal(m[..., 3] == 0, ~np.isfinite(z))


# ------------------------------------------------------------- contour generalisation


SHARED_DEMS = ["SRTMGL3_40.09_-105.55_40.21_-105.35.asc", "hugo_site.asc",
               "pre_runout_DEM.asc", "N10W110.hgt"]  # fmt: skip


def isolated_per_1000(
    rgba: np.ndarray, largest: int = 6, luminance: float | None = None
) -> tuple[float, int]:
    """(isolated components of at most ``largest`` px per 1000 ink px, ink px) of a map drawn
    with ``bands=False, relief=False``: ink is any pixel the contour colour darkened
    (8-connected components of the ink layer, every visible mark counted), or with
    ``luminance`` the pixels darker than that (0-1): the ink one sees at that threshold."""
    ink = (rgba[..., 3] > 0) & (rgba[..., :3] < 255).any(axis=-1)
    if luminance is not None:
        lum = rgba[..., :3].astype(np.float64) / 255.0 @ np.array([0.2126, 0.7152, 0.0722])
        ink &= lum < luminance
    labels, _ = ndimage.label(ink, np.ones((3, 3), bool))
    sizes = np.bincount(labels.ravel())[1:]
    return 1000.0 * np.count_nonzero(sizes <= largest) / max(int(ink.sum()), 1), int(ink.sum())


def _variants(shared_data, name: str):
    """The shared DEM, rounded to whole metres, and with 0.3 m of noise."""
    import dataclasses
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the SRTM .asc has no CRS
        d = read_dem(shared_data / "dem" / name)
    noise = np.random.default_rng(1).normal(0.0, 0.3, d.heights.shape)
    return {
        "as is": d,
        "integer metres": dataclasses.replace(d, heights=np.round(d.heights)),
        "noise 0.3 m": dataclasses.replace(d, heights=(d.heights + noise).astype(np.float32)),
    }


@pytest.mark.parametrize("name", SHARED_DEMS)
def test_default_maps_of_shared_dems_have_no_specks(shared_data, name):
    """Generalised contours (the default): <= 2 isolated <= 6 px ink components per 1000 ink
    px, also when the DEM is rounded to whole metres or 0.3 m of noise is added; the exact
    lines (``generalize=False``) of the same maps have many (the measure can fail)."""
    variants = _variants(shared_data, name)
    if name == "N10W110.hgt":  # 1201^2 and almost all sea: the heights as they are suffice
        variants = {"as is": variants["as is"]}
    for label, d in variants.items():
        specks, ink = isolated_per_1000(sg.topographic_map(d, bands=False, relief=False))
        assert ink > 200, (label, ink)
        assert specks <= 2.0, (label, specks)
    if name != "N10W110.hgt":
        exact, _ = isolated_per_1000(
            sg.topographic_map(variants["noise 0.3 m"], bands=False, relief=False,
                               generalize=False)
        )  # fmt: skip
        assert exact > 8.0, exact


@pytest.mark.parametrize("name", SHARED_DEMS)
def test_fading_minors_leave_no_dashes_at_visible_thresholds(shared_data, name):
    """Minor lines fade where they crowd (Eq. 15): at any visible threshold (luminance < 0.7,
    0.85, 0.95) the default maps still have <= 2 isolated <= 6 px components per 1000 ink px
    (the fading pieces are faint along their length, not broken into dark dashes); the exact
    lines of the same maps have many at luminance < 0.85 (the measure can fail)."""
    d = _variants(shared_data, name)["as is"]
    rgba = sg.topographic_map(d, bands=False, relief=False)
    for threshold in (0.7, 0.85, 0.95):
        specks, ink = isolated_per_1000(rgba, luminance=threshold)
        assert ink > 200, (threshold, ink)
        assert specks <= 2.0, (threshold, specks)
    if name != "N10W110.hgt":
        exact = sg.topographic_map(d, bands=False, relief=False, generalize=False)
        assert isolated_per_1000(exact, luminance=0.85)[0] > 4.0


def test_generalisation_keeps_summits_and_drops_small_rings():
    """Two cones (0.5 m/px): the 20 m ring of the 24 m summit stays; the 10 m ring on top of
    the 10.5 m summit (1 px radius) is drawn exactly but generalised away; their lower rings
    stay."""
    y, x = np.mgrid[0:80, 0:120].astype(np.float32)
    r_big, r_small = np.hypot(x - 30, y - 40), np.hypot(x - 90, y - 40)
    z = np.maximum(0.0, 24.0 - 0.5 * r_big) + np.maximum(0.0, 10.5 - 0.5 * r_small)
    ink = sg.filters.contour_lines(z, interval=5.0, width=1.0, generalize=True)
    exact = sg.filters.contour_lines(z, interval=5.0, width=1.0)
    assert exact[r_small < 2.5].max() > 0.5  # the exact lines draw the small top ring ...
    assert ink[r_small < 3.5].max() == 0.0  # ... generalised, it is gone
    for r, radius in ((r_big, 38.0), (r_small, 11.0)):  # the 5 m rings stay where they were
        assert ink[np.abs(r - radius) <= 1.0].mean() > 0.4
    top = (r_big > 4.0) & (r_big < 9.0)  # the 20 m ring (radius 8 px) of the tall summit
    assert ink[top].max() > 0.5


def colour_islands(rgba: np.ndarray, largest: int = 6) -> int:
    """8-connected pieces of one colour of a bands-only map whose bounding box is at most
    ``largest`` px and which touch neither the picture's edge nor a transparent cell."""
    rgb = rgba[..., :3].astype(np.int64)
    key = np.where(rgba[..., 3] > 0, rgb[..., 0] * 65536 + rgb[..., 1] * 256 + rgb[..., 2], -1)
    cut = ndimage.binary_dilation(key < 0, np.ones((3, 3), bool))
    cut[0, :] = cut[-1, :] = cut[:, 0] = cut[:, -1] = True
    count = 0
    for v in np.unique(key[key >= 0]):
        labels, _ = ndimage.label(key == v, np.ones((3, 3), bool))
        touching = set(np.unique(labels[cut]).tolist())
        for k, box in enumerate(ndimage.find_objects(labels), 1):
            extent = max(box[0].stop - box[0].start, box[1].stop - box[1].start)
            count += extent <= largest and k not in touching
    return count


@pytest.mark.parametrize("name", [*SHARED_DEMS[:3], "jacksboro"])
def test_generalised_maps_leave_no_islands_of_band_colour(shared_data, name):
    """The bands of a generalised map follow its generalised lines: no speck of a band's
    colour (an island of at most 6 px, the rings the lines drop) is left, also on whole-metre
    heights; the bands of the exact heights have such islands (the measure can fail)."""
    if name == "jacksboro":
        from sciviz_gbuf.datasets import load_jacksboro_dem

        variants = {"as is": load_jacksboro_dem()}
    else:
        variants = _variants(shared_data, name)
        variants.pop("noise 0.3 m")
    exact_total = 0
    for label, d in variants.items():
        gen = sg.topographic_map(d, contours=False, relief=False)
        assert colour_islands(gen) == 0, (label, colour_islands(gen))
        exact_total += colour_islands(
            sg.topographic_map(d, contours=False, relief=False, generalize=False)
        )
    if name in ("jacksboro", SHARED_DEMS[0]):  # (hugo_site and pre_runout have no islands)
        assert exact_total > 0


def test_birdseye_bands_leave_no_islands_where_lines_dropped_rings():
    """The bird's-eye bands follow the generalised lines like the plan-view map's."""
    from sciviz_gbuf.datasets import load_jacksboro_dem

    gb = birdseye_gbuffer(load_jacksboro_dem(), size=480, supersample=1)

    def islands(generalize: bool) -> int:
        lay = birdseye_layers(gb, contours=False, generalize=generalize)
        rgba = np.dstack([np.round(lay["bands"] * 255), np.where(lay["alpha"] >= 1.0, 255, 0)])
        return colour_islands(rgba.astype(np.uint8))

    assert islands(True) == 0
    assert islands(False) > 10
