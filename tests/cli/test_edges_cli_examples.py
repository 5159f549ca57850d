"""The edge recipes behind ``sciviz-gbuf edges``, the Fig. 3 / Fig. 7 examples and the demo."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf import InputError
from sciviz_gbuf import filters as F
from sciviz_gbuf.datasets import load_nut
from sciviz_gbuf.recipes import (
    CAPTIONS,
    STYLES,
    fig3_panels,
    fig7_edge_map,
    fig7_panels,
    framed_camera,
    illustrate,
    nut_camera,
    oblique_camera,
    shade_image,
    signed_to_grey,
)
from sciviz_gbuf.recipes.saito1990 import sz_with_background
from tests.helpers.geometry import camera_basis

SIZE = (160, 120)


@pytest.fixture(scope="module")
def box():
    """A box in an oblique view: 3 faces, convex edges between them, a silhouette around."""
    mesh = pv.Box(bounds=(-1.0, 1.0, -0.6, 0.6, -0.4, 0.4)).triangulate()
    camera = oblique_camera(mesh.bounds, up_axis="z", elevation=35, azimuth=-30)
    return sg.capture(mesh, window_size=SIZE, camera=camera, supersample=2)


@pytest.fixture(scope="module")
def nut():
    mesh = load_nut()
    return sg.capture(mesh, window_size=SIZE, camera=nut_camera(mesh.bounds))


# ---------------------------------------------------------------------------- framing
@pytest.mark.parametrize("aspect", [4 / 3, 0.5])
def test_framed_camera_keeps_every_corner_in_view(aspect):
    bounds = (10.0, 14.0, -3.0, 5.0, 100.0, 101.0)
    pos, foc, up = framed_camera(bounds, (1.0, -2.0, 1.5), (0.0, 0.0, 1.0), aspect=aspect)
    d = np.subtract(pos, foc)
    assert np.allclose(np.cross(d, (1.0, -2.0, 1.5)), 0.0, atol=1e-9)  # along the direction
    view, right, upv = camera_basis(SimpleNamespace(position=pos, focal_point=foc, view_up=up))
    corners = np.array(np.meshgrid(*np.reshape(bounds, (3, 2)))).reshape(3, -1).T - pos
    depth = corners @ view
    tan_v = np.tan(np.radians(15.0))
    x = (corners @ right) / (depth * tan_v * aspect)
    y = (corners @ upv) / (depth * tan_v)
    # The one framing rule: the projected box centred, spanning 1 - margin = 85 % of the
    # limiting image dimension (so every corner is in view).
    assert max(np.ptp(x), np.ptp(y)) / 2 == pytest.approx(0.85, abs=2e-3)
    assert abs(x.max() + x.min()) / 2 < 2e-3 and abs(y.max() + y.min()) / 2 < 2e-3
    assert max(np.abs(x).max(), np.abs(y).max()) < 0.86


def test_oblique_camera_elevation_and_axis():
    bounds = (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0)
    pos, foc, up = oblique_camera(bounds, up_axis="y", elevation=30, azimuth=0)
    d = np.subtract(pos, foc)
    assert up == (0.0, 1.0, 0.0)
    assert np.degrees(np.arcsin(d[1] / np.linalg.norm(d))) == pytest.approx(30.0)
    assert d[0] == pytest.approx(0.0, abs=1e-12) and d[2] > 0  # azimuth 0: from the z side
    pos, _, up = oblique_camera(bounds, up_axis="z", elevation=90)
    assert pos[:2] == pytest.approx((0.0, 0.0)) and up == pytest.approx((-1.0, 0.0, 0.0))


@pytest.mark.parametrize(
    ("call", "word"),
    [
        (lambda: framed_camera((0, 1, 0, 1, 0, 1), (0, 0, 1), (0, 0, 2)), "view_up"),
        (lambda: framed_camera((0, 1, 0, 1, 0, 1), (0, 0, 0), (0, 0, 1)), "direction"),
        (lambda: framed_camera((0, 1, 0, 1, 0, 1), (1, 0, 0), (0, 0, 1), margin=1), "margin"),
        (lambda: oblique_camera((0, 1, 0, 1, 0, 1), up_axis="w"), "up_axis"),
        (lambda: oblique_camera((0, 1, 0, 1, 0, 1), elevation=0), "elevation"),
    ],
)
def test_framing_rejects(call, word):
    with pytest.raises(InputError, match=word):
        call()


# ---------------------------------------------------------------------------- illustration
def test_signed_to_grey():
    v = np.array([[-3.0, -0.5, 0.0, 0.5, 3.0, np.nan]])
    np.testing.assert_allclose(signed_to_grey(v), [[0.0, 0.25, 0.5, 0.75, 1.0, 0.5]])
    np.testing.assert_allclose(signed_to_grey(v, scale=2.0)[0, 1], 0.375)
    with pytest.raises(InputError, match="scale"):
        signed_to_grey(v, scale=0.0)


def test_shade_image_is_paper_outside_and_antialiased(box):
    shade = shade_image(box)
    assert shade.shape == box.output_shape
    cover = box.downsample(box.mask.astype(np.float32))
    assert (shade[cover == 0] == 1.0).all()
    assert shade[cover == 1].max() <= 0.85 + 1e-6  # below white: room for edge highlights
    partial = (cover > 0) & (cover < 1)
    assert partial.any() and (shade[partial] > shade[cover == 1].min()).all()


@pytest.mark.parametrize("style", list(STYLES))
def test_illustrate_styles(box, style):
    img = illustrate(box, style=style)
    assert img.dtype == np.float32
    assert img.shape == (*box.output_shape, 4 if style == "edgemap" else 3)
    assert np.isfinite(img).all() and img.min() >= 0.0 and img.max() <= 1.0


def test_fig7_style_draws_convex_white_and_profiles_black(box):
    inner = F.internal_edges(box)
    prof = F.profile_edges(box)
    img = illustrate(box, style="fig7").mean(axis=2)
    shade = shade_image(box)
    convex = (inner > 0.99) & (prof == 0)
    assert convex.sum() > 50  # the box's three convex edges
    np.testing.assert_allclose(img[convex], 1.0, atol=1e-6)
    np.testing.assert_allclose(img[prof > 0.99], 0.0, atol=1e-6)
    plain = (inner == 0) & (prof == 0)
    np.testing.assert_allclose(img[plain], shade[plain], atol=1e-6)
    # the all-black variant draws the same convex edges black
    emap = fig7_edge_map(box, black_only=True)
    assert (emap[..., :3] == 0).all() and (emap[..., 3][convex] > 0.99).all()


def test_lines_style_is_ink_on_paper(box):
    img = illustrate(box, style="lines")
    ink = np.maximum(F.profile_edges(box), F.crease_edges(box))
    np.testing.assert_allclose(img[..., 0], 1.0 - ink, atol=1e-6)
    assert (img[..., 0] == img[..., 2]).all()


def test_illustrate_rejects(box):
    with pytest.raises(InputError, match="style"):
        illustrate(box, style="sketch")
    with pytest.raises(InputError, match="operator"):
        illustrate(box, operator="sobel")
    with pytest.raises(InputError, match="width"):
        illustrate(box, style="lines", width=0.5)


# ---------------------------------------------------------------------------- Saito 1990
def test_sz_background_is_far(nut):
    sz = sz_with_background(nut)
    assert (sz[~nut.mask] == 0).all()
    np.testing.assert_array_equal(sz[nut.mask], nut.sz[nut.mask])


def test_sz_background_parallel_is_farther_than_everything():
    mesh = pv.Sphere()
    g = sg.capture(mesh, window_size=(40, 30), camera="xz", parallel_projection=True)
    sz = sz_with_background(g)
    assert sz[~g.mask].max() < sz[g.mask].min() - 100.0
    assert np.isfinite(sz).all()


def test_fig3_panels(nut):
    panels = fig3_panels(nut)
    keys = [k for k, _, _ in panels]
    assert keys == [
        "depth",
        "gradient",
        "second_order",
        "profile",
        "internal",
        "profile_edges",
        "internal_edges",
    ]
    assert set(keys) <= set(CAPTIONS)
    for _, _, img in panels:
        assert img.shape == nut.output_shape
        assert np.isfinite(img).all() and img.min() >= 0 and img.max() <= 1
    img = dict((k, v) for k, _, v in panels)
    # the literal profile image outlines the nut (the silhouette against the far background)
    outline = nut.mask & ~np.pad(nut.mask, 1)[2:, 1:-1]  # covered pixels with background below
    assert np.median(img["profile"][outline]) < 0.2
    assert np.median(img["profile"][~nut.mask]) == 1.0  # white paper
    # the internal edge image is mid grey on flat faces and has convex (white) edges
    assert np.median(img["internal"]) == pytest.approx(0.5)
    assert (img["internal"] > 0.9).sum() > 20


def test_fig7_panels_with_supersampling():
    mesh = load_nut()
    g = sg.capture(mesh, window_size=SIZE, camera=nut_camera(mesh.bounds), supersample=2)
    panels = fig7_panels(g, width=1.5)
    assert [k for k, _, _ in panels] == [
        "a_shaded",
        "b_depth",
        "c_edges",
        "d_enhanced",
        "c2_edges",
        "d2_enhanced",
        "edgemap_diagonal",
        "edgemap_c1",
    ]
    for key, _, img in panels:
        assert key in CAPTIONS
        assert img.shape[:2] == (SIZE[1], SIZE[0])
        assert np.isfinite(img).all() and img.min() >= 0 and img.max() <= 1
