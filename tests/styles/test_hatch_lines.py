"""Halftone hatching (2003 Fig. 8), the 1990 Fig. 9 line drawings and the Fig. 10 photocopies."""

from __future__ import annotations

import dataclasses
import itertools
from functools import cache

import numpy as np
import pytest
import pyvista as pv
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import lambert, profile_edges
from sciviz_gbuf.styles.hatch import (
    HATCH_MAX_INK,
    family_thresholds,
    hatch,
    stroke_ink,
    tone_coverage,
)
from sciviz_gbuf.styles.illustration import LIGHT
from sciviz_gbuf.styles.lines import COMBOS, line_drawing, modulation, photocopy

SIZE = 160


@cache
def sphere_gb():
    s = pv.Sphere(radius=1.0, theta_resolution=160, phi_resolution=160)
    return sg.capture(s, window_size=(SIZE, SIZE), camera="xy", supersample=2)


@cache
def torus_gb():
    # ParametricTorus: u runs around the ring, v around the tube, both analytically in [0, 1]
    t = pv.ParametricTorus(texture_coordinates=True)
    return sg.capture(t, window_size=(SIZE, SIZE), camera="iso", supersample=2)


def inside(gb, erode: int = 0) -> np.ndarray:
    """Output pixels fully covered by the object (optionally eroded)."""
    m = gb.downsample(gb.mask.astype(np.float32)) > 0.999
    return ndimage.binary_erosion(m, iterations=erode) if erode else m


def out_shade(gb, light=LIGHT) -> np.ndarray:
    return gb.downsample(lambert(gb.normal, light=light, mask=gb.mask))


def out_uv(gb) -> np.ndarray:
    return gb.downsample(np.where(gb.mask[..., None], gb.uv, np.nan))


def bin_means(values, shade, sel, edges):
    means = []
    for a, b in itertools.pairwise(edges):
        s = sel & (shade >= a) & (shade < b)
        if s.sum() >= 50:
            means.append(float(values[s].mean()))
    return np.array(means)


# ----------------------------------------------------------------------------- hatching


@pytest.mark.parametrize("light", [LIGHT, (0.0, 0.0, 1.0), (1.0, -0.3, 0.4)])
def test_hatch_ink_falls_monotonically_with_shade_and_tracks_tone(light):
    gb = sphere_gb()
    ink = 1.0 - hatch(gb, light=light, edges=False)[..., 0]
    sh = out_shade(gb, light)
    edges = np.linspace(0, 1, 11)
    cov = bin_means(ink, sh, inside(gb), edges)
    tone = bin_means(1.0 - sh, sh, inside(gb), edges)
    assert cov.size >= 6
    # brighter bins never get more ink (a little slack for the strokes' phase in small bins)
    assert np.all(np.diff(cov) <= 0.02), cov
    assert cov[0] > cov[-1] + 0.4
    # the union of the prioritised families covers the tone (Freudenberg halftoning), scaled
    # so that the darkest tone keeps paper between the strokes
    assert np.abs(cov - HATCH_MAX_INK * tone).max() < 0.06, (cov, tone)
    if light == LIGHT:
        assert cov[0] > 0.5 and cov[-1] < 0.1, cov


def test_prioritised_thresholds_are_monotone_and_cover_the_tone():
    t = np.linspace(0, 1, 401, dtype=np.float32)[None, :]
    for n, m in itertools.product((1, 2, 4, 7), (0.5, HATCH_MAX_INK, 0.95)):
        c = tone_coverage(t, n, m)
        assert np.all(np.diff(c, axis=-1) >= -1e-7)  # no family ever loses ink as t rises
        union = 1.0 - np.prod(1.0 - c, axis=0)
        np.testing.assert_allclose(union, m * t, atol=1e-5)
        # family f is off until t passes tau_f (priority order), and every family ends at the
        # same coverage a < 1: darker tones add families instead of widening strokes
        tau, _, a = family_thresholds(n, m)
        assert np.all(np.diff(tau) > 0) and tau[0] == 0 and tau[-1] == 1
        for f in range(n):
            assert np.all(c[f, 0][t[0] <= tau[f] + 1e-6] < 1e-5)
        np.testing.assert_allclose(c[:, 0, -1], a, atol=1e-5)
        assert a < 1 and (n == 1 or a <= 1 - (1 - m) ** 0.5 + 1e-6)
    # a stroke's ink grows with its width and integrates to it (antialiased, no dithering)
    d = np.linspace(-5, 5, 10001, dtype=np.float32)
    prev = np.zeros_like(d)
    for w in (0.0, 0.3, 0.9, 1.0, 2.5, 4.0):
        ink = stroke_ink(d, np.float32(w))
        assert np.all(ink >= prev - 1e-7)
        assert float(ink.sum() * (d[1] - d[0])) == pytest.approx(w, abs=2e-3)
        prev = ink


def test_hatch_strokes_are_antialiased_at_their_edges_only():
    gb = sphere_gb()
    ink = 1.0 - hatch(gb, edges=False, angles=(30.0, -60.0))[..., 0]
    sel = inside(gb, erode=2)
    mid = sel & (ink > 0.1) & (ink < 0.9)
    # antialiased, not binary ...
    assert mid.sum() > 0.05 * sel.sum()
    # ... and no flat grey (dithering to a uniform grey would be): every intermediate pixel
    # sits on a stroke's flank, next to clearly lighter or darker pixels (faint sub-pixel
    # strokes in the highlights have plain paper next to them)
    rng = ndimage.maximum_filter(ink, 3) - ndimage.minimum_filter(ink, 3)
    frac = float((rng[mid] > 0.15).mean())
    print(
        f"hatch: {mid.sum()} intermediate pixels ({mid.sum() / sel.sum():.1%}), {frac:.4f} on edges"
    )
    assert frac > 0.98


def test_hatch_is_deterministic_draws_black_profiles_and_uses_colours():
    gb = sphere_gb()
    a, b = hatch(gb), hatch(gb)
    np.testing.assert_array_equal(a, b)
    assert a.dtype == np.float32 and a.shape == (*gb.output_shape, 3)
    cov = gb.downsample(gb.mask.astype(np.float32))
    outline = (cov > 0.2) & (cov < 0.8)
    red = hatch(gb, ink=(1, 0, 0), paper=(0, 0, 1))
    # profiles black whatever the ink: the outline is inked, and dark where the ink is strong
    prof = profile_edges(gb, width=1.0)
    on = outline & (prof > 0.55)
    assert on.sum() > 0.6 * outline.sum()
    assert (red[on].max(axis=-1) < 0.5).all()
    bg = ndimage.binary_erosion(cov == 0, iterations=3)  # the profile line reaches outside
    np.testing.assert_allclose(red[bg], np.broadcast_to([0, 0, 1], red[bg].shape))
    assert red[inside(gb, 3)][..., 1].max() == 0.0  # only ink red and paper blue inside


def test_hatch_uv_needs_uv_and_follows_the_parameterisation():
    gb = sphere_gb()
    assert gb.uv is None
    with pytest.raises(InputError, match="space"):
        hatch(gb, space="uv")
    tg = torus_gb()
    ink = 1.0 - hatch(tg, space="uv", angles=(90.0,), edges=False)[..., 0]
    uv = out_uv(tg)
    check_follows(ink, uv[..., 0], uv[..., 1], inside(tg, erode=3))
    ink_v = 1.0 - hatch(tg, space="uv", angles=(0.0,), edges=False)[..., 0]
    check_follows(ink_v, uv[..., 1], uv[..., 0], inside(tg, erode=3))
    # the uv strokes still track the tone
    sh = out_shade(tg)
    cov = bin_means(
        1.0 - hatch(tg, space="uv", edges=False)[..., 0], sh, inside(tg, 3), np.linspace(0, 1, 6)
    )
    assert np.all(np.diff(cov) <= 0.03) and cov[0] > cov[-1] + 0.3, cov


def grad(f):
    gy, gx = np.gradient(f)
    return gx, gy


def check_follows(ink, along, across, sel):
    """The ink's lines are level lines of ``along``: the ink gradient is parallel to grad(along)
    and (on the torus, where u and v are orthogonal) perpendicular to grad(across)."""
    ix, iy = grad(ink)
    ax, ay = grad(along)
    bx, by = grad(across)
    ni = np.hypot(ix, iy)
    strong = sel & (ni > 0.2) & np.isfinite(ax + ay + bx + by)
    # seams of the parameterisation (u jumping 1 -> 0) have no meaningful gradient
    na, nb = np.hypot(ax, ay), np.hypot(bx, by)
    strong &= (na < 10 * np.nanmedian(na[sel])) & (nb < 10 * np.nanmedian(nb[sel]))
    cos_a = np.abs(ix * ax + iy * ay)[strong] / (ni * na)[strong]
    cos_b = np.abs(ix * bx + iy * by)[strong] / (ni * nb)[strong]
    assert strong.sum() > 300
    assert np.median(cos_a) > 0.9, np.median(cos_a)
    assert np.median(cos_b) < 0.4, np.median(cos_b)


# ----------------------------------------------------------------------------- line drawing


def test_line_drawing_sh_is_the_shade_and_pr_the_profiles():
    tg = torus_gb()
    sh = line_drawing(tg, combo="sh")
    m = inside(tg)
    np.testing.assert_allclose(sh[m], out_shade(tg)[m], atol=1e-5)
    assert np.all(sh[tg.downsample(tg.mask.astype(np.float32)) == 0] == 1.0)
    pr = line_drawing(tg, combo="pr")
    cov = tg.downsample(tg.mask.astype(np.float32))
    outline = (cov > 0.2) & (cov < 0.8)
    assert (pr[outline] < 0.5).mean() > 0.9
    assert (pr[inside(tg, 4)] < 0.5).mean() < 0.1  # only the inner profile of the hole
    for combo in ("shu", "shv", "shuv"):
        img = line_drawing(tg, combo=combo)
        assert (img[outline] < 0.5).mean() > 0.9, combo  # composed with pr
    for combo in ("cu", "cv"):  # the bare hatching of Fig. 9 has no profiles
        assert (line_drawing(tg, combo=combo)[cov == 0] == 1.0).all()


def test_curved_hatching_follows_u_and_v():
    tg = torus_gb()
    uv = out_uv(tg)
    sel = inside(tg, erode=3)
    for combo, a, b in (("cu", 0, 1), ("cv", 1, 0), ("shu", 0, 1), ("shv", 1, 0)):
        ink = 1.0 - line_drawing(tg, combo=combo, spacing=8.0, width=1.5)
        check_follows(ink, uv[..., a], uv[..., b], sel & (line_drawing(tg, combo="pr") > 0.9))
    # at inked pixels u is on a level line: the 1990 hatching draws u = k 2^n (interval 1)
    # with 2^n between d_i |grad u| / 2 and 2 d_i |grad u|, so u lies within the line's
    # half-width of a multiple of the power of two q <= d_i |grad u| / 2
    spacing, width = 16.0, 1.5
    ink = 1.0 - line_drawing(tg, combo="cu", spacing=spacing, width=width)
    u = uv[..., 0]
    gx, gy = grad(u)
    g = np.hypot(gx, gy)
    ok = sel & np.isfinite(g) & (g > 0) & (g < 10 * np.nanmedian(g[sel]))
    q = 2.0 ** np.floor(np.log2(np.where(ok, spacing * g / 2, 1.0)))
    dist = np.abs(u / q - np.round(u / q)) * q / np.where(ok, g, 1.0)  # px to nearest level
    on, off = ok & (ink > 0.7), ok & (ink < 0.02)
    print(
        f"cu: px to the nearest u level: inked {np.median(dist[on]):.2f}, "
        f"paper {np.median(dist[off]):.2f}"
    )
    assert on.sum() > 200
    assert (dist[on] < width / 2 + 0.75).mean() > 0.95
    assert np.median(dist[off]) > 3 * np.median(dist[on])
    # shuv is the union of shu and shv (but where their lines clump: thinned to a skeleton)
    shuv, shu, shv = (line_drawing(tg, combo=c) for c in ("shuv", "shu", "shv"))
    assert (shuv > np.minimum(shu, shv) + 1e-6).mean() < 0.002
    assert (shuv < shu - 0.3).sum() > 100 and (shuv < shv - 0.3).sum() > 100


def test_hatching_is_enhanced_with_the_shade():
    tg = torus_gb()
    sh = out_shade(tg)
    sel = inside(tg, erode=2) & (line_drawing(tg, combo="pr") > 0.99)
    lit, dark = sel & (sh > 0.9), sel & (sh < 0.3)
    assert lit.sum() > 200 and dark.sum() > 200
    for plain, enhanced in (("cu", "shu"), ("cv", "shv")):
        p = 1.0 - line_drawing(tg, combo=plain)
        e = 1.0 - line_drawing(tg, combo=enhanced)
        print(
            f"{enhanced}: ink lit {e[lit].mean():.3f} dark {e[dark].mean():.3f}; "
            f"{plain}: lit {p[lit].mean():.3f} dark {p[dark].mean():.3f}"
        )
        assert e[dark].mean() > 4 * e[lit].mean()
        assert e[lit].mean() < 0.3 * p[lit].mean()  # highlights lose their lines
        assert e[dark].mean() > 0.8 * p[dark].mean()  # shadows keep them
    m = modulation(np.linspace(0, 1, 101, dtype=np.float32))
    assert np.all(np.diff(m) <= 0) and m[0] == 1 and m[-1] == 0


def test_line_drawing_needs_uv_for_hatching():
    gb = sphere_gb()
    for combo in ("cu", "cv", "shu", "shv", "shuv"):
        with pytest.raises(InputError, match="combo"):
            line_drawing(gb, combo=combo)
    assert line_drawing(gb, combo="sh").shape == gb.output_shape
    nouv = dataclasses.replace(torus_gb(), uv=None)
    with pytest.raises(InputError, match="combo"):
        line_drawing(nouv)


# ----------------------------------------------------------------------------- photocopies


def copy_quality(orig: np.ndarray, copy: np.ndarray, sel: np.ndarray) -> dict[str, float]:
    """Measures of what five copies did to an image (grey, 1 = paper) inside ``sel``.

    - ``kept``: fraction of the original's line pixels (ink > 0.5) still dark (< 0.5);
    - ``kept_any``: fraction of all inked pixels (ink > 0.2, antialiased fringes and faint
      lines included) with a dark copy pixel within one pixel: the line is still there;
    - ``new``: dark copy pixels more than one pixel away from any original line pixel, per
      original line pixel (stray marks, not the thickening of antialiased edges);
    - ``levels``: the number of 16 grey bins holding >= 1% of the object (gradation);
    - ``tone_err``: mean |difference| of the tone seen from a distance (a Gaussian low-pass of
      3 px, which turns hatching into its grey) — what a reader perceives as the shading;
    - ``tone_corr``: correlation of that perceived tone between original and copy.
    """
    line = (1.0 - orig) > 0.5
    near = ndimage.binary_dilation(line, iterations=1)
    dark = copy < 0.5
    n_line = max(int(line.sum()), 1)

    def levels(a):
        h = np.bincount(np.minimum((a[sel] * 16).astype(int), 15), minlength=16)
        return int((h >= 0.01 * sel.sum()).sum())

    lo, lc = ndimage.gaussian_filter(orig, 3.0), ndimage.gaussian_filter(copy, 3.0)
    return {
        "kept": float(dark[line].mean()) if line.any() else float("nan"),
        "kept_any": float(ndimage.binary_dilation(dark)[(1.0 - orig) > 0.2].mean()),
        "new": float((dark & ~near & sel).sum() / n_line),
        "levels_orig": levels(orig),
        "levels_copy": levels(copy),
        "tone_err": float(np.abs(lo - lc)[sel].mean()),
        "tone_corr": float(np.corrcoef(lo[sel], lc[sel])[0, 1]),
    }


def test_photocopies_ruin_the_shade_but_keep_line_drawings():
    """1990 Fig. 10: after five copies sh is "completely poor", cv almost as the original.

    The content of a line drawing is its lines: >= 90% of them must still be dark, with almost
    no stray marks, and the tone they convey from a distance must stay. The content of the
    shaded image is its gradation: the 16 grey bins it spreads over must collapse to black and
    paper (<= 3 bins), and its perceived tone must go badly wrong.
    """
    tg = torus_gb()
    sel = inside(tg, erode=4)
    sh = line_drawing(tg, combo="sh")
    q_sh = copy_quality(sh, photocopy(sh, copies=5, seed=1), sel)
    print("\nsh      :", {k: round(v, 3) for k, v in q_sh.items()})
    assert q_sh["levels_orig"] >= 12 and q_sh["levels_copy"] <= 3
    assert q_sh["tone_err"] > 0.12
    for combo, width in (("cv", 1.0), ("shuv", 1.0), ("cv", 1.5), ("shuv", 1.5)):
        img = line_drawing(tg, combo=combo, width=width)
        q = copy_quality(img, photocopy(img, copies=5, seed=1), sel)
        print(f"{combo:4} w={width}:", {k: round(v, 3) for k, v in q.items()})
        assert q["kept"] >= 0.9
        # shuv's half-tone lines are thinner than a pixel (grey): some fade over five copies
        assert q["kept_any"] >= (0.9 if combo == "cv" else 0.8)
        assert q["new"] <= 0.02
        assert q["tone_err"] < 0.06
        assert q_sh["tone_err"] > 2.0 * q["tone_err"]


def test_photocopy_model():
    ramp = np.tile(np.linspace(0, 1, 64, dtype=np.float32), (64, 1))
    one = photocopy(ramp, copies=1, noise=0.0)
    five = photocopy(ramp, copies=5, noise=0.0)
    # a steep, monotone, non-linear tone curve: black and paper stay, mid tones are pushed apart
    assert np.all(np.diff(five, axis=1) >= -1e-6)
    assert five[:, :5].max() < 0.02 and five[:, -5:].min() > 0.98
    assert (np.abs(five - 0.5) < 0.3).mean() < 0.15 < (np.abs(one - 0.5) < 0.3).mean()
    # 8-bit output, deterministic with a seed, identity for zero copies (but quantised)
    c = photocopy(ramp, seed=3)
    np.testing.assert_array_equal(c, photocopy(ramp, seed=3))
    np.testing.assert_allclose(c * 255, np.round(c * 255), atol=1e-3)
    np.testing.assert_allclose(photocopy(ramp, copies=0), np.round(ramp * 255) / 255, atol=1e-6)
    rgb = photocopy(np.stack([ramp] * 3, axis=-1), noise=0.0)
    np.testing.assert_allclose(rgb[..., 1], five, atol=1e-6)  # channels copied alike


# ----------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"space": "world"}, "space"),
        ({"spacing": 0}, "spacing"),
        ({"spacing": float("nan")}, "spacing"),
        ({"angles": []}, "angles"),
        ({"angles": [0, float("inf")]}, "angles"),
        ({"max_width": -1}, "max_width"),
        ({"max_ink": 1.0}, "max_ink"),
        ({"max_ink": 0.0}, "max_ink"),
        ({"uv_scale": 2.0}, "uv_scale"),
        ({"profile_width": 0.5}, "profile_width"),
        ({"ink": (2, 0, 0)}, "ink"),
        ({"paper": (1, 1)}, "paper"),
        ({"light": (0, 0, 0)}, "light"),
    ],
)
def test_hatch_bad_parameters(kwargs, name):
    with pytest.raises(InputError, match=name):
        hatch(sphere_gb(), **kwargs)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"combo": "shx"}, "combo"),
        ({"spacing": -2}, "spacing"),
        ({"width": float("nan")}, "width"),
        ({"profile_width": 0.2}, "profile_width"),
        ({"light": (0, 0)}, "light"),
    ],
)
def test_line_drawing_bad_parameters(kwargs, name):
    with pytest.raises(InputError, match=name):
        line_drawing(torus_gb(), **kwargs)


@pytest.mark.parametrize(
    ("args", "kwargs", "name"),
    [
        ((np.ones(5),), {}, "image"),
        ((np.full((4, 4), np.nan),), {}, "image"),
        ((np.ones((4, 4)),), {"copies": -1}, "copies"),
        ((np.ones((4, 4)),), {"copies": 2.5}, "copies"),
        ((np.ones((4, 4)),), {"blur": -0.1}, "blur"),
        ((np.ones((4, 4)),), {"pivot": 1.0}, "pivot"),
        ((np.ones((4, 4)),), {"contrast": 0}, "contrast"),
        ((np.ones((4, 4)),), {"noise": -1}, "noise"),
    ],
)
def test_photocopy_bad_parameters(args, kwargs, name):
    with pytest.raises(InputError, match=name):
        photocopy(*args, **kwargs)


def test_not_a_gbuffer():
    with pytest.raises(InputError, match="gb"):
        hatch(np.zeros((4, 4, 3)))
    with pytest.raises(InputError, match="gb"):
        line_drawing(np.zeros((4, 4, 3)))


# ----------------------------------------------------------------------------- odd parameters

finite = {"allow_nan": False, "allow_infinity": False}


@settings(max_examples=25, deadline=None)
@given(
    space=st.sampled_from(["screen", "uv"]),
    spacing=st.floats(0.3, 60, **finite),
    angles=st.lists(st.floats(-1000, 1000, **finite), min_size=1, max_size=5),
    max_width=st.none() | st.floats(0.01, 50, **finite),
    light=st.tuples(*[st.floats(-1, 1, **finite)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
)
def test_hatch_odd_parameters_stay_in_range(space, spacing, angles, max_width, light):
    img = hatch(
        torus_gb(), space=space, spacing=spacing, angles=angles, max_width=max_width, light=light
    )
    assert img.shape == (SIZE, SIZE, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and img.min() >= 0 and img.max() <= 1


@settings(max_examples=25, deadline=None)
@given(
    combo=st.sampled_from(sorted(COMBOS)),
    spacing=st.floats(0.3, 60, **finite),
    width=st.floats(0.05, 20, **finite),
    profile_width=st.floats(1, 6, **finite),
    copies=st.integers(0, 6),
    blur=st.floats(0, 3, **finite),
    pivot=st.floats(0.01, 0.99, **finite),
    contrast=st.floats(0.1, 100, **finite),
)
def test_line_drawing_and_copies_odd_parameters_stay_in_range(
    combo, spacing, width, profile_width, copies, blur, pivot, contrast
):
    img = line_drawing(
        torus_gb(), combo=combo, spacing=spacing, width=width, profile_width=profile_width
    )
    assert img.shape == (SIZE, SIZE) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and img.min() >= 0 and img.max() <= 1
    cp = photocopy(img[::4, ::4], copies=copies, blur=blur, pivot=pivot, contrast=contrast, seed=0)
    assert np.all(np.isfinite(cp)) and cp.min() >= 0 and cp.max() <= 1
