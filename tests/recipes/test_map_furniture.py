"""Map furniture: the legend's swatches are the map's band colours, the scale bar's length
matches the georeference to 1 % (projected and geographic grids)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import sciviz_gbuf as sg
import sciviz_gbuf.datasets
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes.furniture import legend_classes, scale_bar

BARE = {"relief": False, "contours": False, "generalize": False}


def _assert_swatches_match(dem, **opts):
    """Every map pixel's colour is the swatch of the class holding its height."""
    classes = legend_classes(dem, **opts)
    assert classes
    img = sg.topographic_map(dem, **BARE, **opts)
    d = read_dem(dem) if isinstance(dem, np.ndarray) else dem
    z = d.heights
    lows = np.array([c.low for c in classes])
    highs = np.array([c.high for c in classes])
    # the classes tile the range, lowest first
    assert (np.diff(lows) > 0).all() and np.allclose(lows[1:], highs[:-1])
    assert lows[0] == pytest.approx(np.nanmin(z)) and highs[-1] == pytest.approx(np.nanmax(z))
    ok = np.isfinite(z)
    # away from the class edges (a float32 height on an edge may fall either side)
    gap = np.min(np.abs(z[..., None] - lows[None, None, 1:]), axis=-1) if lows.size > 1 else 1e9
    ok &= gap > 1e-3 * max(1.0, float(np.nanmax(np.abs(z))))
    k = np.clip(np.searchsorted(lows, z[ok], side="right") - 1, 0, len(classes) - 1)
    want = np.array([c.rgb for c in classes], np.uint8)[k]
    diff = np.abs(img[ok][:, :3].astype(int) - want.astype(int)).max()
    # a continuous ramp is listed in 64 steps: within a step the map's colour drifts a little
    assert diff <= (6 if opts.get("bands") == "continuous" else 0)
    return classes


def test_legend_is_the_map_bands_of_the_bundled_dem():
    dem = sg.datasets.load_jacksboro_dem()
    classes = _assert_swatches_match(dem)
    # one band per major interval (100 m): inner edges are multiples of it
    assert all(c.low % 100 == 0 for c in classes[1:])
    assert len({c.rgb for c in classes}) == len(classes)


@pytest.mark.parametrize(
    "opts",
    [
        {"bands": 50.0},
        {"bands": [300.0, 420.0, 700.0]},
        {"bands": "continuous"},
        {"interval": 20.0, "major_interval": 200.0, "cmap": "viridis"},
        {"sea_level": 450.0},
    ],
)
def test_legend_follows_the_band_options(opts):
    dem = sg.datasets.load_jacksboro_dem()
    classes = _assert_swatches_match(dem, **opts)
    if "sea_level" in opts:
        assert any(c.high == 450.0 for c in classes)


def test_legend_of_a_shared_dem_with_nodata(shared_data):
    _assert_swatches_match(read_dem(shared_data / "dem" / "hugo_site.asc"))


def test_no_bands_no_legend():
    assert legend_classes(sg.datasets.load_jacksboro_dem(), bands=False) == []


def _parallel_metres_per_degree(lat: float) -> float:
    """WGS 84: a degree of longitude along the parallel ``lat`` (radius N cos phi)."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    phi = math.radians(lat)
    n = a / math.sqrt(1 - e2 * math.sin(phi) ** 2)
    return n * math.cos(phi) * math.pi / 180.0


def test_scale_bar_on_a_projected_grid(shared_data):
    dem = read_dem(shared_data / "dem" / "pre_runout_DEM.asc")  # 10 m cells
    bar = scale_bar(dem)
    assert bar.pixels == pytest.approx(bar.metres / 10.0, rel=0.01)
    assert bar.pixels <= 0.25 * dem.shape[1] < 2.5 * bar.pixels
    big = scale_bar(dem, size=1600)  # the map is 1049 px wide: 0.763 m... per px
    w = 1049
    assert big.pixels == pytest.approx(big.metres / (80 * 10.0 / w), rel=0.01)


@pytest.mark.parametrize("name", ["SRTMGL3_40.09_-105.55_40.21_-105.35.asc", "N10W110.hgt"])
def test_scale_bar_on_a_geographic_grid(shared_data, name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        dem = read_dem(shared_data / "dem" / name)
    assert dem.geographic
    for opts in ({}, {"size": 1000}):
        bar = scale_bar(dem, **opts)
        _x0, dx, _, y0, _, dy = dem.transform
        h, w = dem.shape
        lat = y0 + h / 2 * dy
        out_w = w if not opts else (1000 if w >= h else round(1000 * w / h))
        deg_per_px = dx * w / out_w
        want = bar.metres / (deg_per_px * _parallel_metres_per_degree(lat))
        assert bar.pixels == pytest.approx(want, rel=0.01)
        assert bar.text.endswith(" m") or bar.text.endswith(" km")


def test_scale_bar_lengths_are_round():
    for spacing in (0.3, 1.0, 7.0, 30.0, 1000.0):
        bar = scale_bar(read_dem(np.zeros((50, 400), np.float32), spacing=spacing))
        mant = bar.metres / 10 ** math.floor(math.log10(bar.metres))
        assert round(mant, 9) in (1.0, 2.0, 5.0)
        assert 0.1 * 400 <= bar.pixels <= 0.25 * 400


@pytest.mark.parametrize("fraction", [0, 2, math.nan, "x", True])
def test_scale_bar_bad_fraction(fraction):
    with pytest.raises(InputError, match="fraction"):
        scale_bar(np.zeros((10, 10), np.float32), fraction=fraction)
