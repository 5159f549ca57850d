"""Profile / internal / crease edges, the edge map and enhancement on real captures with known
geometry: where the lines must be, where they must not be, their sign, width and robustness."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.core.camera import CameraInfo
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import (
    crease_edges,
    edge_map,
    enhance,
    id_edges,
    internal_edges,
    profile_edges,
)


def _camera(position, focal=(0, 0, 0), up=(0, 0, 1), angle=30.0, parallel=False, scale=1.0):
    cam = pv.Camera()
    cam.position, cam.focal_point, cam.up = position, focal, up
    cam.view_angle = angle
    cam.parallel_projection = parallel
    cam.parallel_scale = scale
    return cam


def project(cam: CameraInfo, pts) -> np.ndarray:
    """World points -> (row, col) pixel coordinates (row 0 on top), float."""
    pts = np.asarray(pts, dtype=np.float64)
    clip = np.c_[pts, np.ones(len(pts))] @ cam.world_to_clip().T
    ndc = clip[:, :2] / clip[:, 3:]
    w, h = cam.window_size
    return np.c_[(1 - ndc[:, 1]) / 2 * h, (ndc[:, 0] + 1) / 2 * w] - 0.5


def segment_image(shape, segments, step=0.1) -> np.ndarray:
    """Rasterise pixel-space segments ((r0, c0), (r1, c1)) into a bool image."""
    out = np.zeros(shape, bool)
    for a, b in segments:
        n = int(np.hypot(*(np.subtract(b, a))) / step) + 2
        t = np.linspace(0, 1, n)[:, None]
        p = np.rint(a + (np.subtract(b, a)) * t).astype(int)
        ok = (p[:, 0] >= 0) & (p[:, 0] < shape[0]) & (p[:, 1] >= 0) & (p[:, 1] < shape[1])
        out[p[ok, 0], p[ok, 1]] = True
    return out


def near(img: np.ndarray, px: float) -> np.ndarray:
    """Pixels within ``px`` of a True pixel of ``img``."""
    if not img.any():
        return np.zeros_like(img)
    return ndimage.distance_transform_edt(~img) <= px


# --------------------------------------------------------------------------- the cube
@pytest.fixture(scope="module")
def cube_capture():
    cube = pv.Cube(center=(0, 0, 0), x_length=2, y_length=2, z_length=2)
    cam = _camera((6, 4.5, 5), angle=35)
    gb = sg.capture(cube, window_size=(300, 260), camera=cam)
    return cube, gb


def _cube_segments(gb):
    """The 3 inner and 6 outline edges of the cube seen from the (+x, +y, +z) octant."""
    corners = {(sx, sy, sz): (sx, sy, sz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)}
    pix = {k: project(gb.camera, [v])[0] for k, v in corners.items()}
    front = (1, 1, 1)
    inner = [(pix[front], pix[(-1, 1, 1)]), (pix[front], pix[(1, -1, 1)]),
             (pix[front], pix[(1, 1, -1)])]  # fmt: skip
    ring = [(1, -1, 1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1), (1, 1, -1), (1, -1, -1)]
    outline = [(pix[ring[i]], pix[ring[(i + 1) % 6]]) for i in range(6)]
    return inner, outline


def test_cube_has_exactly_its_nine_visible_edges(cube_capture):
    _, gb = cube_capture
    inner, outline = _cube_segments(gb)
    prof = profile_edges(gb) > 0.5
    internal = internal_edges(gb)
    conv = internal > 0.5
    assert not (internal < -0.25).any()  # a cube has no concave edge
    # every pixel of ink lies on one of the 9 edges ...
    assert near(segment_image(gb.shape, outline), 1.5)[prof].all()
    assert near(segment_image(gb.shape, inner), 1.5)[conv].all()
    # ... and each of the 9 edges is drawn along its whole length (all but its end pixels)
    for segs, ink in ((inner, conv), (outline, prof)):
        for seg in segs:
            truth = segment_image(gb.shape, [seg])
            hit = near(ink, 1.5)[truth].mean()
            assert hit > 0.97, hit
    # the hidden corner's three edges are absent
    hidden = project(gb.camera, [(-1, -1, -1)])[0]
    r, c = np.rint(hidden).astype(int)
    assert not (prof | conv)[r - 3 : r + 4, c - 3 : c + 4].any()


def test_crease_is_the_unsigned_internal_edge_and_profile_is_not_a_crease(cube_capture):
    _, gb = cube_capture
    np.testing.assert_allclose(crease_edges(gb), np.abs(internal_edges(gb)), atol=1e-6)
    prof = profile_edges(gb) > 0.5
    assert (crease_edges(gb)[prof] < 0.5).mean() > 0.95


# --------------------------------------------------------------------------- smooth shapes
@pytest.mark.parametrize(
    "shape",
    [
        pytest.param(lambda: pv.Sphere(radius=1, theta_resolution=48, phi_resolution=48),
                     id="sphere"),
        pytest.param(lambda: pv.Cylinder(radius=1, height=2.5, resolution=96, capping=True,
                                          direction=(0, 0, 1)), id="cylinder"),
        pytest.param(lambda: pv.ParametricTorus(ringradius=1.0, crosssectionradius=0.35),
                     id="torus"),
    ],
)  # fmt: skip
@pytest.mark.parametrize("parallel", [False, True])
def test_smooth_tessellated_surfaces_have_no_internal_edges(shape, parallel):
    mesh = shape()
    cam = _camera((4, -3, 2.5), angle=35, parallel=parallel, scale=1.6)
    gb = sg.capture(mesh, window_size=(256, 256), camera=cam)
    internal = internal_edges(gb)
    allowed = np.zeros(gb.shape, bool)
    if mesh.n_points and isinstance(mesh, pv.PolyData) and mesh.bounds[5] == 1.25:
        # The capped cylinder's two rims are real (convex) creases: lines only there.
        t = np.linspace(0, 2 * np.pi, 721)
        for z in (-1.25, 1.25):
            p = project(gb.camera, np.c_[np.cos(t), np.sin(t), np.full_like(t, z)])
            allowed |= segment_image(gb.shape, list(itertools.pairwise(p)))
        allowed = near(allowed, 2.0)
        assert (internal[allowed] > 0.5).sum() > 100  # the rims are drawn, convex
    assert np.abs(internal[~allowed]).max() < 0.25, np.abs(internal[~allowed]).max()
    prof = profile_edges(gb)
    assert prof.max() == 1.0
    # profile ink only on the outline and occluding contours, never inside a smooth patch
    assert (prof > 0.5).sum() < 0.06 * gb.mask.sum()


def test_sphere_profile_is_the_projected_circle():
    r_s = 1.0
    cam = _camera((0, -6, 0), angle=30)
    gb = sg.capture(pv.Sphere(radius=r_s, theta_resolution=90, phi_resolution=90),
                    window_size=(240, 240), camera=cam)  # fmt: skip
    prof = profile_edges(gb) > 0.5
    rows, cols = np.nonzero(prof)
    # The silhouette of a sphere seen from distance D is a circle of angular radius asin(r/D).
    half = np.arcsin(r_s / 6.0)
    f = 120 / np.tan(np.radians(15))
    radius_px = f * np.tan(half)
    rad = np.hypot(rows + 0.5 - 120, cols + 0.5 - 120)
    assert np.abs(rad - radius_px).max() < 1.5
    assert len(rows) > 2 * np.pi * radius_px * 0.85  # closed 8-connected ring, 1 px wide
    assert len(rows) < 2 * np.pi * radius_px * 1.6


@pytest.mark.parametrize("tilt", [80.0, 85.0, 89.0])
@pytest.mark.parametrize("parallel", [False, True])
def test_grazing_planes_give_no_false_profile(tilt, parallel):
    plane = pv.Plane(i_size=40, j_size=40, i_resolution=40, j_resolution=40)  # z = 0
    a = np.radians(tilt)  # angle between the view direction and the plane normal
    eye = (0.0, -6 * np.sin(a), 6 * np.cos(a))
    cam = _camera(eye, focal=(0, 0, 0), up=(0, 1, 0) if tilt < 1 else (0, 0, 1), angle=40,
                  parallel=parallel, scale=2.0)  # fmt: skip
    gb = sg.capture(plane, window_size=(200, 160), camera=cam)
    assert gb.mask.sum() > 2000
    prof = profile_edges(gb)
    inside = np.pad(ndimage.binary_erosion(gb.mask, np.ones((3, 3))), 0)
    assert prof[inside].max() == 0.0
    assert np.abs(internal_edges(gb)).max() == 0.0
    em = edge_map(gb)
    assert em[..., 3][ndimage.binary_erosion(gb.mask, np.ones((5, 5)))].max() == 0.0


# --------------------------------------------------------------------------- sign
def test_concave_edge_is_negative_and_convex_positive():
    # An L-shaped prism: one concave edge (the inner corner), the others convex.
    ell = pv.PolyData(
        np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float),
        faces=[6, 0, 1, 2, 3, 4, 5],
    ).extrude((0, 0, 1), capping=True)
    cam = _camera((4.5, 4.0, 3.5), focal=(0.8, 0.8, 0.4), angle=35)
    gb = sg.capture(ell, window_size=(260, 260), camera=cam)
    internal = internal_edges(gb)
    concave = internal < -0.5
    assert concave.sum() > 20
    seg = project(gb.camera, [(1, 1, 0), (1, 1, 1)])
    assert near(segment_image(gb.shape, [(seg[0], seg[1])]), 1.5)[concave].all()
    seg_convex = project(gb.camera, [(2, 0, 1), (2, 1, 1)])  # top edge of the +x face
    truth = segment_image(gb.shape, [(seg_convex[0], seg_convex[1])])
    assert (internal[near(truth, 1.0)] > 0.5).any()
    assert not (internal[near(truth, 1.5)] < -0.25).any()


# --------------------------------------------------------------------------- width, AA
def _box_front():
    """A box seen face-on in parallel projection: its left outline is a vertical line."""
    return _camera((0, -5, 0), up=(0, 0, 1), parallel=True, scale=1.5)


@pytest.mark.parametrize(("width", "supersample"), [(1, 1), (3, 1), (2, 3), (1, 4), (1.5, 4)])
def test_line_width_in_output_pixels(width, supersample):
    box = pv.Box(bounds=(-1, 1, -1, 1, -1, 1))
    cam = _box_front()
    gb = sg.capture(box, window_size=(120, 100), camera=cam, supersample=supersample)
    prof = profile_edges(gb, width=width)
    assert prof.shape == gb.output_shape
    rows = slice(35, 65)
    left = prof[rows, :60].sum(axis=1)  # ink across the left outline, per row
    assert np.abs(left - width).max() <= 0.5, left
    if supersample > 1:
        assert ((prof > 0.05) & (prof < 0.95)).any()  # antialiased, not bilevel


def test_enhance_and_edge_map_compose_as_in_2003(cube_capture):
    _, gb = cube_capture
    for op in ("diagonal", "c1"):
        em = edge_map(gb, operator=op)
        assert em.shape == (*gb.output_shape, 4) and em.dtype == np.float32
        assert em.min() >= 0 and em.max() <= 1
        inner, outline = _cube_segments(gb)
        on_inner = near(segment_image(gb.shape, inner), 0.5) & ~near(
            segment_image(gb.shape, outline), 4
        )
        assert em[..., 0][on_inner].mean() > 0.5
        assert em[..., 3][near(segment_image(gb.shape, outline), 0.5)].mean() > 0.5
        assert em[..., 3][~near(segment_image(gb.shape, outline), 3)].max() < 0.05
    shade = sg.filters.lambert(gb.normal, mask=gb.mask, ambient=0.2)
    out = enhance(shade, em, inner_color=(1, 0, 0), profile_color=(0, 0, 1))
    assert out.shape == (*gb.output_shape, 3) and 0 <= out.min() and out.max() <= 1
    full_prof = em[..., 3] == 1
    np.testing.assert_allclose(out[full_prof], [[0, 0, 1]] * full_prof.sum(), atol=1e-6)
    full_inner = (em[..., 0] == 1) & (em[..., 3] == 0)
    np.testing.assert_allclose(out[full_inner], [[1, 0, 0]] * full_inner.sum(), atol=1e-6)
    no_edge = (em[..., 0] == 0) & (em[..., 3] == 0) & gb.mask
    np.testing.assert_allclose(out[no_edge][:, 0], shade[no_edge], atol=1e-6)


def test_id_edges_outline_objects_and_cells(cube_capture):
    _, gb = cube_capture
    objs = id_edges(gb, ids="object") > 0.5
    np.testing.assert_array_equal(objs, profile_edges(gb) == 1.0)  # one object: its outline
    cells = id_edges(gb, ids="cell") > 0.5
    assert (cells & ~objs).sum() > 0  # face boundaries (each face is one cell here)
    two = sg.capture([pv.Sphere(center=(-0.6, 0, 0)), pv.Sphere(center=(0.6, 0, 0))],
                     window_size=(160, 120), camera=_camera((0, -4, 0), angle=40))  # fmt: skip
    e = id_edges(two) > 0.5
    mid_col = e[:, 75:85].any(axis=0).sum()
    assert mid_col > 0  # where the spheres meet


def test_edges_rerun_on_a_loaded_gbuffer(cube_capture, tmp_path):
    _, gb = cube_capture
    gb.save(tmp_path / "c.npz")
    back = sg.GBuffer.load(tmp_path / "c.npz")
    np.testing.assert_array_equal(profile_edges(back), profile_edges(gb))
    np.testing.assert_array_equal(internal_edges(back), internal_edges(gb))
    np.testing.assert_array_equal(edge_map(back, operator="c1"), edge_map(gb, operator="c1"))


def test_bad_parameters_name_themselves(cube_capture):
    _, gb = cube_capture
    with pytest.raises(InputError, match="gb"):
        profile_edges(np.zeros((4, 4)))
    with pytest.raises(InputError, match="crease_angle"):
        internal_edges(gb, crease_angle=0)
    with pytest.raises(InputError, match="depth_jump"):
        profile_edges(gb, depth_jump=-1)
    with pytest.raises(InputError, match="width"):
        crease_edges(gb, width=0.5)
    with pytest.raises(InputError, match="operator"):
        edge_map(gb, operator="sobel")
    with pytest.raises(InputError, match="ids"):
        id_edges(gb, ids="patch")
    em = edge_map(gb)
    with pytest.raises(InputError, match="edge_map"):
        enhance(np.zeros((3, 3, 3)), em)
    with pytest.raises(InputError, match="inner_color"):
        enhance(np.zeros(gb.output_shape), em, inner_color=(2, 0, 0))


# --------------------------------------------------------------------------- odd buffers
@pytest.fixture(scope="module")
def tiny_gb():
    return sg.capture(pv.Sphere(), window_size=(7, 5), camera=_camera((0, -3, 0)))


_vals = st.floats(width=32, allow_nan=True, allow_infinity=True)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow,
          HealthCheck.function_scoped_fixture])  # fmt: skip
@given(data=st.data())
def test_odd_gbuffer_contents_never_crash_or_leave_range(tiny_gb, data):
    h, w = tiny_gb.shape
    gb = tiny_gb
    sz = data.draw(hnp.arrays(np.float32, (h, w), elements=_vals))
    depth = data.draw(hnp.arrays(np.float32, (h, w), elements=_vals))
    normal = data.draw(hnp.arrays(np.float32, (h, w, 3), elements=_vals))
    mask = data.draw(hnp.arrays(np.bool_, (h, w)))
    odd = sg.GBuffer(
        depth=depth, sz=sz, normal=normal, world=gb.world, object_id=gb.object_id,
        cell_id=gb.cell_id, mask=mask, camera=gb.camera,
    )  # fmt: skip
    prof = profile_edges(odd)
    assert prof.shape == (h, w) and np.isfinite(prof).all() and 0 <= prof.min() <= prof.max() <= 1
    internal = internal_edges(odd)
    assert np.isfinite(internal).all() and np.abs(internal).max() <= 1
    for op in ("diagonal", "c1"):
        em = edge_map(odd, operator=op)
        assert np.isfinite(em).all() and em.min() >= 0 and em.max() <= 1
    assert np.isfinite(id_edges(odd)).all()
