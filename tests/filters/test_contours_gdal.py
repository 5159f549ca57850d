"""Contour lines in plan view against real ``gdal_contour`` lines on the real DEMs.

GDAL's lines (marching squares between pixel centres) are sampled every 0.05 px and mapped to
fractional pixel-centre coordinates (row, col) with the inverse of GDAL's own geotransform.
"Within 1 px" always means a Euclidean distance <= 1 pixel, measured from a pixel *centre* to
the nearest GDAL line sample (precision) or from a GDAL line sample to the nearest pixel centre
with ink (recall); the sampling adds at most 0.025 px of error.

Our lines are compared like for like: ``g_eps=0`` (no Eq. 11 flat-region fade; exactly flat
pixels still get no ink), no ``c_dense`` (no Eq. 15 thinning), width 1, linear profile. The
intervals keep lines a few pixels apart, so that "within 1 px" is not met by any ink at all;
the half-interval shift below shows it is not.
"""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import cKDTree

from sciviz_gbuf.filters import contour_lines
from sciviz_gbuf.readers import read_dem
from tests.helpers import gdal_contour

rasterio = pytest.importorskip("rasterio")

SRTM = "SRTMGL3_40.09_-105.55_40.21_-105.35.asc"
# case -> (interval, base). N10W110 is sea at exactly 0 with an atoll up to 9 m: its levels
# sit at half metres (the level at 0 m is tested on its own below).
CASES = {
    "hugo_site.asc": (10.0, 0.0),
    "pre_runout_DEM.asc": (20.0, 0.0),
    SRTM: (100.0, 0.0),
    "N10W110.hgt": (1.0, 0.5),
    "jacksboro": (100.0, 0.0),
}
PRECISION = 0.98  # measured 0.987 .. 1.0 (0.996 .. 1.0 within 1.5 px)
RECALL = 0.995  # measured 0.9995 .. 1.0


def load(case: str, data: Path, tmp_path: Path):
    """(file for gdal_contour, our DEM): the DEM file itself, or for Matplotlib's jacksboro
    ``.npz`` a float32 GeoTIFF with the same heights and transform that ``read_dem`` gives."""
    if case != "jacksboro":
        src = data / "dem" / case
    else:
        from matplotlib.cbook import get_sample_data

        src = Path(get_sample_data("jacksboro_fault_dem.npz", asfileobj=False))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # no CRS: "taken as degrees"
        dem = read_dem(src)
    if case != "jacksboro":
        return src, dem
    src = tmp_path / "jacksboro.tif"
    h, w = dem.heights.shape
    profile = {"driver": "GTiff", "width": w, "height": h, "count": 1, "dtype": "float32"}
    transform = rasterio.Affine.from_gdal(*dem.transform)
    with rasterio.open(src, "w", nodata=float("nan"), transform=transform, **profile) as ds:
        ds.write(dem.heights, 1)
    return src, dem


def gdal_samples(src: Path, interval: float, base: float, tmp_path: Path) -> np.ndarray:
    """``gdal_contour -i interval -off base`` lines as (N, 2) (row, col) pixel-centre samples."""
    if shutil.which("gdal_contour") is None:
        pytest.skip("gdal_contour (gdal-bin) is not installed")
    pts = gdal_contour.gdal_samples(src, interval, tmp_path, base=base)
    assert pts is not None, f"gdal_contour drew no line of {src}"
    return pts


def compare(z, pts, *, interval, base, generalize=False, steep=None, apart=None):
    """(precision, recall, ink). Precision: share of pixels with ink >= 0.5 whose centre lies
    within 1 px of a GDAL line, every such pixel counted (grid border and nodata edges
    included). Recall: share of GDAL samples within 1 px of a pixel centre with ink > 0.25.
    ``steep``: judge only pixels (and GDAL samples in pixels) where lines lie at most this
    many px apart (``interval / |grad z|``, central differences); ``apart``: only where they
    lie more than this many px apart."""
    ink = contour_lines(z, interval=interval, base=base, width=1.0, g_eps=0.0,
                        generalize=generalize)  # fmt: skip
    judged = np.argwhere(ink >= 0.5)
    if steep is not None or apart is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            spacing = interval / np.hypot(*np.gradient(z.astype(np.float64)))
        near = spacing <= steep if steep is not None else spacing > apart
        judged = judged[near[judged[:, 0], judged[:, 1]]]
        cell = np.clip(np.rint(pts).astype(int), 0, np.array(z.shape) - 1)
        pts = pts[near[cell[:, 0], cell[:, 1]]]
    d_ours, _ = cKDTree(pts).query(judged, distance_upper_bound=2.0)
    d_gdal, _ = cKDTree(np.argwhere(ink > 0.25)).query(pts, distance_upper_bound=2.0)
    return np.mean(d_ours <= 1.0), np.mean(d_gdal <= 1.0), ink


@pytest.mark.parametrize("case", CASES)
def test_lines_sit_on_gdal_contour_lines(case, shared_data, tmp_path):
    src, dem = load(case, shared_data, tmp_path)
    with rasterio.open(src) as ds:  # our georeference is GDAL's
        np.testing.assert_allclose(dem.transform, ds.transform.to_gdal(), rtol=1e-12, atol=1e-9)
    interval, base = CASES[case]
    pts = gdal_samples(src, interval, base, tmp_path)
    precision, recall, ink = compare(dem.heights, pts, interval=interval, base=base)
    assert precision >= PRECISION, (precision, recall)
    assert recall >= RECALL, (precision, recall)
    assert len(pts) > 10_000  # a fair amount of line
    # nodata cells (hugo_site is half NODATA) never get ink
    nodata = np.isnan(dem.heights)
    assert not ink[nodata].any()
    if case == "hugo_site.asc":
        assert nodata.mean() > 0.3


# Generalisation drops rings and specks of a few px, most of them on gentle ground: GDAL
# lines it leaves out (measured recall 0.89 .. 0.99 where lines are more than 2 px apart);
# those it draws sit on GDAL's (precision 0.985 .. 0.998).
GENERALISED_RECALL = 0.85
APART = 2.0  # px between lines beyond which positions are judged (closer lines merge)


@pytest.mark.parametrize("case", [c for c in CASES if c != "N10W110.hgt"])
def test_generalised_lines_sit_on_gdal_lines(case, shared_data, tmp_path):
    """``generalize=True`` moves no line more than 0.6 px (its tolerance band): wherever lines
    are more than 2 px apart, steep or gentle ground, they are within 1 px of ``gdal_contour``'s
    as the exact lines are (N10W110 has no such ground: its atoll)."""
    src, dem = load(case, shared_data, tmp_path)
    interval, base = CASES[case]
    pts = gdal_samples(src, interval, base, tmp_path)
    precision, recall, _ = compare(dem.heights, pts, interval=interval, base=base,
                                   generalize=True, apart=APART)  # fmt: skip
    assert precision >= PRECISION, (precision, recall)
    assert recall >= GENERALISED_RECALL, (precision, recall)
    # and the comparison can fail: half an interval off misses
    shifted, _, _ = compare(dem.heights, pts, interval=interval, base=base + interval / 2,
                            generalize=True, apart=APART)  # fmt: skip
    assert shifted < 0.6, shifted


@pytest.mark.parametrize("case", [c for c in CASES if c != "N10W110.hgt"])
def test_lines_half_an_interval_off_miss_gdal(case, shared_data, tmp_path):
    """The comparison can fail: our lines at ``base + interval / 2`` fall mostly > 1 px from
    GDAL's (N10W110 is left out: its shifted levels land on the sea's exact 0, the tie below)."""
    src, dem = load(case, shared_data, tmp_path)
    interval, base = CASES[case]
    pts = gdal_samples(src, interval, base, tmp_path)
    precision, recall, _ = compare(dem.heights, pts, interval=interval, base=base + interval / 2)
    assert precision < 0.6, precision
    assert recall < 0.6, recall


def test_level_at_the_flat_sea_height_draws_no_shoreline(shared_data, tmp_path):
    """A level at exactly the sea's height (0 m): like GDAL (which nudges values equal to a
    level up), a value equal to a level counts as above it, so the sea is not outlined."""
    src, dem = load("N10W110.hgt", shared_data, tmp_path)
    pts = gdal_samples(src, 2.0, 0.0, tmp_path)
    precision, recall, ink = compare(dem.heights, pts, interval=2.0, base=0.0)
    assert recall >= RECALL
    assert precision >= PRECISION
    z = dem.heights
    # sea cells whose neighbours stay below the 2 m level: only the 0 m level is near them
    below_2 = ndimage.maximum_filter(z, 3) < 2.0
    shore = (z == 0) & below_2 & ndimage.binary_dilation(z > 0, np.ones((3, 3), bool))
    assert shore.sum() > 20
    assert ink[shore].max() == 0.0


def test_near_miss_draws_no_line():
    """A summit 0.3 m below a level: |s - p| / g is small on its top, but no line exists there
    (GDAL draws none); the level that is crossed is drawn, where it is crossed."""
    y, x = np.mgrid[-20:21, -20:21].astype(np.float32)
    r = np.hypot(x, y)
    z = 9.7 - 0.5 * r  # a cone, summit 0.3 m below the 10 m level
    ink = contour_lines(z, interval=10.0, width=1.0, g_eps=0.0)
    assert ink[r < 8].max() == 0.0  # the slope is 0.5 m/px: |s - p| / g < 1 px at the top
    ring = ink >= 0.5  # the 0 m level: a circle of radius 19.4
    assert ring.sum() > 40 and np.all(np.abs(r[ring] - 19.4) <= 1.0)


def test_generalised_level_at_the_sea_height_does_not_flood_the_sea(shared_data, tmp_path):
    """A wide major line at exactly the sea's height (0 m, majors every 5 m): the smoothed
    gradient reaches a few px out to sea from the island's slope, but no line may be drawn
    where the heights around are all exactly that level (it once flooded a 4 px band)."""
    _, dem = load("N10W110.hgt", shared_data, tmp_path)
    z = dem.heights[780:900, 880:1000]
    land = z > 0
    # 8-connected distance > 1 px from land: the 3x3 around is all sea at 0 m
    open_sea = ~ndimage.binary_dilation(land, np.ones((3, 3), bool))
    assert open_sea.sum() > 1000 and land.sum() > 300
    for generalize in (True, False):
        ink = contour_lines(z, interval=1.0, major_interval=5.0, width=1.0, major_width=2.0,
                            generalize=generalize)  # fmt: skip
        assert ink[open_sea].max() == 0.0, generalize
        assert (ink[land] > 0.5).sum() > 100  # the island's own lines are drawn
