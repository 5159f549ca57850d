"""The GPU route of the live overlay (``source="gpu"``): GLSL inside the user's frame, held to
the CPU route (``capture`` + ``edge_map``) as the reference, beside PyVista's render passes.

Mesa llvmpipe runs the same shaders as a graphics card would; what is measured here is the
route's correctness, not its speed (``benchmarks/bench_gpu_live.py``)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest
import pyvista as pv
from pyvista import examples
from scipy import ndimage
from vtkmodules.vtkCommonDataModel import vtkDataObject
from vtkmodules.vtkRenderingCore import vtkHardwareSelector

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import edge_map
from sciviz_gbuf.live import gl_info, is_hardware
from tests.helpers.paths import SHARED_DATA

RED, BLUE = (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)
RING = np.ones((3, 3), bool)  # "within one pixel"


@pytest.fixture(scope="module")
def nut() -> pv.PolyData:
    return examples.load_nut()


@pytest.fixture(scope="module")
def cad() -> pv.PolyData:
    path = SHARED_DATA / "meshes" / "vtkdata_42400-IDGH.stl"
    if not path.is_file():
        pytest.skip(f"{path} not available")
    return pv.read(path)


@pytest.fixture(scope="module")
def organic() -> pv.PolyData:
    """A marching-cubes surface of a segmented MRI (the frog's skeleton), decimated: staircase
    facets, thin bones, self-occlusion."""
    return examples.load_frog_tissues().contour([1.5]).extract_largest().decimate(0.7)


def _plotter(mesh: pv.PolyData, size=(480, 360), parallel=False, **kwargs) -> pv.Plotter:
    pl = pv.Plotter(off_screen=True, window_size=size, **kwargs)
    pl.add_mesh(mesh, color="tan")
    pl.camera.azimuth = 30
    pl.camera.elevation = 20
    if parallel:
        pl.enable_parallel_projection()
    return pl


def _agreement(inner: np.ndarray, prof: np.ndarray, ref: np.ndarray) -> tuple[float, ...]:
    """(GPU strong pixels within 1 px of the reference's, the reference's within 1 px of the
    GPU's, reference profile pixels with a GPU profile pixel within 1 px); strong: > 0.5."""
    gs = (inner > 0.5) | (prof > 0.5)
    rs = (ref[..., 0] > 0.5) | (ref[..., 3] > 0.5)
    rp = ref[..., 3] > 0.5
    assert rs.sum() > 500 and gs.sum() > 500
    precision = ndimage.binary_dilation(rs, RING)[gs].mean()
    recall = ndimage.binary_dilation(gs, RING)[rs].mean()
    profile_recall = ndimage.binary_dilation(prof > 0.5, RING)[rp].mean()
    return float(precision), float(recall), float(profile_recall)


def _red(img: np.ndarray) -> np.ndarray:
    return (img[..., 0] > 200) & (img[..., 1] < 70) & (img[..., 2] < 70)


@pytest.mark.parametrize("parallel", [False, True], ids=["perspective", "parallel"])
@pytest.mark.parametrize("which", ["nut", "cad", "organic"])
def test_gpu_edges_agree_with_capture_and_edge_map(which, parallel, request):
    mesh = request.getfixturevalue(which)
    pl = _plotter(mesh, parallel=parallel)
    with pv.VtkErrorCatcher(raise_errors=True, emit_warnings=True), warnings.catch_warnings():
        warnings.simplefilter("error")
        pl.gbuf.enable_edge_enhancement(source="gpu")
        pl.screenshot()
        assert pl.gbuf.live.route == "gpu"
        inner, prof = pl.gbuf.live.gpu_edge_planes()
    assert inner.shape == prof.shape == (360, 480)
    precision, recall, profile_recall = _agreement(inner, prof, edge_map(sg.capture(pl)))
    assert precision >= 0.95, precision
    assert recall >= 0.95, recall
    assert profile_recall >= 0.98, profile_recall
    pl.close()


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"width": 3.0},
        {"width": 4.0, "operator": "c1"},
        {"style": "profile", "crease_angle": 45.0},
        {"depth_jump": 3.0, "opacity": 0.5},
    ],
    ids=["default", "width3", "width4-c1", "profile", "jump-opacity"],
)
def test_gpu_frame_equals_the_cpu_frame_route(nut, options):
    """Same depth in, same picture out: the GPU route against the CPU ``frame`` route (which
    reads the same depth back and runs ``edge_map`` and the overlay in numpy/numba), one
    sample per pixel. Colours to the 8-bit rounding, line pixels to a handful."""
    colors = {"inner_color": BLUE, "profile_color": RED}
    pictures, inked = {}, {}
    for source in ("frame", "gpu"):
        pl = _plotter(nut)
        pl.disable_anti_aliasing()
        pl.render_window.SetMultiSamples(0)
        plain = pl.screenshot().astype(int)
        pl.gbuf.enable_edge_enhancement(source=source, **colors, **options)
        pictures[source] = pl.screenshot().astype(int)
        assert pl.gbuf.live.route == source
        inked[source] = np.abs(pictures[source] - plain).max(axis=-1) > 8
        pl.close()
    diff = np.abs(pictures["gpu"] - pictures["frame"]).max(axis=-1)
    assert (diff > 2).mean() <= 2e-3, (diff > 2).sum()
    assert inked["frame"].sum() > 300
    assert (inked["gpu"] == inked["frame"]).mean() >= 0.998


def test_parameters_are_uniforms_and_disable_restores_the_plain_frame(nut):
    pl = _plotter(nut)
    plain = pl.screenshot()
    pl.gbuf.enable_edge_enhancement(source="gpu", profile_color=RED)
    first = pl.screenshot()
    live = pl.gbuf.live
    programs = live._gpu.program_ids()
    assert len(programs) == 3 and _red(first).sum() > 300
    frames = live.gpu_frames
    pl.gbuf.enable_edge_enhancement(source="gpu", profile_color=BLUE, width=3, crease_angle=50)
    second = pl.screenshot()
    assert pl.gbuf.live is live and live.gpu_frames > frames  # the same overlay, redrawn
    assert live._gpu.program_ids() == programs  # nothing compiled for new parameters
    assert _red(second).sum() == 0
    pl.render()
    pl.render()
    assert live.updates == 0  # no capture, no read-back: every frame drawn in the shaders
    pl.gbuf.disable_edge_enhancement()
    assert np.array_equal(pl.screenshot(), plain)
    pl.close()


PASSES = {
    "msaa": lambda pl: pl.enable_anti_aliasing("msaa"),
    "ssaa": lambda pl: pl.enable_anti_aliasing("ssaa"),
    "ssao": lambda pl: pl.enable_ssao(),
    "edl": lambda pl: pl.enable_eye_dome_lighting(),
    "depth_peeling": lambda pl: pl.enable_depth_peeling(),
    "shadows": lambda pl: pl.enable_shadows(),
}


@pytest.mark.parametrize("name", list(PASSES))
def test_gpu_route_beside_pyvista_render_passes(nut, name):
    pl = _plotter(nut)
    PASSES[name](pl)
    with pv.VtkErrorCatcher(raise_errors=True, emit_warnings=True), warnings.catch_warnings():
        warnings.simplefilter("error")
        plain = pl.screenshot()
        pl.gbuf.enable_edge_enhancement(source="gpu", profile_color=RED)
        img = pl.screenshot()
        assert pl.gbuf.live.route == "gpu"
        inner, prof = pl.gbuf.live.gpu_edge_planes()
    ref = edge_map(sg.capture(pl))
    _, _, profile_recall = _agreement(inner, prof, ref)
    assert profile_recall >= 0.98, profile_recall
    # the lines reach the picture: red within a pixel of the reference profiles
    strong = ref[..., 3] > 0.9
    assert ndimage.binary_dilation(_red(img), RING)[strong].mean() >= 0.9
    assert _red(plain).sum() == 0
    pl.gbuf.disable_edge_enhancement()
    assert np.array_equal(pl.screenshot(), plain)
    pl.close()


def test_only_the_chosen_subplot_is_inked_and_resizing_follows(nut):
    def scene(enhance: bool) -> tuple[pv.Plotter, np.ndarray]:
        pl = pv.Plotter(off_screen=True, shape=(1, 2), window_size=(480, 240), border=False)
        for col in range(2):
            pl.subplot(0, col)
            pl.add_mesh(nut, color="tan")
        if enhance:
            pl.subplot(0, 1)
            pl.gbuf.enable_edge_enhancement(source="gpu", profile_color=RED)
        return pl, pl.screenshot()

    plain_pl, plain = scene(False)
    pl, img = scene(True)
    assert np.array_equal(img[:, :240], plain[:, :240])  # the left subplot untouched
    assert _red(img[:, 240:]).sum() > 200
    inner, prof = pl.gbuf.live.gpu_edge_planes()
    assert prof.shape == (240, 240)
    pl.window_size = (600, 300)
    plain_pl.window_size = (600, 300)
    img = pl.screenshot()
    assert np.array_equal(img[:, :300], plain_pl.screenshot()[:, :300])
    inner, prof = pl.gbuf.live.gpu_edge_planes()
    assert prof.shape == (300, 300)
    # the reference: the subplot's own capture (the CPU route's, at the subplot's size)
    _, _, profile_recall = _agreement(inner, prof, edge_map(pl.gbuf.live.capture()))
    assert profile_recall >= 0.98
    pl.close()
    plain_pl.close()


def _select(pl: pv.Plotter) -> set[int]:
    """Cell ids a hardware selector finds over the whole subplot."""
    sel = vtkHardwareSelector()
    sel.SetRenderer(pl.renderer)
    sel.SetFieldAssociation(vtkDataObject.FIELD_ASSOCIATION_CELLS)
    w, h = pl.renderer.GetSize()
    sel.SetArea(0, 0, w - 1, h - 1)
    res = sel.Select()
    ids: set[int] = set()
    for k in range(res.GetNumberOfNodes()):
        arr = res.GetNode(k).GetSelectionList()
        ids.update(int(arr.GetValue(i)) for i in range(arr.GetNumberOfTuples()))
    return ids


def test_hardware_picking_is_unchanged(nut):
    pl = _plotter(nut)
    pl.screenshot()
    before = _select(pl)
    pl.gbuf.enable_edge_enhancement(source="gpu")
    pl.screenshot()
    frames = pl.gbuf.live.gpu_frames
    after = _select(pl)
    assert len(before) > 100 and after == before
    assert pl.gbuf.live.gpu_frames == frames  # the selector's frames were left alone
    pl.close()


def test_auto_keeps_the_cpu_routes_on_a_software_rasteriser(nut):
    pl = _plotter(nut)
    pl.gbuf.enable_edge_enhancement()
    pl.screenshot()
    info = gl_info(pl.render_window)
    assert "llvmpipe" in info["renderer"].lower() or is_hardware(pl.render_window)
    if not is_hardware(pl.render_window):
        assert pl.gbuf.live.route in ("capture", "frame")
        assert pl.gbuf.live.gpu_frames == 0
    pl.close()


def test_gpu_route_refuses_what_it_cannot_draw(nut):
    pl = _plotter(nut)
    with pytest.raises(InputError, match="style: source='gpu'"):
        pl.gbuf.enable_edge_enhancement(source="gpu", style="lines")
    with pytest.raises(InputError, match="supersample"):
        pl.gbuf.enable_edge_enhancement(source="gpu", supersample=2)
    pl.close()


_CLOSE = textwrap.dedent(
    """
    import os
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv
    from pyvista import examples
    import sciviz_gbuf  # noqa: F401
    pl = pv.Plotter(off_screen=True, window_size=(200, 150))
    pl.add_mesh(examples.load_nut())
    pl.gbuf.enable_edge_enhancement(source="gpu")
    pl.screenshot()
    assert pl.gbuf.live.route == "gpu", pl.gbuf.live.route
    pl.window_size = (240, 180)  # textures made again at the new size
    pl.screenshot()
    {ending}
    print("done")
    """
)


@pytest.mark.parametrize("ending", ["pl.close()", "pl.gbuf.disable_edge_enhancement()"])
def test_gl_resources_are_released_without_leak_warnings(ending):
    run = subprocess.run(
        [sys.executable, "-c", _CLOSE.format(ending=ending)],
        capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "done"
    assert run.stderr.strip() == "", run.stderr


def test_a_pass_that_drops_the_depth_falls_back_to_the_cpu_once(nut):
    """PyVista's ``add_blurring`` (VTK's Gaussian blur pass) copies back only its colour: the
    frame's depth is the pass's quad, one value everywhere. The GPU route says so once and
    the CPU capture route draws the edges from the next frame on."""
    pl = _plotter(nut)
    pl.add_blurring()
    with pytest.warns(RuntimeWarning, match="depth is empty under the render pass"):
        pl.gbuf.enable_edge_enhancement(source="gpu", profile_color=RED)
        pl.screenshot()
    assert "vtkGaussianBlurPass" in pl.gbuf.live.gpu_unavailable
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pl.camera.azimuth += 10
        pl.render()
        img = pl.screenshot()
    assert pl.gbuf.live.route == "capture"
    strong = edge_map(sg.capture(pl))[..., 3] > 0.9
    assert ndimage.binary_dilation(_red(img), RING)[strong].mean() >= 0.9
    pl.close()
