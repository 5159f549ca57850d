"""Contour labels: placement rules checked independently (tests/helpers/label_checks.py) on
analytic shapes and the shared DEMs, knock-out of the lines under the text, GeoJSON, CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import sciviz_gbuf as sg
import sciviz_gbuf.datasets
from sciviz_gbuf.cli import main
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes._intervals import contour_intervals
from sciviz_gbuf.recipes._map import as_dem
from sciviz_gbuf.recipes._resample import map_grid
from sciviz_gbuf.recipes.labels import (
    label_boxes,
    label_ink,
    label_options,
    label_text,
    place_labels,
)
from tests.helpers.cli import assert_clean_failure, checksums, run_cli
from tests.helpers.label_checks import problems

SHARED_DEMS = [
    "hugo_site.asc",
    "pre_runout_DEM.asc",
    "SRTMGL3_40.09_-105.55_40.21_-105.35.asc",
    "N10W110.hgt",
]


def cone(shape=(600, 800), slope=1.0, top=1000.0) -> np.ndarray:
    """A cone on 1 m pixels whose apex is the grid's centre (heights fall ``slope`` per px)."""
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    return (top - slope * np.hypot(x - (w - 1) / 2, y - (h - 1) / 2)).astype(np.float32)


def check_map(dem, **kw):
    """Labels of a map and every rule they break (see :func:`problems`)."""
    labels = sg.contour_labels(dem, **kw)
    size = {k: kw[k] for k in ("size", "scale", "dpi") if k in kw}
    grid = map_grid(as_dem(dem), **size)
    _, _, minor, major = contour_intervals(
        grid.heights, kw.get("interval"), kw.get("major_interval")
    )
    _, spacing = label_options(kw.get("label_size"), kw.get("label_spacing"))
    step = major if major is not None else minor
    return labels, problems(labels, grid.heights.astype(np.float64), step, spacing), grid


def assert_clean(found):
    bad = {k: v[:3] for k, v in found.items() if v}
    assert not bad, bad


def test_cone_labels_follow_the_rings_and_face_the_apex():
    z = cone()
    labels, found, _ = check_map(z, interval=10.0, major_interval=50.0)
    assert_clean(found)
    assert len(labels) >= 20
    cy, cx = (z.shape[0] - 1) / 2, (z.shape[1] - 1) / 2
    for lab in labels:
        # on the ring of its level (the cone's height falls 1 per px from the apex)
        r = math.hypot(lab.x - cx, lab.y - cy)
        assert abs(r - (1000.0 - lab.level)) < 0.6
        # the baseline is the ring's tangent, the text's top towards the apex (uphill)
        a = math.radians(lab.angle)
        up = np.array([-math.sin(a), -math.cos(a)])  # image coordinates, rows down
        to_apex = np.array([cx - lab.x, cy - lab.y]) / r
        assert up @ to_apex > math.cos(math.radians(6))
    # Every label of a ring at least ``spacing`` along the ring from the others.
    _, spacing = label_options(None, None)
    for level in {lab.level for lab in labels}:
        ring = [lab for lab in labels if lab.level == level]
        theta = sorted(math.atan2(lab.y - cy, lab.x - cx) for lab in ring)
        r = 1000.0 - level
        gaps = np.diff([*theta, theta[0] + 2 * math.pi]) * r
        assert (gaps >= spacing - 1.0).all()


def test_labels_prefer_to_read_upright():
    """On a cone the top of the numbers faces the apex: labels south of it read upright,
    north of it they would be upside down. A line that reads upright somewhere gets no
    upside-down label: whole rings and the arcs that reach south of the apex are labelled
    south of it."""
    z = cone()
    h, w = z.shape
    cy, cx = (h - 1) / 2, (w - 1) / 2
    labels = sg.contour_labels(z, interval=10.0, major_interval=50.0)
    assert len(labels) >= 10
    for lab in labels:
        r = np.hypot(lab.x - cx, lab.y - cy)
        if abs(lab.angle) > 90:
            # only on a ring the frame cuts into four arcs: the northern one has no upright
            # place at all
            assert r > max(cx, cy) and lab.y < cy, lab
        else:
            assert lab.y > cy, lab  # upright: south of the apex


@pytest.mark.parametrize("name", ["SRTMGL3_40.09_-105.55_40.21_-105.35.asc", "hugo_site.asc"])
def test_upside_down_labels_only_where_a_line_reads_upright_nowhere(shared_data, name):
    """Upside-down labels (the text reads uphill only so) are few: lines that have an
    upright place carry none."""
    dem = read_dem(shared_data / "dem" / name)
    labels = sg.contour_labels(dem, size=1600)
    down = [lab for lab in labels if abs(lab.angle) > 90]
    assert len(labels) >= 10 and len(down) <= 0.15 * len(labels)


def test_label_text():
    assert label_text(1200.0, 100.0) == "1200"
    assert label_text(-20.0, 10.0) == "\u221220"
    assert label_text(12.5, 2.5) == "12.5"
    assert label_text(0.25, 0.25) == "0.25"
    assert label_text(-0.0, 1.0) == "0"


@pytest.mark.parametrize("name", SHARED_DEMS)
def test_labels_on_shared_dems(shared_data, name):
    """The shared DEMs mapped at a print-like size: every rule holds, and every index
    contour longer than three label spacings has a label."""
    dem = read_dem(shared_data / "dem" / name)
    labels, found, grid = check_map(dem, size=1600)
    assert_clean(found)
    if name != "N10W110.hgt":  # the atoll has no index contour of a label's length
        assert len(labels) >= 10
    # the labels' map coordinates are the transform of their pixel positions
    x0, dx, rx, y0, ry, dy = grid.transform
    for lab in labels[:20]:
        assert lab.map_x == pytest.approx(x0 + (lab.x + 0.5) * dx + (lab.y + 0.5) * rx)
        assert lab.map_y == pytest.approx(y0 + (lab.x + 0.5) * ry + (lab.y + 0.5) * dy)


def test_labels_on_the_bundled_dem_and_rounded_and_noisy_copies():
    """The bundled DEM, rounded to whole metres (terraces) and with 0.5 m of noise: the same
    rules hold."""
    dem = sg.datasets.load_jacksboro_dem()
    rng = np.random.default_rng(0)
    for heights in (
        dem.heights,
        np.round(dem.heights),
        dem.heights + rng.normal(0, 0.5, dem.shape).astype(np.float32),
    ):
        d = read_dem(heights.astype(np.float32), spacing=dem.pixel_size[0])
        labels, found, _ = check_map(d, size=1400)
        assert_clean(found)
        assert len(labels) >= 50


def test_short_rings_get_no_label():
    """Small hills whose index rings are shorter than four label lengths: no label."""
    y, x = np.mgrid[0:200, 0:300].astype(np.float64)
    z = np.zeros_like(x)
    for cx, cy in ((60, 60), (200, 120)):
        z = np.maximum(z, 100 - np.hypot(x - cx, y - cy) * 4)
    labels = sg.contour_labels(z.astype(np.float32), interval=20.0, major_interval=50.0)
    assert labels == []  # the 50 m rings have a radius of 12.5 px: 79 px around


def test_long_ring_gets_labels_and_a_ring_is_labelled_once_per_spacing():
    z = cone((400, 400), slope=1.0, top=500.0)
    labels = sg.contour_labels(z, interval=100.0, major_interval=100.0, label_spacing=200.0)
    on_400 = [lab for lab in labels if lab.level == 400.0]  # radius 100: 628 px around
    assert 1 <= len(on_400) <= 3


def test_labels_avoid_nodata_and_the_frame():
    z = cone((300, 400), slope=0.8)
    z[:, 200:230] = np.nan  # a strip of nodata through the middle
    labels, found, _grid = check_map(z, interval=10.0, major_interval=20.0)
    assert_clean(found)
    assert labels
    for lab in labels:
        half = math.hypot(lab.width, lab.height) / 2
        if abs(lab.x - 215) < half:  # near the strip: its box must not reach into it
            box = label_boxes([lab], z.shape) > 0
            assert not np.isnan(z[box]).any()


def test_no_line_ink_under_the_text_box():
    """White paper, red lines, blue text: under every label box only white and blue mix
    (R == G), where the lines run (and did before) only outside; the text is drawn in it."""
    dem = sg.datasets.load_jacksboro_dem()
    opts = {"size": 1000, "bands": False, "relief": False, "contour_color": (1.0, 0.0, 0.0)}
    plain = sg.topographic_map(dem, **opts)
    img = sg.topographic_map(dem, labels=True, label_color=(0.0, 0.0, 1.0), **opts)
    labels = sg.contour_labels(dem, size=1000)
    assert len(labels) > 30
    boxes = label_boxes(labels, img.shape[:2])
    inside = boxes >= 1.0
    r, g = img[..., 0].astype(int), img[..., 1].astype(int)
    assert np.abs(r - g)[inside].max() <= 1  # no red (line) ink
    # lines did run there without labels, so something was knocked out
    assert (np.abs(plain[..., 0].astype(int) - plain[..., 1])[inside] > 50).sum() > 100
    # the text is there: every box holds blue ink, and outside the boxes the map is unchanged
    ink = label_ink(labels, img.shape[:2], label_options(None, None)[0])
    for lab in labels:
        one = label_boxes([lab], img.shape[:2]) >= 1.0
        assert ink[one].max() > 0.9
    assert (ink[boxes == 0] == 0).all()
    assert (img[boxes == 0] == plain[boxes == 0]).all()


def test_text_ink_matches_the_label_angle():
    """The rendered text's long axis (second moments of its ink) has the label's angle."""
    z = cone()
    labels = sg.contour_labels(z, interval=10.0, major_interval=50.0)
    for lab in labels[:10]:
        ink = label_ink([lab], z.shape, 11.0)
        rows, cols = np.nonzero(ink > 0.3)
        wts = ink[rows, cols]
        xc, yc = np.average(cols, weights=wts), np.average(rows, weights=wts)
        assert math.hypot(xc - lab.x, yc - lab.y) < 1.5  # centred on the line
        cov = np.cov(np.stack([cols - xc, -(rows - yc)]), aweights=wts)
        _evals, evecs = np.linalg.eigh(cov)
        axis = evecs[:, 1]
        a = math.radians(lab.angle)
        assert abs(axis @ [math.cos(a), math.sin(a)]) > math.cos(math.radians(5))


def test_geojson_of_labels(tmp_path):
    dem = read_dem(cone((300, 400)), transform=(500000.0, 2.0, 0.0, 4000000.0, 0.0, -2.0),
                   crs="EPSG:32633")  # fmt: skip
    labels = sg.contour_labels(dem, interval=10.0, major_interval=50.0)
    fc = sg.labels_to_geojson(labels, crs="EPSG:32633")
    from sciviz_gbuf.writers import write_geojson

    path = tmp_path / "labels.geojson"
    write_geojson(path, fc)
    back = json.loads(path.read_text(encoding="utf-8"))
    assert back["crs"]["properties"]["name"] == "EPSG:32633"
    assert len(back["features"]) == len(labels)
    for f, lab in zip(back["features"], labels, strict=True):
        x, y = f["geometry"]["coordinates"]
        assert x == pytest.approx(500000.0 + (lab.x + 0.5) * 2.0)
        assert y == pytest.approx(4000000.0 - (lab.y + 0.5) * 2.0)
        assert f["properties"]["text"] == lab.text
        assert f["properties"]["rotation"] == pytest.approx(-lab.angle, abs=1e-3)


def test_geojson_refuses_nan(tmp_path):
    from sciviz_gbuf.writers import write_geojson

    bad = {"type": "FeatureCollection", "features": [{"geometry": {"coordinates": [math.nan]}}]}
    with pytest.raises(InputError, match="collection"):
        write_geojson(tmp_path / "x.geojson", bad)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"label_size": 0}, "label_size"),
        ({"label_size": 2}, "label_size"),
        ({"label_size": 1e6}, "label_size"),
        ({"label_size": math.nan}, "label_size"),
        ({"label_size": True}, "label_size"),
        ({"label_spacing": -1}, "label_spacing"),
        ({"label_spacing": 1e9}, "label_spacing"),
        ({"labels": "yes"}, "labels"),
        ({"label_color": (2, 0, 0)}, "label_color"),
    ],
)
def test_bad_label_options(kw, match):
    with pytest.raises(InputError, match=match):
        sg.topographic_map(cone((40, 50)), **{"labels": True, **kw})


def test_chunked_dem_has_no_labels(tmp_path):
    pytest.importorskip("dask.array")
    path = tmp_path / "cone.npy"
    np.save(path, cone((64, 64)))
    lazy = read_dem(path, chunks=32)
    with pytest.raises(InputError, match="labels"):
        sg.topographic_map(lazy, labels=True)
    with pytest.raises(InputError, match="labels"):
        sg.contour_labels(lazy)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    shape=st.tuples(st.integers(3, 90), st.integers(3, 90)),
    holes=st.floats(0.0, 0.6),
    amplitude=st.floats(0.01, 1e4),
)
@example(seed=35701742, shape=(3, 3), holes=0.0, amplitude=1.0)  # no index level at all
def test_odd_fields_break_no_rule(seed, shape, holes, amplitude):
    rng = np.random.default_rng(seed)
    z = np.cumsum(np.cumsum(rng.standard_normal(shape), 0), 1) * amplitude
    z[rng.random(shape) < holes] = np.nan
    if not np.isfinite(z).any():
        return
    labels = place_labels(z, step=amplitude * 5, band=amplitude * 5, font_px=6.0, spacing_px=60)
    found = problems(labels, z, amplitude * 5, 60.0)
    found["unlabelled"] = []  # random walks are not straight anywhere
    assert_clean(found)


def test_cli_topo_labels(tmp_path):
    out, gj = tmp_path / "map.png", tmp_path / "labels.geojson"
    rc = main(["topo", "--labels", "--size", "800", "-o", str(out), "--labels-geojson", str(gj)])
    assert rc == 0 and out.is_file()
    fc = json.loads(gj.read_text(encoding="utf-8"))
    assert len(fc["features"]) == len(sg.contour_labels(sg.datasets.load_jacksboro_dem(), size=800))


@pytest.mark.parametrize(
    "argv, match",
    [
        (["--labels-geojson", "x.geojson"], "--labels-geojson"),
        (["--labels", "--labels-geojson", "x.txt"], "--labels-geojson"),
        (["--labels", "--label-size", "1000"], "label_size"),
        (["--labels", "--chunks", "64"], "--labels"),
    ],
)
def test_cli_bad_label_options(tmp_path, argv, match):
    out = tmp_path / ("m.tif" if "--chunks" in argv else "m.png")
    dem = tmp_path / "d.npy"
    np.save(dem, cone((60, 70)))
    inputs = checksums([dem])
    proc = run_cli(["topo", dem, "-o", out, *argv], cwd=tmp_path)
    assert_clean_failure(proc, names=match, outputs=[out], inputs=inputs)
