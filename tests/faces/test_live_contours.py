"""Live contour lines in an actor's own shaders (``pl.gbuf.enable_contour_lines``), held to
``contour_lines`` of the captured field (the CPU route) as the reference."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import pyvista as pv
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import contour_line_parameters, contour_lines

RING = np.ones((3, 3), bool)  # "within one pixel"


@pytest.fixture(scope="module")
def hills() -> pv.PolyData:
    return pv.ParametricRandomHills(u_res=300, v_res=300).triangulate().elevation()


@pytest.fixture(scope="module")
def utm_dem() -> pv.PolyData:
    """A DEM surface where users' DEMs are: UTM coordinates (x ~ 4.5e5, y ~ 4.4e6 m, so VTK
    shifts the coordinates before the GPU sees them), heights 1700-2300 m, 30 m cells."""
    y, x = np.mgrid[0:200, 0:260] * 30.0
    z = 2000 + 300 * np.sin(x / 900) * np.cos(y / 700) + 0.04 * x
    grid = pv.StructuredGrid(x + 4.5e5, y + 4.4e6, z)
    return grid.extract_surface(algorithm="dataset_surface").triangulate()


def _scene(mesh, parallel=False, msaa=False, size=(480, 360)):
    """Unlit white surface: a pixel's ink is ``1 - value / plain value``."""
    pl = pv.Plotter(off_screen=True, window_size=size)
    actor = pl.add_mesh(mesh, color="white", lighting=False)
    if not msaa:
        pl.disable_anti_aliasing()
        pl.render_window.SetMultiSamples(0)
    pl.camera.elevation = 35
    pl.camera.azimuth = 20
    if parallel:
        pl.enable_parallel_projection()
    return pl, actor


def _ink(img: np.ndarray, plain: np.ndarray, mask: np.ndarray) -> np.ndarray:
    v = img[..., 0].astype(float)
    p = np.maximum(plain[..., 0].astype(float), 1.0)
    return np.where(mask, 1.0 - v / p, 0.0)


def _agree(gpu: np.ndarray, cpu: np.ndarray) -> tuple[float, float]:
    g, c = gpu > 0.5, cpu > 0.5
    assert g.sum() > 1000 and c.sum() > 1000
    return (
        float(ndimage.binary_dilation(c, RING)[g].mean()),
        float(ndimage.binary_dilation(g, RING)[c].mean()),
    )


@pytest.mark.parametrize("parallel", [False, True], ids=["perspective", "parallel"])
def test_point_scalar_lines_agree_with_contour_lines_of_the_capture(hills, parallel):
    pl, actor = _scene(hills, parallel=parallel)
    plain = pl.screenshot()
    opts = {"interval": 0.05, "major_interval": 0.25}
    with pv.VtkErrorCatcher(raise_errors=True, emit_warnings=True), warnings.catch_warnings():
        warnings.simplefilter("error")
        pl.gbuf.enable_contour_lines(actor, scalars="Elevation", **opts)
        img = pl.screenshot()
    gb = sg.capture(pl, scalars=["Elevation"])
    cpu = contour_lines(gb.scalars["Elevation"], mask=gb.mask, **opts)
    gpu = _ink(img, plain, gb.mask)
    near_cpu, near_gpu = _agree(gpu, cpu)
    assert near_cpu >= 0.95 and near_gpu >= 0.95, (near_cpu, near_gpu)
    # the same profile: ink summed over the picture within a few per cent
    assert abs(gpu.sum() - cpu.sum()) <= 0.05 * cpu.sum()
    pl.close()


def test_world_height_lines_in_utm_coordinates_and_a_moved_actor(utm_dem):
    pl, actor = _scene(utm_dem, size=(640, 480))
    actor.SetPosition(0.0, 0.0, 250.0)  # the model matrix: heights 250 m higher
    actor.SetScale(1.0, 1.0, 2.0)  # ... and exaggerated twice
    pl.reset_camera()
    plain = pl.screenshot()
    pl.gbuf.enable_contour_lines(actor, interval=50, major_interval=250)
    img = pl.screenshot()
    gb = sg.capture(pl)
    assert np.nanmin(gb.world[..., 2][gb.mask]) > 3600  # world heights: 2 * z + 250
    cpu = contour_lines(gb.world[..., 2], mask=gb.mask, interval=50, major_interval=250)
    near_cpu, near_gpu = _agree(_ink(img, plain, gb.mask), cpu)
    assert near_cpu >= 0.95 and near_gpu >= 0.95, (near_cpu, near_gpu)
    # orbiting: the camera terms follow every frame
    pl.camera.azimuth += 40
    pl.render()
    plain2 = pl.gbuf.disable_contour_lines().screenshot()
    pl.gbuf.enable_contour_lines(actor, interval=50, major_interval=250)
    img2 = pl.screenshot()
    gb2 = sg.capture(pl)
    cpu2 = contour_lines(gb2.world[..., 2], mask=gb2.mask, interval=50, major_interval=250)
    near_cpu, near_gpu = _agree(_ink(img2, plain2, gb2.mask), cpu2)
    assert near_cpu >= 0.95 and near_gpu >= 0.95, (near_cpu, near_gpu)
    pl.close()


def test_with_antialiasing_and_lighting_the_lines_stay_within_a_pixel(hills):
    pl = pv.Plotter(off_screen=True, window_size=(480, 360))
    actor = pl.add_mesh(hills, color="tan")  # lit, PyVista's default MSAA
    pl.camera.elevation = 35
    pl.gbuf.enable_contour_lines(actor, scalars="Elevation", interval=0.05, color=(1, 0, 0))
    img = pl.screenshot().astype(int)
    gb = sg.capture(pl, scalars=["Elevation"])
    cpu = contour_lines(gb.scalars["Elevation"], mask=gb.mask, interval=0.05)
    red = (img[..., 0] > 150) & (img[..., 1] < 90) & (img[..., 2] < 90)
    # full CPU ink is red within a pixel; red lies within a pixel of CPU ink (antialiased
    # lines: any ink)
    assert ndimage.binary_dilation(red, RING)[cpu > 0.9].mean() >= 0.95
    assert ndimage.binary_dilation(cpu > 0.25, RING)[red].mean() >= 0.95
    pl.close()


def test_parameters_are_uniforms_and_disable_restores_the_plain_frame(hills):
    pl, actor = _scene(hills)
    plain = pl.screenshot()
    sp = actor.GetShaderProperty()
    replacements = sp.GetNumberOfShaderReplacements()
    pl.gbuf.enable_contour_lines(actor, scalars="Elevation", interval=0.05)
    first = pl.screenshot()
    assert sp.GetNumberOfShaderReplacements() == replacements + 4
    uniforms = sp.GetFragmentCustomUniforms()
    listed = uniforms.GetUniformListMTime()
    pl.gbuf.enable_contour_lines(actor, scalars="Elevation", interval=0.1, width=2.0,
                                 color=(0, 0, 1))  # fmt: skip
    second = pl.screenshot()
    # new values of the same uniforms: VTK recompiles only when the list changes
    assert uniforms.GetUniformListMTime() == listed
    assert not np.array_equal(first, second)
    assert (second[..., 2] > second[..., 0] + 50).sum() > 300  # blue lines now
    assert pl.gbuf.contour_lines_enabled
    pl.gbuf.disable_contour_lines(actor)
    assert not pl.gbuf.contour_lines_enabled
    assert sp.GetNumberOfShaderReplacements() == replacements
    assert uniforms.GetNumberOfUniforms() == 0
    assert np.array_equal(pl.screenshot(), plain)
    pl.close()


def test_dense_minor_lines_fade_and_majors_stay(hills):
    """Eq. 15: seen from far away the minors crowd and fade to c_dense = 0 (the default with
    majors), the majors stay; the CPU reference fades the same pixels."""
    pl, actor = _scene(hills, size=(240, 180))
    plain = pl.screenshot()
    opts = {"interval": 0.1, "major_interval": 1.0}  # heights 0.2 - 7.5: ~2 px between minors
    pl.gbuf.enable_contour_lines(actor, scalars="Elevation", **opts)
    img = pl.screenshot()
    gb = sg.capture(pl, scalars=["Elevation"])
    gpu = _ink(img, plain, gb.mask)
    cpu = contour_lines(gb.scalars["Elevation"], mask=gb.mask, **opts)
    crowded = contour_lines(gb.scalars["Elevation"], mask=gb.mask, interval=0.1, c_dense=1.0)
    assert gpu[gb.mask].mean() < 0.6 * crowded[gb.mask].mean()  # thinned out
    assert np.abs(gpu - cpu)[gb.mask].mean() <= 0.03
    pl.close()


def test_default_actor_and_height_axis(hills):
    pl, _ = _scene(hills)
    plain = pl.screenshot()
    pl.gbuf.enable_contour_lines(interval=0.5)  # the only actor, world z
    img = pl.screenshot()
    gb = sg.capture(pl)
    cpu = contour_lines(gb.world[..., 2], mask=gb.mask, interval=0.5)
    near_cpu, near_gpu = _agree(_ink(img, plain, gb.mask), cpu)
    assert near_cpu >= 0.95 and near_gpu >= 0.95
    pl.gbuf.enable_contour_lines(interval=2.0, height=(1, 0, 0))  # x: straight lines
    img = pl.screenshot()
    cpu = contour_lines(gb.world[..., 0], mask=gb.mask, interval=2.0)
    near_cpu, near_gpu = _agree(_ink(img, plain, gb.mask), cpu)
    assert near_cpu >= 0.95 and near_gpu >= 0.95
    pl.close()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"interval": 0.0}, "interval"),
        ({"interval": float("nan")}, "interval"),
        ({"interval": 1.0, "scalars": "nope"}, "no point array 'nope'"),
        ({"interval": 1.0, "scalars": "Normals"}, "one component"),
        ({"interval": 1.0, "scalars": "Elevation", "height": "z"}, "not both"),
        ({"interval": 1.0, "height": "w"}, "height"),
        ({"interval": 1.0, "height": (0, 0, 0)}, "nonzero 3-vector"),
        ({"interval": 1.0, "width": 1e6}, "width"),
        ({"interval": 1.0, "color": (2, 0, 0)}, "color"),
        ({"interval": 1.0, "opacity": 1.5}, "opacity"),
        ({"interval": 1.0, "major_width": 2.0}, "major_width"),
    ],
)
def test_bad_arguments_are_one_clear_error(hills, kwargs, match):
    pl, actor = _scene(hills, size=(64, 48))
    with pytest.raises(InputError, match=match):
        pl.gbuf.enable_contour_lines(actor, **kwargs)
    assert not pl.gbuf.contour_lines_enabled
    assert actor.GetShaderProperty().GetNumberOfShaderReplacements() == 0
    pl.close()


def test_the_actor_must_be_a_surface_of_this_plotter(hills):
    pl = pv.Plotter(off_screen=True, window_size=(64, 48))
    pl.add_mesh(hills)
    pl.add_mesh(hills.translate((30, 0, 0)))
    with pytest.raises(InputError, match="2 mesh actors"):
        pl.gbuf.enable_contour_lines(interval=1.0)
    other = pv.Plotter(off_screen=True).add_mesh(hills)
    with pytest.raises(InputError, match="not in any of the plotter's subplots"):
        pl.gbuf.enable_contour_lines(other, interval=1.0)
    pl.close()


def test_the_parameters_are_those_of_contour_lines():
    p = contour_line_parameters(interval=20, major_interval=100, width=1.5)
    assert p["q"] == 20 and p["major_q"] == 100
    assert p["dense_at"] == 3.0  # 2 * width: minors fade where they would touch
    assert p["inv_geps"] == pytest.approx(50.0)  # g_eps = interval / 1000
    with pytest.raises(InputError, match="major_width"):
        contour_line_parameters(interval=20, major_width=3)


# Line parameters turning on each part of the fragment shader (glsl.contour_fs_impl): majors,
# a non-linear profile, a sub-pixel line (cap < 1), c_sparse, dense fading with c_dense > 0.
VARIANTS = {
    "minor only": {"interval": 0.05},
    "majors": {"interval": 0.05, "major_interval": 0.25},
    "smooth profile": {"interval": 0.05, "profile": "smooth", "width": 2.0},
    "thin": {"interval": 0.05, "width": 0.6},
    "c_sparse": {"interval": 0.05, "c_sparse": 0.2, "g_eps": 0.2},
    "c_dense": {"interval": 0.05, "major_interval": 0.25, "c_dense": 0.3, "dense_spacing": 6},
}


def test_every_shader_variant_agrees_with_contour_lines_in_one_actor(hills):
    """Each set of parameters draws what contour_lines draws; switching between them in one
    actor swaps the program (VTK's cache keeps each) with no VTK error, and only a part
    turned on or off swaps it."""
    from sciviz_gbuf.live.contours import contour_options, shader_features

    pl, actor = _scene(hills)
    plain = pl.screenshot()
    gb = sg.capture(pl, scalars=["Elevation"])
    seen = set()
    for name, opts in [*VARIANTS.items(), ("minor only again", VARIANTS["minor only"])]:
        defaults = {
            "major_interval": None, "base": 0.0, "width": 1.0, "major_width": None,
            "profile": "linear", "c_dense": None, "dense_spacing": None, "g_eps": None,
            "c_sparse": 0.0, "color": (0, 0, 0), "opacity": 1.0,
        }  # fmt: skip
        seen.add(contour_options(**{**defaults, **opts})["features"])
        with pv.VtkErrorCatcher(raise_errors=True, emit_warnings=True):
            pl.gbuf.enable_contour_lines(actor, scalars="Elevation", **opts)
            img = pl.screenshot()
        cpu = contour_lines(gb.scalars["Elevation"], mask=gb.mask, **opts)
        gpu = _ink(img, plain, gb.mask)
        strong = cpu > 0.5
        if strong.sum() > 1000:
            near_cpu, near_gpu = _agree(gpu, cpu)
            assert near_cpu >= 0.95 and near_gpu >= 0.95, (name, near_cpu, near_gpu)
        # the ink itself, pixel by pixel (8-bit screenshots, faint sparse/dense fills)
        assert np.abs(gpu - cpu)[gb.mask].mean() <= 0.03, name
        assert abs(gpu.sum() - cpu.sum()) <= 0.06 * cpu.sum(), name
    assert len(seen) == len(VARIANTS)  # each a program of its own
    assert shader_features(contour_line_parameters(interval=1.0, width=3.0)) == frozenset(
        {"beyond"}
    )  # the default: the two nearest levels of one family, nothing else
    pl.close()
