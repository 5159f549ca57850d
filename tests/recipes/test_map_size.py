"""Maps at any size: size=/scale=/dpi= of the terrain recipes, the resampling of the heights
before the map (smooth lines at 4x, area averages when smaller, no nodata bleeding), the
georeference of the output grid and the refusals."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import sciviz_gbuf as sg
from sciviz_gbuf.compose import write_geotiff, write_png
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes import birdseye_gbuffer, map_grid
from sciviz_gbuf.recipes.terrain import CONTOUR_COLOR, resample_heights
from sciviz_gbuf.writers._png_encoder import encode_png

# --------------------------------------------------------------------- lines at 4x: no steps

CELL, SLOPE, CX, CY = 10.0, 0.5, 23.37, 24.61  # m per cell, height per m, apex (cells)
RADII = np.arange(4.0, 22.0, 3.0)  # the levels' circles, in cells (apex excluded)
LINES = {"interval": SLOPE * CELL * 3.0, "bands": False, "relief": False, "dense_spacing": 1.0}


def cone(n: int = 48) -> np.ndarray:
    """A cone: its contours are circles of known radius about an apex off the grid's nodes."""
    r, c = np.mgrid[0:n, 0:n].astype(np.float64)
    return (200.0 - SLOPE * CELL * np.hypot(c - CX, r - CY)).astype(np.float32)


def line_centre_errors(img: np.ndarray, k: float) -> np.ndarray:
    """Ink-weighted mean radius minus the analytic radius, in output pixels, for every level
    and every 4-pixel arc of its circle (the ink centroid across the line)."""
    rgb = img[..., :3].astype(np.float64) / 255.0
    ink = np.clip((1.0 - rgb[..., 0]) / (1.0 - CONTOUR_COLOR[0]), 0.0, 1.0)
    ii, jj = np.mgrid[0 : ink.shape[0], 0 : ink.shape[1]]
    xs, ys = (jj + 0.5) / k - 0.5, (ii + 0.5) / k - 0.5  # pixel centres in cells
    r = np.hypot(xs - CX, ys - CY) * k
    ang = np.arctan2(ys - CY, xs - CX) + np.pi
    errors = []
    for radius in RADII * k:
        near = np.abs(r - radius) < 2.5 + 0.5 * k
        arcs = int(2 * np.pi * radius / 4)
        arc = (ang / (2 * np.pi) * arcs).astype(int) % arcs
        for a in range(arcs):
            m = near & (arc == a)
            w = ink[m]
            if w.sum() > 0.5:
                errors.append(np.sum(w * r[m]) / w.sum() - radius)
    return np.asarray(errors)


def test_lines_at_4x_are_smooth_not_stair_stepped():
    """At 4x the grid, every contour's ink centre lies within 0.5 output px of the analytic
    circle; the same heights blown up cell by cell (what a 1x map enlarged shows) are off by
    more than a pixel, so the measure sees stair steps."""
    z = cone()
    ours = sg.topographic_map(read_dem(z, spacing=CELL), scale=4, **LINES)
    assert ours.shape == (192, 192, 4)
    err = line_centre_errors(ours, 4)
    assert err.size > 300  # every level was found along its whole circle
    assert np.abs(err).max() <= 0.5, np.abs(err).max()
    blocky = np.kron(z, np.ones((4, 4), np.float32))
    # exact lines: the default generalisation would smooth the blocks' steps away
    steps = sg.topographic_map(read_dem(blocky, spacing=CELL / 4), generalize=False, **LINES)
    assert np.abs(line_centre_errors(steps, 4)).max() > 1.0


def test_line_widths_stay_in_output_pixels():
    """Ink across a line (its width) is the same at 1x and 4x: widths are output pixels."""
    d = read_dem(cone(), spacing=CELL)
    widths = []
    for k in (1, 4):
        img = sg.topographic_map(d, scale=k, width=2.0, **LINES)
        ink = (255 - img[..., 0].astype(float)) / (255 * (1 - CONTOUR_COLOR[0]))
        ii, jj = np.mgrid[0 : ink.shape[0], 0 : ink.shape[1]]
        r = np.hypot((jj + 0.5) / k - 0.5 - CX, (ii + 0.5) / k - 0.5 - CY)
        # the circles r = 1, 4, ..., 19 cells lie whole inside r < 20.5: ink / length = width
        length = sum(2 * np.pi * rc * k for rc in np.arange(1.0, 20.0, 3.0))
        widths.append(ink[r < 20.5].sum() / length)
    assert widths == pytest.approx([2.0, 2.0], rel=0.15), widths


# ------------------------------------------------------------------------ resample_heights


def test_downsampling_is_an_area_average():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(40, 60)).astype(np.float32)
    small = resample_heights(z, (10, 15))
    blocks = z.reshape(10, 4, 15, 4).mean(axis=(1, 3))
    np.testing.assert_allclose(small, blocks, atol=1e-5)
    # a fraction of a cell per pixel: still the mean over the pixel's area
    odd = resample_heights(z, (7, 11))
    assert odd.mean() == pytest.approx(z.mean(), abs=1e-5)
    # a checkerboard averages out instead of aliasing into stripes (decimation would)
    board = np.indices((64, 64)).sum(axis=0) % 2 * np.float32(100.0)
    np.testing.assert_allclose(resample_heights(board, (16, 16)), 50.0, atol=1e-4)
    assert np.ptp(resample_heights(board, (13, 13))) < 10.0


def test_downsampling_nodata_counts_only_valid_cells():
    z = np.full((8, 8), 10.0, np.float32)
    z[:4, :2] = np.nan  # block (0, 0) half nodata: still valid, its mean 10
    z[4:, 4:7] = np.nan  # block (1, 1): 3/4 nodata -> nodata
    z[4:, 7] = 30.0
    small = resample_heights(z, (2, 2))
    assert small[0, 0] == pytest.approx(10.0)
    assert np.isnan(small[1, 1])
    assert small[0, 1] == small[1, 0] == pytest.approx(10.0)


def test_upsampling_is_exact_on_a_plane_even_beside_nodata():
    """Cubic convolution reproduces a plane; the two rings filled by extrapolation around a
    hole keep it exact right up to the hole, whose cells keep their square footprint, and the
    grid's border is extrapolated the same way (no flattening or ringing at the edges)."""
    r, c = np.mgrid[0:20, 0:24].astype(np.float32)
    z = 3.0 * c - 2.0 * r + 50.0
    holed = z.copy()
    holed[8:12, 9:14] = np.nan
    up = resample_heights(holed, (80, 96))
    rr, cc = np.mgrid[0:80, 0:96].astype(np.float32)
    u, v = (cc + 0.5) / 4 - 0.5, (rr + 0.5) / 4 - 0.5
    truth = 3.0 * u - 2.0 * v + 50.0  # out to the grid's edges (half a cell past the centres)
    hole = np.zeros((80, 96), bool)
    hole[32:48, 36:56] = True
    assert np.array_equal(np.isnan(up), hole)
    np.testing.assert_allclose(up[~hole], truth[~hole], atol=2e-4)


def test_upsampling_does_not_ring_at_a_cliff():
    z = np.zeros((12, 12), np.float32)
    z[:, 6:] = 100.0
    up = resample_heights(z, (48, 48))
    assert up.min() >= 0.0 and up.max() <= 100.0  # no overshoot: no false contour rings
    assert (np.diff(up, axis=1) >= 0).all()  # monotone across the cliff


# ------------------------------------------------------------------------ grid, georeference


def test_map_grid_halves_the_pixel_and_keeps_the_extent():
    d = read_dem(cone(30)[:20], spacing=(10.0, 5.0))
    g = map_grid(d, scale=2)
    assert g.shape == (40, 60)
    assert g.pixel_size == pytest.approx((5.0, 2.5))
    assert g.bounds == pytest.approx(d.bounds)
    assert g.transform[1] == pytest.approx(d.transform[1] / 2)
    assert g.transform[5] == pytest.approx(d.transform[5] / 2)
    assert map_grid(d) is d and map_grid(d, scale=1) is d and map_grid(d, size=30) is d
    assert map_grid(d, size=90).shape == (60, 90)  # the long side, aspect kept
    assert map_grid(d, size=(45, 0)).shape == (30, 45)
    assert map_grid(d, size=(45, 40)).shape == (40, 45)  # exactly, pixels non-square
    # 1:25000 at 300 dpi: 2.1167 m per pixel in both directions
    m = map_grid(d, scale="1:25000", dpi=300)
    assert m.pixel_size == pytest.approx((25000 * 0.0254 / 300,) * 2, rel=0.02)
    assert m.shape == (round(20 * 5.0 / 2.1167), round(30 * 10.0 / 2.1167))
    assert map_grid(d, scale=25000, dpi=300).shape == m.shape


def test_default_map_is_unchanged():
    d = read_dem(cone(24), spacing=CELL)
    base = sg.topographic_map(d)
    assert np.array_equal(base, sg.topographic_map(d, scale=1.0))
    assert np.array_equal(base, sg.topographic_map(d, size=(24, 24)))


def test_geotiff_of_a_2x_map_has_half_the_pixel_and_the_same_extent(tmp_path):
    rasterio = pytest.importorskip("rasterio")
    d = read_dem(cone(20)[:16], spacing=CELL)
    rgba = sg.topographic_map(d, scale=2)
    assert rgba.shape == (32, 40, 4)
    write_geotiff(tmp_path / "m.tif", rgba, dem=d)
    write_geotiff(tmp_path / "g.tif", rgba, dem=map_grid(d, scale=2))
    with rasterio.open(tmp_path / "m.tif") as src, rasterio.open(tmp_path / "g.tif") as src2:
        assert src.transform.a == pytest.approx(d.transform[1] / 2)
        assert src.transform.e == pytest.approx(d.transform[5] / 2)
        west, east, south, north = d.bounds
        assert tuple(src.bounds) == pytest.approx((west, south, east, north))
        assert src2.transform == src.transform


def test_relief_follows_the_output_pixel():
    """A tilted plane's relief is the same at 1x and 4x: the hillshade sees the output pixel's
    size in metres, not one cell's."""
    r, c = np.mgrid[0:16, 0:16].astype(np.float32)
    d = read_dem(2.0 * c + 1.0 * r, spacing=CELL)
    opts = {"contours": False, "bands": False}
    one = sg.topographic_map(d, **opts)[4:12, 4:12, :3].astype(int)
    four = sg.topographic_map(d, scale=4, **opts)[16:48, 16:48, :3].astype(int)
    assert np.ptp(one) <= 1 and np.ptp(four) <= 1
    assert abs(one.mean() - four.mean()) <= 1


def test_nodata_does_not_bleed_at_4x():
    """A plane with a hole, mapped at 4x: outside the hole every pixel is as without it."""
    r, c = np.mgrid[0:24, 0:28].astype(np.float32)
    z = (100.0 + 4.0 * c - 2.5 * r).astype(np.float32)
    holed = z.copy()
    holed[9:14, 10:17] = np.nan
    # exact lines: the resampling is on trial here (generalised lines may end differently
    # within a few px of a hole: tests/recipes/test_terrain_maps.py holds that to 3 px)
    fixed = {"interval": 5.0, "major_interval": 25.0, "vmin": 0.0, "vmax": 250.0}
    fixed |= {"generalize": False, "z_factor": 1.0}
    full = sg.topographic_map(read_dem(z, spacing=CELL), scale=4, **fixed)
    cut = sg.topographic_map(read_dem(holed, spacing=CELL), scale=4, **fixed)
    hole = np.zeros(full.shape[:2], bool)
    hole[36:56, 40:68] = True
    assert (cut[hole] == 0).all() and (cut[~hole, 3] == 255).all()
    assert np.abs(full[~hole].astype(int) - cut[~hole].astype(int)).max() <= 1


def test_a_smaller_map_averages():
    d = read_dem(cone(48), spacing=CELL)
    small = sg.topographic_map(d, size=24)
    assert small.shape == (24, 24, 4) and (small[..., 3] == 255).all()


# ---------------------------------------------------------------------------------- refusals


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"size": 100, "scale": 2}, "scale: expected size= or scale=, not both"),
        ({"scale": "1:25000"}, "dpi: a map scale '1:25000' needs dpi="),
        ({"dpi": 300}, "dpi: expected together with a map scale"),
        ({"size": 200, "dpi": 300}, "dpi: expected together with a map scale"),
        ({"scale": 25000, "dpi": 1e6}, r"dpi: expected a number in \(0, 9600\]"),
        ({"scale": 2, "dpi": float("nan")}, "dpi: expected"),
        ({"size": 20000}, r"size: expected an integer in \[1, 16384\]"),
        ({"size": (0, 0)}, "size: expected at least one side > 0"),
        ({"size": 1.5}, "size: expected an integer"),
        ({"size": True}, "size: expected an integer"),
        ({"size": (10, 20, 30)}, r"size: expected a long side N or \(width, height\)"),
        ({"scale": 1e6}, r"scale: 1000000.0 gives a map side of .* at most 16384"),
        ({"scale": 1e-6}, "scale: 1e-06 gives a map under one pixel"),
        ({"scale": -2}, "scale: expected a finite number > 0"),
        ({"scale": "2:3"}, "scale: expected pixels per cell"),
        ({"scale": 4, "dpi": 300}, "scale: 4 gives a map side"),  # 1:4 at 300 dpi
        ({"scale": "1:10", "dpi": 9600}, "at most 16384"),
    ],
)
def test_bad_or_conflicting_size_options(options, message):
    d = read_dem(cone(24), spacing=CELL)
    with pytest.raises(InputError, match=message) as info:
        sg.topographic_map(d, **options)
    assert "\n" not in str(info.value)


def test_size_options_are_checked_before_the_dem_is_read(tmp_path):
    with pytest.raises(InputError, match="size"):
        sg.topographic_map(tmp_path / "missing.asc", size=0)


def test_out_of_core_refuses_another_size():
    da = pytest.importorskip("dask.array")
    z = da.from_array(cone(24), chunks=12)
    with pytest.raises(InputError, match="scale: a DEM read in chunks"):
        sg.topographic_map(z, scale=2, interval=5.0, vmin=0.0, vmax=200.0)
    same = sg.topographic_map(z, size=24, interval=5.0, vmin=0.0, vmax=200.0)
    assert same.shape == (24, 24, 4)  # its own grid: fine


# ------------------------------------------------------------------------------- PNG and DPI


def test_png_records_the_dpi(tmp_path):
    img = np.zeros((4, 5, 4), np.uint8)
    write_png(tmp_path / "a.png", img, dpi=300)
    with Image.open(tmp_path / "a.png") as im:
        assert im.info["dpi"] == pytest.approx((300, 300), abs=0.01)
    with Image.open(io.BytesIO(encode_png(img, dpi=300))) as im:  # the large-image encoder
        assert im.info["dpi"] == pytest.approx((300, 300), abs=0.01)
        assert np.array_equal(np.asarray(im), img)
    write_png(tmp_path / "b.png", img)
    with Image.open(tmp_path / "b.png") as im:
        assert "dpi" not in im.info
    with pytest.raises(InputError, match="dpi"):
        write_png(tmp_path / "c.png", img, dpi=0)


# ------------------------------------------------------------------------------- bird's-eye


def test_birdseye_size_and_scale():
    d = read_dem(cone(30)[:20], spacing=CELL)
    gb = birdseye_gbuffer(d, size=120, supersample=1)
    assert gb.mask.shape == (90, 120)
    gb = birdseye_gbuffer(d, scale=4, supersample=1)  # long side 4 x 30 cells
    assert gb.mask.shape == (90, 120)
    with pytest.raises(InputError, match="size: the G-buffer is already rendered"):
        sg.birdseye_map(gb, size=64)
    with pytest.raises(InputError, match="window_size: expected window_size= or size="):
        birdseye_gbuffer(d, window_size=(64, 48), size=64)
    with pytest.raises(InputError, match="scale: a map scale '1:25000' applies to plan-view"):
        sg.sumi_e(d, scale="1:25000")
    with pytest.raises(InputError, match=r"size: expected an integer in \[1, 16384\]"):
        sg.birdseye_map(d, size=100_000)
