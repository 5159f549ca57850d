"""The explorer's plan-view map of a DEM: the picture is ``topographic_map``'s, and a control
re-runs only the map layer it changes (contour ink, relief shade or band colours)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sciviz_gbuf.apps.explorer import Explorer, Params
from sciviz_gbuf.datasets import load_jacksboro_dem, load_nut
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes.terrain import topographic_map
from tests.helpers.paths import SHARED_DATA

DATA = SHARED_DATA / "dem"
HUGO = DATA / "hugo_site.asc"


def _on_paper(rgba: np.ndarray) -> np.ndarray:
    """A map's RGBA on white paper (nodata cells are transparent)."""
    return np.where(rgba[..., 3:] > 0, rgba[..., :3], np.uint8(255))


@pytest.fixture(scope="module")
def dem():
    d = load_jacksboro_dem()
    # A corner of it keeps the tests fast; nodata in one block exercises the white paper.
    h = d.heights[:160, :200].copy()
    h[:12, :20] = np.nan
    return dataclasses.replace(d, heights=h, mask=np.isfinite(h))


@pytest.fixture(scope="module")
def dem_explorer(dem) -> Explorer:
    return Explorer(dem.to_pyvista(), window_size=(64, 48), kind="dem", dem=dem)


def test_dem_opens_as_its_map_with_round_contour_intervals(dem_explorer, dem):
    e = dem_explorer
    assert e.params.view == "map"
    assert e.params.map_interval > 0 and e.params.major_every == 5 and e.params.map_bands >= 2
    img = e.render_image(e.params)
    assert img.shape == (*dem.shape, 3) and img.dtype == np.uint8
    assert (img[:12, :20] == 255).all()  # nodata: white paper
    assert e.captures == 0  # the map needs no rendering: no capture until the 3-D view


def test_map_is_topographic_map_with_the_same_parameters(dem_explorer, dem):
    e = dem_explorer
    lo, hi = float(np.nanmin(dem.heights)), float(np.nanmax(dem.heights))
    p = Params(
        view="map",
        map_azimuth=280.0,
        map_altitude=35.0,
        z_factor=2.0,
        relief="multidirectional",
        map_interval=10.0,
        major_every=4,
        map_width=1.5,
        map_bands=5,
    )
    img = e.render_image(p)
    # The parameters spelled out: nothing shared with the explorer's own translation.
    ref = topographic_map(
        dem,
        interval=10.0,
        major_interval=40.0,
        width=1.5,
        major_width=3.0,
        bands=[lo + (hi - lo) * k / 5 for k in range(1, 5)],
        azimuth=280.0,
        altitude=35.0,
        z_factor=2.0,
        variant="multidirectional",
    )
    np.testing.assert_array_equal(img, _on_paper(ref))
    for change in (
        {"map_bands": 0},
        {"map_bands": 1},
        {"map_interval": 0.0},
        {"relief": "igor", "map_azimuth": 45.0},
    ):
        img = e.render_image(dataclasses.replace(p, **change))
        ref = topographic_map(dem, **e.params.map_kwargs(e.map_range))
        np.testing.assert_array_equal(img, _on_paper(ref), err_msg=str(change))
    assert e.params.map_kwargs(e.map_range)["variant"] == "igor"


@pytest.mark.skipif(not HUGO.exists(), reason="needs ../shared/data")
def test_real_dem_file_with_nodata_outline():
    e = Explorer.from_file(HUGO, window_size=(64, 48))
    d = read_dem(HUGO)
    img = e.render_image()
    np.testing.assert_array_equal(
        img, _on_paper(topographic_map(d, **e.params.map_kwargs(e.map_range)))
    )
    assert (img[~d.mask] == 255).all() and (img[d.mask] < 255).any()


def test_contour_interval_changes_only_line_pixels(dem_explorer):
    e = dem_explorer
    base = e.render_image({"map_interval": 0.0, "map_bands": 6, "relief": "regular"})
    a = e.render_image({"map_interval": 10.0})
    b = e.render_image({"map_interval": 25.0})
    lines_a = (a != base).any(axis=2)
    lines_b = (b != base).any(axis=2)
    changed = (a != b).any(axis=2)
    assert changed.any() and lines_a.mean() > lines_b.mean() > 0
    # Every changed pixel is on a line of one of the two maps: shade and tint stay put.
    assert not (changed & ~(lines_a | lines_b)).any()


def test_a_control_recomputes_only_its_layer(dem_explorer):
    e = dem_explorer
    e.render_image({"map_interval": 10.0, "map_bands": 4, "map_azimuth": 315.0, "z_factor": 1.0})
    runs = dict(e.layer_runs)

    def recomputed(change) -> set[str]:
        before = dict(e.layer_runs)
        e.render_image(change)
        return {k for k, v in e.layer_runs.items() if v != before.get(k, 0)}

    assert recomputed({"map_azimuth": 300.0}) == {"map_relief"}
    assert recomputed({"map_altitude": 30.0}) == {"map_relief"}
    assert recomputed({"z_factor": 3.0}) == {"map_relief"}
    assert recomputed({"relief": "combined"}) == {"map_relief"}
    assert recomputed({"map_interval": 12.0}) == {"map_contours"}
    assert recomputed({"major_every": 3}) == {"map_contours"}
    # the widest line sets the rings dropped, and so the band islands filled
    assert recomputed({"map_width": 2.0}) == {"map_contours", "map_bands"}
    assert recomputed({"map_bands": 7}) == {"map_bands"}
    assert recomputed({"map_bands": 4}) == set()  # seen before: cached
    assert recomputed({"style": "toon", "crease_angle": 10.0}) == set()  # 3-D only
    assert e.captures == 0
    assert sum(e.layer_runs.values()) == sum(runs.values()) + 9


def test_view_selector_and_3d_style_layers(dem_explorer):
    e = dem_explorer
    e.set_camera(azimuth=60.0)  # nothing captured yet: only remembered
    assert e.captures == 0
    img = e.render_image({"view": "3d", "style": "gooch", "light_azimuth": 100.0})
    assert img.shape == (48, 64, 3) and e.captures == 1
    assert e.camera.azimuth == 60.0
    before = dict(e.layer_runs)
    e.render_image({"light_azimuth": 60.0})
    e.render_image({"style": "toon"})
    e.render_image({"style": "enhance"})
    # light and style share the edge map: it is not recomputed (toon thins its black inner
    # edges with the profiles where they clump: that cheap pass is a layer of its own)
    assert {k: v for k, v in e.layer_runs.items() if k != "emap_thin"} == {
        k: v for k, v in before.items() if k != "emap_thin"
    }
    e.render_image({"crease_angle": 20.0})
    assert e.layer_runs["emap"] == before["emap"] + 1
    back = e.render_image({"view": "map"})
    assert back.shape[:2] == e.dem.shape


def test_map_parameters_are_checked():
    e = Explorer(load_nut(), window_size=(32, 24))
    assert e.params.view == "3d" and e.dem is None
    with pytest.raises(InputError, match="view"):
        e.render_image({"view": "map"})
    with pytest.raises(InputError, match="view"):
        e.render_image({"view": "plan"})
    for bad, name in (
        ({"map_altitude": 95.0}, "map_altitude"),
        ({"z_factor": 0.0}, "z_factor"),
        ({"major_every": 0}, "major_every"),
        ({"map_bands": -1}, "map_bands"),
        ({"map_width": 0.0}, "map_width"),
        ({"relief": "flat"}, "relief"),
    ):
        with pytest.raises(InputError, match=name):
            e.render_image(bad)
    # The browser sends whole floats for integer controls.
    assert e.update_params({"major_every": 3.0, "map_bands": 2.0}).major_every == 3
