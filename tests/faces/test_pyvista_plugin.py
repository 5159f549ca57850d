"""The PyVista plugin: ``mesh.gbuf`` / ``plotter.gbuf`` and the live edge overlay."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import pyvista as pv
from pyvista import examples
from scipy import ndimage
from vtkmodules.util.numpy_support import vtk_to_numpy

import sciviz_gbuf as sg
from sciviz_gbuf import pyvista_plugin
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import edge_map
from sciviz_gbuf.live import overlay_rgba
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.styles.illustration import illustrate

RED, BLUE = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)

_FRESH = r"""
import json, sys
import pyvista as pv
from importlib.metadata import entry_points

classes = [pv.DataSet, pv.PolyData, pv.ImageData, pv.StructuredGrid, pv.UnstructuredGrid,
           pv.RectilinearGrid, pv.MultiBlock, pv.BasePlotter, pv.Plotter]
out = {
    # class dicts along the MRO: `hasattr(cls, "gbuf")` would itself import the plugin
    "shadowed_before": [
        c.__name__ for c in classes if any("gbuf" in k.__dict__ for k in c.__mro__)
    ],
    "imported_before": "sciviz_gbuf" in sys.modules,
    "accessor_eps": {e.name: e.value for e in entry_points(group="pyvista.accessors")},
    "component_eps": {e.name: e.value for e in entry_points(group="pyvista.plotter_components")},
}
acc = pv.Sphere().gbuf
out["accessor_module"] = type(acc).__module__
out["class_level"] = pv.PolyData.gbuf.__name__
out["imported_after"] = "sciviz_gbuf" in sys.modules
pl = pv.Plotter(off_screen=True)
out["component"] = type(pl.gbuf).__name__
out["registered"] = [r.source for r in pv.registered_accessors() if r.name == "gbuf"]
pl.close()
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def nut() -> pv.PolyData:
    return examples.load_nut()


def _fresh_python(code: str) -> dict:
    env = dict(os.environ)
    if not env.get("DISPLAY"):
        env.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_entry_points_make_gbuf_work_without_importing_the_package():
    out = _fresh_python(_FRESH)
    # before any access: no PyVista class has a `gbuf` attribute, nothing of ours is imported
    assert out["shadowed_before"] == []
    assert out["imported_before"] is False
    assert out["accessor_eps"].get("gbuf") == "sciviz_gbuf.pyvista_plugin"
    assert out["component_eps"].get("gbuf") == "sciviz_gbuf.pyvista_plugin"
    # the first `.gbuf` makes PyVista import the plugin lazily
    assert out["accessor_module"] == "sciviz_gbuf.pyvista_plugin"
    assert out["imported_after"] is True
    assert out["class_level"] == "GBufAccessor"
    assert out["component"] == "GBufPlotterComponent"
    assert out["registered"] == ["sciviz_gbuf.pyvista_plugin.GBufAccessor"]


def test_register_is_idempotent_and_silent():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pyvista_plugin.register()
        pyvista_plugin.register()
    assert pv.PolyData.gbuf is pyvista_plugin.GBufAccessor
    assert pv.Plotter.gbuf is pyvista_plugin.GBufPlotterComponent


def test_capture_equals_package_capture_and_chains(nut):
    kw = {"window_size": (160, 120), "camera": "iso", "supersample": 1}
    img = nut.gbuf.capture(**kw)
    gb = sg.capture(nut, **kw)
    assert isinstance(img, pv.ImageData)
    assert img.dimensions == (160, 120, 1)
    for name, arr in gb.channels().items():
        got = np.asarray(img.point_data[name]).reshape(120, 160, *np.shape(arr)[2:])[::-1]
        np.testing.assert_array_equal(got, np.asarray(arr).astype(got.dtype), err_msg=name)
    # the GBuffer is reachable again from the image, bit for bit
    back = img.gbuf.gbuffer()
    np.testing.assert_array_equal(back.depth, gb.depth)
    assert back.camera.window_size == gb.camera.window_size
    # chaining: ordinary PyVista filters on the result
    covered = img.threshold(0.5, scalars="mask")
    assert covered.n_cells > 0
    assert covered.n_points < img.n_points
    assert covered.get_data_range("depth")[0] > 0


def test_edges_image_equals_illustrate(nut):
    kw = {"window_size": (160, 120), "camera": "xy"}
    pic = nut.gbuf.edges(style="enhance", width=1.5, **kw)
    # supersample 2 by default, as `sciviz-gbuf edges`
    ref = illustrate(sg.capture(nut, supersample=2, **kw), style="enhance", width=1.5)
    rgb = np.asarray(pic.point_data["RGB"]).reshape(120, 160, 3)[::-1]
    np.testing.assert_array_equal(rgb, np.round(np.clip(ref, 0, 1) * 255).astype(np.uint8))
    assert pic.active_scalars_name == "RGB"
    assert (rgb.sum(axis=-1) == 0).sum() > 100  # black profile lines are there
    # from a captured G-buffer image: no new render, same picture
    again = nut.gbuf.capture(supersample=2, **kw).gbuf.edges(style="enhance", width=1.5)
    np.testing.assert_array_equal(again.point_data["RGB"], pic.point_data["RGB"])
    edgemap = nut.gbuf.edges(style="edgemap", **kw)
    assert edgemap.point_data["RGBA"].shape == (160 * 120, 4)


def _hills(ny: int = 60, nx: int = 80) -> np.ndarray:
    y, x = np.mgrid[0:ny, 0:nx].astype(np.float64)
    return (300 + 80 * np.sin(x / 9) * np.cos(y / 7) + 2 * y).astype(np.float32)


def test_topographic_map_on_dem_grid_and_image():
    heights = _hills()
    dem = read_dem(heights, spacing=10.0, geographic=False)
    ref = sg.topographic_map(dem, interval=10, major_interval=50)  # (H, W, 4), row 0 north
    grid = dem.to_pyvista()
    out = grid.gbuf.topographic_map(interval=10, major_interval=50)
    assert isinstance(out, pv.ImageData)
    assert out.dimensions == grid.dimensions
    np.testing.assert_allclose(out.spacing[:2], (10.0, 10.0))
    np.testing.assert_allclose(out.origin[:2], np.asarray(grid.points[0, :2]))
    got = np.asarray(out.point_data["RGBA"]).reshape(60, 80, 4)[::-1]
    np.testing.assert_array_equal(got, ref)
    # a 2-D ImageData with a height array, j running north
    img = pv.ImageData(dimensions=(80, 60, 1), spacing=(10, 10, 1))
    img.point_data["h"] = heights[::-1].ravel()
    out2 = img.gbuf.topographic_map(heights="h", interval=10, major_interval=50)
    np.testing.assert_array_equal(out2.point_data["RGBA"], out.point_data["RGBA"])


def _coloured(img: np.ndarray, rgb: tuple[float, float, float]) -> np.ndarray:
    """Pixels within 60/255 of a pure colour in every channel."""
    target = np.asarray(rgb) * 255
    return np.all(np.abs(img[..., :3].astype(float) - target) < 60, axis=-1)


def _agreement(img: np.ndarray, emap: np.ndarray) -> tuple[float, float, float, int]:
    """Fraction of strong profile / inner pixels drawn red / blue; red outside any ink."""
    prof = emap[..., 3] >= 0.9
    inner = (emap[..., 0] >= 0.9) & (emap[..., 3] <= 0.1)
    red, blue = _coloured(img, RED), _coloured(img, BLUE)
    stray = float((red & (emap[..., 3] < 0.05)).sum() / max(red.sum(), 1))
    return (
        float((red & prof).sum() / prof.sum()),
        float((blue & inner).sum() / max(inner.sum(), 1)),
        stray,
        int(prof.sum()),
    )


def _assert_matches_capture(pl: pv.Plotter, img: np.ndarray, step: int) -> None:
    """The screenshot shows capture + edge_map of the same view: >= 95 % of its strong profile
    pixels red and inner pixels blue, at most 2 % of the red outside any ink."""
    emap = edge_map(sg.capture(pl), operator="diagonal", crease_angle=30.0)
    prof_ok, inner_ok, stray, n_prof = _agreement(img, emap)
    assert n_prof > 500
    assert prof_ok >= 0.95, (step, prof_ok)
    assert inner_ok >= 0.95, (step, inner_ok)
    assert stray <= 0.02, (step, stray)


def test_live_screenshot_matches_capture_and_disable_restores(nut):
    pl = pv.Plotter(off_screen=True, window_size=(400, 300))
    pl.add_mesh(nut)
    plain = pl.screenshot()
    assert pl.gbuf.enable_edge_enhancement(inner_color=BLUE, profile_color=RED) is pl
    assert pl.gbuf.edge_enhancement_enabled
    for step in range(2):
        img = pl.screenshot()
        _assert_matches_capture(pl, img, step)
        if step == 0:
            # those pixels are not red in the plain rendering: the overlay drew them
            assert _coloured(plain, RED).sum() == 0
            assert not np.array_equal(img, plain)
            first = img
            pl.camera.azimuth += 30
            pl.render()  # off-screen, screenshot() alone does not render a new frame
        else:
            assert not np.array_equal(img, first)
    updates = pl.gbuf.live.updates
    assert updates == 2  # one capture per new view
    pl.render()
    pl.render()
    assert pl.gbuf.live.updates == updates  # unchanged frames reuse the overlay
    pl.camera.azimuth -= 30
    pl.gbuf.disable_edge_enhancement()
    assert not pl.gbuf.edge_enhancement_enabled
    assert np.array_equal(pl.screenshot(), plain)
    pl.close()


def test_live_default_style_draws_black_profiles(nut):
    pl = pv.Plotter(off_screen=True, window_size=(320, 240))
    pl.add_mesh(nut)
    pl.gbuf.enable_edge_enhancement()
    img = pl.screenshot()
    emap = edge_map(sg.capture(pl))
    prof = emap[..., 3] >= 0.9
    black = np.all(img[..., :3] < 60, axis=-1)
    assert (black & prof).sum() / prof.sum() >= 0.95
    # show() renders through the same window: same frame
    shown = pl.show(return_img=True, auto_close=False)
    assert np.array_equal(shown, img)
    window = pl.render_window
    n_observers = window.HasObserver("StartEvent")
    pl.close()  # the close hook detaches: no error, no observer of ours left
    assert n_observers == 1
    assert not window.HasObserver("StartEvent")


def test_live_overlay_is_subplot_local(nut):
    def scene(enhance: bool) -> tuple[pv.Plotter, np.ndarray]:
        pl = pv.Plotter(off_screen=True, shape=(1, 2), window_size=(400, 200), border=False)
        for col in range(2):
            pl.subplot(0, col)
            pl.add_mesh(nut)
        if enhance:
            pl.subplot(0, 1)
            pl.gbuf.enable_edge_enhancement(inner_color=BLUE, profile_color=RED)
        return pl, pl.screenshot()

    pl_plain, plain = scene(False)
    pl, img = scene(True)
    assert np.array_equal(img[:, :200], plain[:, :200])  # left subplot untouched
    assert not np.array_equal(img[:, 200:], plain[:, 200:])
    # the right subplot agrees with a capture of that subplot at its own size
    pl.subplot(0, 1)
    gb = sg.capture(pl, window_size=(200, 200), camera=pl.renderer.GetActiveCamera())
    prof_ok, _, stray, _ = _agreement(img[:, 200:], edge_map(gb))
    # pl.gbuf.capture is the same G-buffer as an ImageData
    as_image = pl.gbuf.capture(window_size=(200, 200), camera=pl.renderer.GetActiveCamera())
    np.testing.assert_array_equal(as_image.gbuf.gbuffer().depth, gb.depth)
    assert prof_ok >= 0.95
    assert stray <= 0.02
    pl.subplot(0, 0)
    assert not pl.gbuf.edge_enhancement_enabled
    layers = pl.render_window.GetNumberOfLayers()
    pl.gbuf.enable_edge_enhancement()  # both subplots now; removed in the "wrong" order
    assert not np.array_equal(pl.screenshot()[:, :200], plain[:, :200])
    pl.gbuf.disable_edge_enhancement()
    pl.subplot(0, 1)
    pl.gbuf.disable_edge_enhancement()
    assert np.array_equal(pl.screenshot(), plain)
    assert pl.render_window.GetNumberOfLayers() == layers - 1  # every layer we added is gone
    pl.close()
    pl_plain.close()


@pytest.mark.parametrize(
    "kwargs",
    [
        {"style": "nope"},
        {"operator": "sobel"},
        {"width": 0},
        {"crease_angle": -5},
        {"supersample": 0},
        {"supersample": 1.5},
        {"inner_color": (2, 0, 0)},
        {"profile_color": "red"},
        {"opacity": 3},
    ],
)
def test_bad_live_arguments(kwargs):
    pl = pv.Plotter(off_screen=True, window_size=(64, 48))
    pl.add_mesh(pv.Sphere())
    with pytest.raises(InputError):
        pl.gbuf.enable_edge_enhancement(**kwargs)
    assert not pl.gbuf.edge_enhancement_enabled
    pl.close()


def test_bad_accessor_arguments(nut):
    with pytest.raises(InputError):
        nut.gbuf.capture(window_size=(0, 10))
    with pytest.raises(InputError):
        nut.gbuf.capture(camera="sideways")
    with pytest.raises(InputError):
        nut.gbuf.edges(style="watercolour")
    with pytest.raises(InputError):
        nut.gbuf.topographic_map()  # not a grid
    with pytest.raises(InputError):
        nut.gbuf.gbuffer()  # not a captured image
    with pytest.raises(InputError):
        pv.ImageData(dimensions=(4, 4, 4)).gbuf.topographic_map()  # 3-D
    with pytest.raises(InputError):
        pv.ImageData(dimensions=(4, 4, 1)).gbuf.topographic_map()  # no heights array
    with pytest.raises(TypeError):
        nut.gbuf.capture((100, 100))  # keyword-only


def test_live_uploaded_pixels_are_the_rounded_overlay(nut):
    # The overlay is written in place into the kept image (inked pixels only, the last
    # frame's cleared): frame after frame it equals the rounded overlay_rgba, flipped.
    pl = pv.Plotter(off_screen=True, window_size=(240, 180))
    pl.add_mesh(nut)
    pl.gbuf.enable_edge_enhancement(inner_color=BLUE, profile_color=RED, opacity=0.8)
    live = pl.gbuf.live
    pl.screenshot()  # the first frame
    for step in range(3):
        if step:
            pl.camera.azimuth += 25.0
            pl.render()
        assert live.updates == step + 1
        expected = np.round(overlay_rgba(live.last_gbuffer, live.params) * 255.0).astype(np.uint8)
        got = vtk_to_numpy(live._image.GetPointData().GetScalars()).reshape(180, 240, 4)[::-1]
        np.testing.assert_array_equal(got, expected)
    pl.close()


@pytest.mark.parametrize("source", ["auto", "frame"])
def test_live_frame_route_matches_capture_without_a_second_render(nut, source):
    pl = pv.Plotter(off_screen=True, window_size=(400, 300))
    pl.add_mesh(nut)
    pl.disable_anti_aliasing()
    pl.render_window.SetMultiSamples(0)  # one depth sample per pixel: auto takes the frame
    pl.gbuf.enable_edge_enhancement(inner_color=BLUE, profile_color=RED, source=source)
    for step in range(2):
        img = pl.screenshot()
        assert pl.gbuf.live.route == "frame"
        assert pl.gbuf.live._session is None  # no capture session: nothing rendered twice
        _assert_matches_capture(pl, img, step)
        pl.camera.azimuth += 30
        pl.render()
    assert pl.gbuf.live.updates == 3
    pl.close()


def test_live_auto_captures_where_the_frame_depth_is_not_exact(nut):
    pl = pv.Plotter(off_screen=True, window_size=(200, 150))
    pl.add_mesh(nut)
    assert pl.render_window.GetMultiSamples() > 1  # PyVista's default anti-aliasing
    pl.gbuf.enable_edge_enhancement()
    pl.screenshot()
    assert pl.gbuf.live.route == "capture"
    pl.gbuf.enable_edge_enhancement(source="frame")  # asked for: taken, up to a pixel off
    img = pl.screenshot()
    assert pl.gbuf.live.route == "frame"
    emap = edge_map(sg.capture(pl))
    black = np.all(img[..., :3] < 60, axis=-1)
    near = ndimage.binary_dilation(black)
    assert near[emap[..., 3] >= 0.9].mean() >= 0.95
    with pytest.raises(InputError, match="source"):
        pl.gbuf.enable_edge_enhancement(source="shader")
    with pytest.raises(InputError, match="supersample"):
        pl.gbuf.enable_edge_enhancement(source="frame", supersample=2)
    pl.close()
