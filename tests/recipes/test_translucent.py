"""Transparency from multi-layer G-buffers (issue 24 item 4): ``compose.layered`` and the
translucent-skin CT view, on a synthetic head (a soft-tissue ball around a bone ball) whose
picture is known in closed form, and on the shared Philips phantom."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.compose import LAYERED_LIGHT, layered
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.recipes.medical import BONE, SKIN, SKIN_OPACITY

R_SKIN, R_BONE = 40.0, 20.0


@pytest.fixture(scope="module")
def head():
    """1 mm voxels: 0 HU inside 40 mm, 1000 HU inside 20 mm, air (-1000) outside."""
    n = 101
    g = pv.ImageData(dimensions=(n, n, n), spacing=(1.0, 1.0, 1.0), origin=(-50.0, -50.0, -50.0))
    r = np.linalg.norm(np.asarray(g.points), axis=1)
    hu = np.where(r <= R_BONE, 1000.0, np.where(r <= R_SKIN, 0.0, -1000.0))
    # a smooth step (1 mm): the isosurfaces sit at their radii
    hu = np.interp(r, [R_BONE - 1, R_BONE + 1, R_SKIN - 1, R_SKIN + 1], [1000, 0, 0, -1000])
    g.point_data["HU"] = hu.astype(np.float32)
    return g


def _shade(n_eye: np.ndarray, ambient: float = 0.3) -> float:
    light = np.asarray(LAYERED_LIGHT) / np.linalg.norm(LAYERED_LIGHT)
    return ambient + (1 - ambient) * max(0.0, float(n_eye @ light))


def test_translucent_skin_over_bone_is_the_closed_form_mix(head):
    size = 300
    img = sg.ct_enhance(head, translucent="skin", inner="bone", window_size=(size, size),
                        supersample=2, background=(1.0, 1.0, 1.0))  # fmt: skip
    assert img.shape == (size, size, 4) and (img[..., 3] == 255).all()
    rgb = img[..., :3].astype(np.float64) / 255
    c = (size - 1) / 2
    # the head fills FILL of the picture: the skin's radius in pixels
    yy, xx = np.mgrid[:size, :size]
    rad = np.hypot(xx - c, yy - c)
    ink = rgb.mean(axis=2) < 0.5
    # the skin's outline, then the bone's outline seen through it, at radius ratio 1/2
    profile = np.array([ink[(rad >= r0) & (rad < r0 + 1)].mean() for r0 in range(int(c))])
    rings = np.flatnonzero(profile > 0.5)
    r_skin = int(rings.max())
    assert 0.75 * c < r_skin < 0.95 * c, rings
    inner_rings = rings[(rings > 0.3 * r_skin) & (rings < 0.7 * r_skin)]
    # the bone's outline (and its dark grazing rim just inside) ends at half the skin's radius
    assert len(inner_rings) and abs(inner_rings.max() - r_skin / 2) <= 2.0, rings
    assert not ((rings > 2) & (rings < 0.3 * r_skin)).any()  # nothing else: no stray rings
    # the centre: skin (facing the eye) at SKIN_OPACITY over bone, both lit alike
    s = _shade(np.array([0.0, 0.0, 1.0]))
    expect = s * (SKIN_OPACITY * np.asarray(SKIN) + (1 - SKIN_OPACITY) * np.asarray(BONE))
    np.testing.assert_allclose(rgb[int(c) - 2 : int(c) + 3, int(c) - 2 : int(c) + 3].mean((0, 1)),
                               expect, atol=0.03)  # fmt: skip
    # between the outlines: the skin alone over white paper (its far side is not drawn again)
    ring = (rad > 0.62 * r_skin) & (rad < 0.7 * r_skin) & (np.abs(yy - c) < 4) & (xx > c)
    x = (xx[ring] - c) / r_skin  # on the horizontal line through the centre: n = (x, 0, z)
    for px, col in zip(x[::3], rgb[ring][::3], strict=False):
        n = np.array([px, 0.0, np.sqrt(1 - px * px)])
        want = SKIN_OPACITY * _shade(n) * np.asarray(SKIN) + (1 - SKIN_OPACITY)
        np.testing.assert_allclose(col, want, atol=0.05)


def test_layered_opaque_front_is_the_front_alone():
    outer = pv.Sphere(radius=2.0, theta_resolution=80, phi_resolution=80)
    inner = pv.Sphere(radius=1.0, theta_resolution=80, phi_resolution=80)
    cam = [(0, -10, 0), (0, 0, 0), (0, 0, 1)]
    two = sg.capture([outer, inner], window_size=(120, 120), camera=cam, layers=3)
    one = sg.capture([outer], window_size=(120, 120), camera=cam, layers=1)
    a = layered(two, opacity=1.0)
    b = layered(one, opacity=1.0)
    np.testing.assert_allclose(a, b, atol=2e-3)  # the ball inside never shows
    see = layered(two, opacity=(0.5, 1.0), colors=((1, 0, 0), (0, 0, 1)))
    centre = see[55:65, 55:65, :3].mean((0, 1))
    assert centre[2] > 0.2 and centre[0] > 0.2  # red film over the blue ball
    yy, xx = np.mgrid[:120, :120]
    rad = np.hypot(xx - 59.5, yy - 59.5)
    film = (see[..., 0] > 0.3) & (see[..., 3] > 0.99)
    r_ball = rad[see[..., 2] > 0.2].max()
    assert (see[..., 2][film & (rad > r_ball + 3)] < 0.05).all()  # no blue beyond the ball
    with pytest.raises(InputError, match="opacity"):
        layered(two, opacity=2.0)


def test_translucent_needs_a_source_or_surfaces():
    with pytest.raises(InputError, match="translucent"):
        sg.recipes.medical.ct_translucent(None, translucent="skin", inner="bone")


def test_philips_phantom_translucent_view(shared_data):
    """The shared Philips phantom (a skull in soft-tissue-equivalent plastic, in its holder):
    a picture with both the skin's and the bone's colours, and no empty frame."""
    img = sg.ct_enhance(shared_data / "ct" / "dcm_qa_ct_Philips_phantom_5mm",
                        translucent="skin", inner="bone", window_size=(256, 256),
                        background=(1.0, 1.0, 1.0))  # fmt: skip
    rgb = img[..., :3].astype(np.float64) / 255
    drawn = rgb.mean(axis=2) < 0.97
    assert 0.2 < drawn.mean() < 0.9
    assert (img[..., 3] == 255).all()
