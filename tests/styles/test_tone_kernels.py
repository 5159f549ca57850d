"""The one-pass gooch and toon shades against the array expressions they replaced, bit for bit."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.filters import lambert
from sciviz_gbuf.styles import gooch, tone, toon
from sciviz_gbuf.styles.illustration import shade_image
from sciviz_gbuf.styles.tone import GOOCH_BASE, GOOCH_COOL, GOOCH_WARM

# the module (``sciviz_gbuf.styles.hatch`` is also the style function the package exports)
H = importlib.import_module("sciviz_gbuf.styles.hatch")


def _reference_gooch(gb, light, k_warm, k_cool, bg):
    """Plane by plane at buffer size, then the box filter (the code the kernel replaced)."""
    t = tone._n_dot_l(gb, light)
    t += np.float32(1.0)
    t *= np.float32(0.5)
    one_minus_t = np.float32(1.0) - t
    paper = ~np.asarray(gb.mask, dtype=bool)
    clip = max(float(k_warm.max()), float(k_cool.max())) > 1.0 - 2.0**-20
    ss = gb.supersample > 1
    out = np.empty((*(gb.output_shape if ss else gb.shape), 3), dtype=np.float32)
    for c in range(3):
        plane = t * k_warm[c] + one_minus_t * k_cool[c]
        if clip:
            np.clip(plane, 0.0, 1.0, out=plane)
        np.copyto(plane, bg[c], where=paper)
        out[..., c] = gb.downsample(plane) if ss else plane
    return np.clip(out, 0.0, 1.0, out=out)


@pytest.fixture(scope="module")
def buffers():
    out = []
    torus = pv.ParametricTorus()
    for ss in (1, 2, 3):
        gb = sg.capture(torus, window_size=(90, 70), supersample=ss)
        out.append(gb)
    odd = sg.capture(pv.Sphere(), window_size=(60, 50), supersample=2)
    n = odd.normal.copy()
    n[odd.mask][::7, 0] = np.nan  # surface normals with a missing component
    rows, cols = np.nonzero(odd.mask)
    n[rows[::5], cols[::5], 1] = np.nan
    n[rows[::11], cols[::11], 2] = np.inf
    odd.normal = n
    out.append(odd)
    return out


@pytest.mark.parametrize("light", [(0.3, 0.5, 1.0), (-1.0, 0.2, 0.1)])
def test_gooch_shade_equals_plane_by_plane(buffers, light):
    lv = tone._unit_light(light)
    f = np.float32
    base = np.asarray(GOOCH_BASE, f)
    k_cool = np.asarray(GOOCH_COOL, f) + f(0.2) * base
    k_warm = np.asarray(GOOCH_WARM, f) + f(0.6) * base
    for gb in buffers:
        ref = _reference_gooch(gb, lv, k_warm, k_cool, np.ones(3, f))
        np.testing.assert_array_equal(gooch(gb, light=light, edges=False), ref)
    # tones that reach 1: the clipped blend
    gb = buffers[1]
    warm = np.asarray((1.0, 1.0, 0.9), f)
    ref = _reference_gooch(gb, lv, warm + f(0.6) * base, k_cool, np.ones(3, f))
    got = gooch(gb, light=light, warm=(1.0, 1.0, 0.9), edges=False)
    np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("levels", [1, 3, 7, [0.2, 0.5, 0.9, 1.0]])
def test_toon_shade_equals_the_texel_gather(buffers, levels):
    base = tone._validate.rgb(tone.TOON_BASE, "base")
    table = tone._shade_table(levels, base)
    lv = tone._unit_light(tone.LIGHT)
    bg = np.ones(3, np.float32)
    for gb in buffers:
        ref = tone._finish(gb, tone._toon_colour(gb, lv, table, 0.0, bg))
        np.testing.assert_array_equal(toon(gb, levels=levels, edges=False), ref)


@pytest.mark.parametrize("light", [(-0.4, 0.5, 0.77), (0.0, 0.0, 1.0)])
@pytest.mark.parametrize("ambient", [0.0, 0.2])
def test_shade_image_equals_lambert_then_downsample(buffers, light, ambient):
    for gb in buffers:
        shade = lambert(gb.normal, light=light, ambient=ambient)
        shade = np.where(gb.mask, np.float32(0.85) * shade, np.float32(1.0))
        ref = np.clip(gb.downsample(shade), 0.0, 1.0).astype(np.float32)
        got = shade_image(gb, light=light, ambient=ambient, highlight=0.85)
        np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("kw", [{}, {"spacing": 3.0, "angles": (10.0, 75.0, 140.0)},
                                {"max_width": 1.5, "max_ink": 0.9}])  # fmt: skip
def test_screen_strokes_equal_the_family_by_family_arrays(buffers, kw):
    for gb in buffers:
        k = gb.supersample
        sp = float(kw.get("spacing", H.HATCH_SPACING)) * k
        theta = H._angles(kw.get("angles", H.HATCH_ANGLES))
        m_ink = float(kw.get("max_ink", H.HATCH_MAX_INK))
        cap = kw.get("max_width")
        cap_w = None if cap is None else float(cap) * k
        t = H._tone(gb.normal, tone.LIGHT, np.asarray(gb.mask, dtype=bool))
        ref = H._array_strokes(gb, t, "screen", theta, sp, m_ink, cap_w, None, k)
        tau, left, _ = H.family_thresholds(theta.size, m_ink)
        got = np.empty_like(ref)
        lv = tone._unit_light(tone.LIGHT)
        cap_arg = -1.0 if cap_w is None else cap_w
        H._hk.screen_strokes(
            gb.normal, gb.mask, lv, theta.astype(np.float64), sp, cap_arg, tau, left, m_ink, got
        )
        np.testing.assert_array_equal(got, ref)


def _reference_hatch_tail(gb, strokes, edges, pw, ink_c, paper_c):
    """The array code that turned the strokes into the picture (before the compose kernel)."""
    k = gb.supersample
    mask = np.asarray(gb.mask, dtype=bool)
    amount = strokes.copy() if k == 1 else gb.downsample(strokes)
    np.clip(amount, 0.0, 1.0, out=amount)
    keep = None
    if edges:
        prof = H.profile_ink(gb, width=pw)
        halo = H.profile_halo(prof)
        halo[gb.downsample(mask.astype(np.float32)) < np.float32(1.0)] = np.float32(0.0)
        amount *= np.float32(1.0) - halo
        keep = np.float32(1.0) - prof
    rgb = np.empty((*amount.shape, 3), dtype=np.float32)
    plane = np.empty_like(amount)
    for c in range(3):
        np.multiply(amount, ink_c[c] - paper_c[c], out=plane)
        plane += paper_c[c]
        if keep is not None:
            plane *= keep
        rgb[..., c] = plane
    return np.clip(rgb, 0.0, 1.0, out=rgb)


@pytest.mark.parametrize("edges", [True, False])
def test_hatch_compose_equals_the_array_tail(buffers, edges):
    f = np.float32
    ink_c, paper_c = np.asarray((0.1, 0.05, 0.2), f), np.asarray((1.0, 0.97, 0.9), f)
    for gb in buffers:
        k = gb.supersample
        theta = H._angles(H.HATCH_ANGLES)
        tau, left, _ = H.family_thresholds(theta.size, H.HATCH_MAX_INK)
        strokes = np.empty(gb.shape, f)
        H._hk.screen_strokes(
            gb.normal, gb.mask, tone._unit_light(tone.LIGHT), theta.astype(np.float64),
            float(H.HATCH_SPACING) * k, -1.0, tau, left, float(H.HATCH_MAX_INK), strokes,
        )  # fmt: skip
        ref = _reference_hatch_tail(gb, strokes, edges, 1.5, ink_c, paper_c)
        got = H.hatch(gb, edges=edges, profile_width=1.5, ink=ink_c, paper=paper_c)
        np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("light", [(0.3, 0.5, 1.0), (-1.0, 0.2, 0.1)])
def test_drawing_modulation_equals_lambert_then_modulation(buffers, light):
    L = importlib.import_module("sciviz_gbuf.styles.lines")
    for gb in buffers:
        ref = L.modulation(lambert(gb.normal, light=light, mask=gb.mask))
        np.testing.assert_array_equal(L._modulation(gb, light), ref)


def _reference_enhanced(gb, index, spacing, width, m):
    """Two hatchings of the masked field and the blend (the code the one pass replaced)."""
    k = gb.supersample
    field = np.where(gb.mask, gb.uv[..., index], np.nan).astype(np.float32)
    full = sg.filters.hatching(field, spacing=spacing * k, width=width * k, mask=gb.mask)
    thin = sg.filters.hatching(field, spacing=spacing * k, width=0.5 * width * k, mask=gb.mask)
    a = np.clip(2.0 * m - 1.0, 0.0, 1.0)
    return np.where(m >= 0.5, thin + a * (full - thin), 2.0 * m * thin).astype(np.float32)


@pytest.mark.parametrize(("spacing", "width"), [(6.0, 1.0), (3.0, 2.5), (12.0, 0.6)])
def test_drawing_hatching_equals_two_hatchings_and_the_blend(buffers, spacing, width):
    L = importlib.import_module("sciviz_gbuf.styles.lines")
    for gb in buffers:
        gb = L.with_section_uv(gb)
        m = L._modulation(gb, (0.3, 0.5, 1.0))
        on = m[gb.mask]
        assert (on < 0.5).any() and (on > 0.5).any()  # both branches of the blend are met
        for index in (0, 1):
            ref = _reference_enhanced(gb, index, spacing, width, m)
            got = L._enhanced(gb, index, spacing, width, m)
            assert got.dtype == np.float32
            # the same up to a fused multiply-add in the blend
            np.testing.assert_allclose(got, ref, rtol=0, atol=2e-7)
            assert (ref > 0.2).sum() > 20  # there are lines


def test_modulated_hatching_reads_nan_as_no_ink_and_clips():
    y, x = np.mgrid[0:40, 0:50].astype(np.float32)
    field = 0.37 * x + 0.11 * y
    full = sg.filters.hatching(field, spacing=6.0, width=2.0)
    ones = sg.filters.modulated_hatching(field, np.full(field.shape, 1.0), spacing=6.0, width=2.0)
    np.testing.assert_allclose(ones, full, atol=2e-7)
    over = sg.filters.modulated_hatching(field, np.full(field.shape, 7.0), spacing=6.0, width=2.0)
    np.testing.assert_array_equal(over, ones)
    nan = sg.filters.modulated_hatching(field, np.full(field.shape, np.nan), spacing=6.0, width=2.0)
    neg = sg.filters.modulated_hatching(field, np.full(field.shape, -3.0), spacing=6.0, width=2.0)
    assert not nan.any() and not neg.any()
    half = sg.filters.modulated_hatching(field, np.full(field.shape, 0.5), spacing=6.0, width=2.0)
    thin = sg.filters.hatching(field, spacing=6.0, width=1.0)
    np.testing.assert_allclose(half, thin, atol=2e-7)
    with pytest.raises(sg.InputError, match="modulation"):
        sg.filters.modulated_hatching(field, np.ones((3, 3)))
