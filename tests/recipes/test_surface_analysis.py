"""Reflection lines, highlight lines, isophotes and the surface-analysis recipe (1990 §4.5).

The sphere checks compare with the analytic sphere; the seam checks measure, on the rendered
G-buffer, how the direction of the reflection lines changes across a C2, a C1-not-C2 and a G0
join of two bicubic patches (the acceptance test of CAD zebra tools).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import pyvista as pv
from hypothesis import given, settings
from hypothesis import strategies as st

import sciviz_gbuf as sg
from sciviz_gbuf.cli import main
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters.reflection import (
    highlight_lines,
    isophotes,
    reflection_angle,
    reflection_lines,
)
from sciviz_gbuf.readers.patches import read_patches
from sciviz_gbuf.recipes.surface import (
    MODES,
    seam_patches,
    surface_analysis,
    surface_gbuffer,
    surface_layers,
)
from tests.helpers.geometry import rays_by_hand
from tests.helpers.paths import SHARED_DATA

SPHERE_BPT = SHARED_DATA / "patches" / "sphere.bpt"
TEAPOT_BPT = SHARED_DATA / "patches" / "teapot.bpt"
needs_patches = pytest.mark.skipif(not SPHERE_BPT.is_file(), reason="shared patch data absent")


def analytic_sphere(cam):
    """Per output pixel: hit point on the unit sphere at the origin (NaN on a miss) and the
    unit view ray, from a hand-made pinhole camera."""
    origin, direction = rays_by_hand(cam)
    b = np.sum(origin * direction, axis=-1)
    c = np.sum(origin * origin, axis=-1) - 1.0
    disc = b * b - c
    t = -b - np.sqrt(np.where(disc >= 0, disc, np.nan))
    return origin + t[..., None] * direction, direction


def theta_of(r, axis):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    w = np.eye(3)[int(np.argmin(np.abs(a)))]
    e1 = w - (w @ a) * a
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    return np.arctan2(r @ e2, r @ e1)


def wrapped_gradient(theta):
    gy = np.gradient(np.unwrap(theta, axis=0), axis=0)
    gx = np.gradient(np.unwrap(theta, axis=1), axis=1)
    return np.hypot(gx, gy)


@pytest.fixture(scope="module")
def sphere_gb():
    mesh = read_patches(SPHERE_BPT).to_mesh(resolution=48) if SPHERE_BPT.is_file() else None
    if mesh is None:
        pytest.skip("shared patch data absent")
    cam = ((0.4, -3.0, 2.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    return sg.capture(mesh, window_size=(240, 240), camera=cam, supersample=2)


# --------------------------------------------------------------------- the analytic sphere


@needs_patches
@pytest.mark.parametrize("axis", [(0, 0, 1), (1, 0.3, 0.2)])
def test_reflection_lines_on_the_sphere_patches_are_the_analytic_curves(sphere_gb, axis):
    gb = sphere_gb
    stripes = 12
    ink = reflection_lines(gb, axis=axis, stripes=stripes, width=1.0)
    # The analytic pattern at the output pixels (the camera at output resolution).
    cam = gb.camera
    out_cam = dataclasses.replace(cam, window_size=(240, 240))
    hit, d = analytic_sphere(out_cam)
    n = hit  # unit sphere: the normal is the point
    r = d - 2 * np.sum(d * n, axis=-1, keepdims=True) * n
    theta = theta_of(r, axis)
    period = 2 * np.pi / stripes
    off = np.abs((theta + period / 2) % period - period / 2)  # to the nearest light, radians
    g = wrapped_gradient(theta)
    dist_px = off / g
    # Away from the silhouette and the pattern's singular points (where lines crowd).
    rho = np.linalg.norm(np.cross(hit, -d), axis=-1)  # distance from the view axis, < 1 inside
    calm = np.isfinite(dist_px) & (rho < 0.9) & (period / g > 6.0)
    drawn = (ink > 0.5) & calm
    assert drawn.sum() > 200
    assert np.all(dist_px[drawn] <= 1.0)
    # And no line is missing: wherever a light's curve passes within 0.25 px, ink is there.
    on_curve = calm & (dist_px < 0.25)
    assert on_curve.sum() > 100
    assert np.all(ink[on_curve] > 0.4)


@needs_patches
def test_isophotes_of_a_headlit_sphere_are_circles(sphere_gb):
    gb = sphere_gb
    ink = isophotes(gb, light=(0, 0, 1), interval=15.0, width=1.0)  # eye-space headlight
    cam = dataclasses.replace(gb.camera, window_size=(240, 240))
    hit, _ = analytic_sphere(cam)
    # N . L with L the eye's view axis (towards the viewer), per pixel, analytically.
    view_axis = -np.asarray(cam.direction)
    angle = np.degrees(np.arccos(np.clip(hit @ view_axis, -1, 1)))
    off = np.abs((angle + 7.5) % 15.0 - 7.5)
    g = np.hypot(*np.gradient(angle))
    calm = np.isfinite(off / g) & (angle < 70) & (angle > 10)
    drawn = (ink > 0.5) & calm
    assert drawn.sum() > 100
    assert np.all((off / g)[drawn] <= 1.0)


@needs_patches
def test_highlight_lines_do_not_depend_on_the_eye(sphere_gb):
    mesh = read_patches(SPHERE_BPT).to_mesh(resolution=32)
    views = [((0.4, -3.0, 2.0), (0, 0, 0), (0, 0, 1)), ((3.0, 1.0, 1.0), (0, 0, 0), (0, 0, 1))]
    gbs = [sg.capture(mesh, window_size=(120, 120), camera=v) for v in views]
    for mode, same in (("highlight", True), ("reflection", False)):
        errors = []
        for gb in gbs:
            theta = reflection_angle(gb, axis=(0, 0.3, 1), mode=mode)
            p = gb.world[gb.mask].astype(np.float64)
            expected = theta_of(p / np.linalg.norm(p, axis=1)[:, None], (0, 0.3, 1))
            diff = np.angle(np.exp(1j * (theta[gb.mask] - expected)))
            errors.append(np.percentile(np.abs(diff), 99))
        # the normal of the tessellated patches is the analytic one to well below a degree
        assert (max(errors) < np.radians(0.5)) == same


# ------------------------------------------------------------------------------ the seams


def seam_gbuffer(continuity: str):
    view = ((1.0, -1.2, 4.0), (1.0, 0.75, 0.6), (0.0, 1.0, 0.0))
    return surface_gbuffer(
        seam_patches(continuity), view=view, resolution=64, window_size=(320, 240), supersample=1
    )


def side_gradient(theta, ys, xs, y0, x0):
    """theta ~ quadratic in (x, y) fitted over the pixels of one side, unwrapped around its
    median; returns (theta, d theta/dx, d theta/dy) extrapolated to the seam point (x0, y0)."""
    t = theta[ys, xs].astype(np.float64)
    t = np.median(t) + np.angle(np.exp(1j * (t - np.median(t))))
    x, y = xs - x0, ys - y0
    basis = np.column_stack([np.ones_like(t), x, y, x * x, x * y, y * y])
    coef, *_ = np.linalg.lstsq(basis, t, rcond=None)
    return coef[:3]


def seam_measure(gb, axis=(1.0, 0.4, 0.0)):
    """Along the seam, the angle between the reflection lines' directions just left and just
    right of it (degrees), and the jump of theta across it (radians), at sample points."""
    from scipy import ndimage

    theta = reflection_angle(gb, axis=axis)
    pid = np.where(gb.mask, gb.scalars["patch_id"], -1)
    left, right = pid == 0, pid == 1
    # seam pixels: left pixels with a right neighbour
    seam = left & ndimage.binary_dilation(right)
    dl = ndimage.distance_transform_edt(~seam)
    ys, xs = np.nonzero(seam)
    keep = (ys > ys.min() + 20) & (ys < ys.max() - 20)
    turns, jumps = [], []
    for y0, x0 in list(zip(ys[keep], xs[keep], strict=True))[::6]:
        box = (slice(max(y0 - 10, 0), y0 + 11), slice(max(x0 - 10, 0), x0 + 11))
        sides = []
        for side in (left, right):
            m = np.zeros_like(side)
            m[box] = side[box] & (dl[box] <= 9)
            yy, xx = np.nonzero(m)
            if len(yy) < 40:
                break
            sides.append(side_gradient(theta, yy, xx, y0 + 0.5, x0 + 0.5))
        if len(sides) < 2:
            continue
        (t0, b0, c0), (t1, b1, c1) = sides
        # line direction = perpendicular to the gradient; compare as undirected lines
        cosang = abs(b0 * b1 + c0 * c1) / (np.hypot(b0, c0) * np.hypot(b1, c1))
        turns.append(np.degrees(np.arccos(min(cosang, 1.0))))
        jumps.append(abs(np.angle(np.exp(1j * (t0 - t1)))))
    return np.array(turns), np.array(jumps)


@pytest.fixture(scope="module")
def seams():
    return {c: seam_measure(seam_gbuffer(c)) for c in ("C2", "C1", "G0")}


def test_reflection_lines_turn_at_a_c1_seam_and_not_at_a_c2_seam(seams):
    c2_turn, c2_jump = seams["C2"]
    c1_turn, c1_jump = seams["C1"]
    assert len(c2_turn) > 10 and len(c1_turn) > 10
    # C2: no turn beyond noise; C1 (curvature jumps): a clear turn all along the seam.
    # (measured: C2 0.1 deg, C1 25 deg)
    assert np.median(c2_turn) < 1.0 and np.percentile(c2_turn, 90) < 2.0
    assert np.percentile(c1_turn, 10) > 10.0
    assert np.median(c1_turn) > 5 * np.median(c2_turn)
    # both keep the lines connected (normals continuous): no jump of theta across the seam
    assert np.median(c1_jump) < 0.01 and np.median(c2_jump) < 0.01


def test_reflection_lines_break_at_a_g0_crease(seams):
    _, g0_jump = seams["G0"]
    _, c1_jump = seams["C1"]
    assert len(g0_jump) > 10
    # the normal jumps at the crease, so theta (and every line) is cut and displaced
    assert np.median(g0_jump) > 0.2
    assert np.median(g0_jump) > 10 * np.median(c1_jump)


def test_stripe_images_show_the_seams():
    """The rendered ink (not only theta) differs between the C1 and the C2 surface near the
    seam, and is identical away from it (the left patch is the same in both)."""
    c2, c1 = seam_gbuffer("C2"), seam_gbuffer("C1")
    z2 = reflection_lines(c2, axis=(1, 0.4, 0), stripes=24, style="stripes")
    z1 = reflection_lines(c1, axis=(1, 0.4, 0), stripes=24, style="stripes")
    from scipy import ndimage

    right = (c2.scalars["patch_id"] == 1) & (c1.scalars["patch_id"] == 1)
    left = (c2.scalars["patch_id"] == 0) & (c1.scalars["patch_id"] == 0) & c1.mask & c2.mask
    # (the antialiasing of a stripe edge looks one pixel across the seam)
    left &= ~ndimage.binary_dilation(right, iterations=2)
    assert np.abs(z2 - z1)[left].max() < 0.05
    assert np.abs(z2 - z1)[right].mean() > 0.2


# -------------------------------------------------------------------------- the filters


def test_stripes_cover_the_duty_fraction_and_are_antialiased(sphere_gb):
    gb = sphere_gb
    for duty in (0.3, 0.5):
        ink = reflection_lines(gb, style="stripes", stripes=12, duty=duty)
        inner = gb.downsample(gb.mask.astype(np.float32)) == 1
        assert abs(ink[inner].mean() - duty) < 0.05
        partial = (ink[inner] > 0.05) & (ink[inner] < 0.95)
        assert 0.01 < partial.mean() < 0.3  # soft edges, not a soft picture


def test_phase_turns_the_lights(sphere_gb):
    a = reflection_lines(sphere_gb, stripes=12, phase=0.0)
    b = reflection_lines(sphere_gb, stripes=12, phase=30.0)  # a full period: the same lines
    c = reflection_lines(sphere_gb, stripes=12, phase=15.0)
    assert np.abs(a - b).max() < 1e-3
    assert np.abs(a - c).mean() > 0.05


def test_highlight_lines_is_the_highlight_mode(sphere_gb):
    assert np.array_equal(
        highlight_lines(sphere_gb, axis=(1, 0, 0)),
        reflection_lines(sphere_gb, axis=(1, 0, 0), mode="highlight"),
    )


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"axis": (0, 0, 0)}, "axis"),
        ({"axis": (1, 2)}, "axis"),
        ({"stripes": 0}, "stripes"),
        ({"width": -1}, "width"),
        ({"style": "checker"}, "style"),
        ({"mode": "mirror"}, "mode"),
        ({"duty": 1.0}, "duty"),
    ],
)
def test_reflection_lines_reject(sphere_gb, kwargs, word):
    with pytest.raises(InputError, match=word):
        reflection_lines(sphere_gb, **kwargs)


def test_filters_need_a_gbuffer_and_isophote_levels(sphere_gb):
    with pytest.raises(InputError, match="GBuffer"):
        reflection_lines(np.zeros((4, 4)))
    with pytest.raises(InputError, match="levels"):
        isophotes(sphere_gb, levels=[2.0])
    with pytest.raises(InputError, match="frame"):
        isophotes(sphere_gb, frame="screen")
    lv = isophotes(sphere_gb, levels=[0.5, 0.9], light=(0, 0, 1), frame="world")
    assert lv.shape == sphere_gb.output_shape and lv.max() > 0.5


@settings(max_examples=30, deadline=None)
@given(
    axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda a: np.linalg.norm(a) > 1e-3),
    stripes=st.floats(1, 64),
    width=st.floats(0.2, 6),
    style=st.sampled_from(["lines", "stripes"]),
    mode=st.sampled_from(["reflection", "highlight"]),
)
def test_reflection_lines_always_in_range(sphere_gb, axis, stripes, width, style, mode):
    opts = {"axis": axis, "stripes": stripes, "width": width, "style": style, "mode": mode}
    ink = reflection_lines(sphere_gb, **opts)
    assert ink.dtype == np.float32 and ink.shape == sphere_gb.output_shape
    assert np.isfinite(ink).all() and ink.min() >= 0 and ink.max() <= 1
    bg = sphere_gb.downsample(sphere_gb.mask.astype(np.float32)) == 0
    assert (ink[bg] == 0).all()


# --------------------------------------------------------------------------- the recipe


@pytest.fixture(scope="module")
def c1_gb():
    return seam_gbuffer("C1")


@pytest.mark.parametrize("mode", MODES)
def test_surface_analysis_modes(c1_gb, mode):
    img = surface_analysis(c1_gb, mode=mode, curvature="mean")
    again = surface_analysis(c1_gb, mode=mode, curvature="mean")
    assert np.array_equal(img, again)
    assert img.dtype == np.uint8 and img.shape == (*c1_gb.output_shape, 4)
    assert img[0, 0, 3] == 0 and img[120, 160, 3] == 255


def test_curvature_map_is_symmetric_about_zero(c1_gb):
    lay = surface_layers(c1_gb, mode="curvature", curvature="mean", curvature_limit=1.0)
    k = c1_gb.downsample(np.where(c1_gb.mask, c1_gb.scalars["mean_curvature"], np.nan))
    rgb = lay["rgb"]
    solid = (c1_gb.downsample(c1_gb.mask.astype(np.float32)) == 1) & np.isfinite(k)
    pos, neg = solid & (k > 0.3), solid & (k < -0.3)
    assert pos.any() and neg.any()
    # red for positive, blue for negative; near zero almost white
    assert (rgb[pos][:, 0] > rgb[pos][:, 2]).all() and (rgb[neg][:, 2] > rgb[neg][:, 0]).all()
    flat = solid & (np.abs(k) < 0.02)
    if flat.any():
        assert rgb[flat].min() > 0.9


def test_seam_curvature_jumps_only_at_c1():
    for continuity, jumps in (("C2", False), ("C1", True)):
        ps = seam_patches(continuity)
        # along the seam (u = 1 on patch 0, u = 0 on patch 1), compare the mean curvature
        v = np.linspace(0.1, 0.9, 9)
        k0 = ps.curvatures(0, np.ones_like(v), v)
        k1 = ps.curvatures(1, np.zeros_like(v), v)
        h0, h1 = np.asarray(k0[1]), np.asarray(k1[1])
        assert (np.abs(h0 - h1).min() > 0.1) == jumps
        if not jumps:
            assert np.abs(h0 - h1).max() < 1e-9


def test_surface_analysis_rejects(c1_gb):
    with pytest.raises(InputError, match="mode"):
        surface_analysis(c1_gb, mode="zebra")
    with pytest.raises(InputError, match="curvature"):
        surface_analysis(c1_gb, mode="curvature", curvature="total")
    with pytest.raises(InputError, match="continuity"):
        seam_patches("C3")
    plain = sg.capture(pv.Sphere(), window_size=(64, 64))
    with pytest.raises(InputError, match="no 'gaussian_curvature'"):
        surface_analysis(plain, mode="curvature")
    with pytest.raises(InputError, match="patches"):
        surface_analysis(42)


@needs_patches
def test_teapot_analysis_has_no_holes():
    gb = surface_gbuffer(TEAPOT_BPT, resolution=12, window_size=(200, 150))
    img = surface_analysis(gb, mode="reflection")
    assert np.isfinite(gb.normal[gb.mask]).all()
    assert 0.08 < (img[..., 3] > 0).mean() < 0.8


@needs_patches
def test_cli_patches(tmp_path, capsys):
    out = tmp_path / "teapot.png"
    args = ["patches", str(TEAPOT_BPT), "-o", str(out), "--size", "160x120", "--mode", "stripes"]
    assert main(args) == 0
    assert out.is_file() and "teapot" in capsys.readouterr().out
    assert main(["patches", str(tmp_path / "none.bpt"), "-o", str(out)]) == 2
    assert "none.bpt" in capsys.readouterr().err
    bad = tmp_path / "bad.bpt"
    bad.write_text("1\n3 3\n0 0 0\n")
    assert main(["patches", str(bad), "-o", str(out)]) == 2
    assert "line" in capsys.readouterr().err


def test_parametric_surfaces_keep_their_uv_and_get_curvature():
    gb = surface_gbuffer(pv.ParametricTorus, view="iso", window_size=(160, 120))
    assert gb.uv is not None
    assert np.nanmax(gb.uv) <= 1.0 + 1e-4 and np.nanmin(gb.uv) >= -1e-4  # barycentric round-off
    img = surface_analysis(gb, mode="curvature")
    assert (img[..., 3] == 255).mean() > 0.3  # (the centre of the picture is the hole)
    # the outer rim of a torus is elliptic (K > 0, red), the inner hyperbolic (K < 0, blue)
    k = gb.scalars["gaussian_curvature"][gb.mask]
    assert k.max() > 0 > k.min()
    plain = surface_gbuffer(pv.Sphere(radius=2.0), window_size=(96, 96))
    k = plain.scalars["gaussian_curvature"][plain.mask]
    assert abs(np.median(k) - 0.25) < 0.03  # mesh-based, 1 / r^2
