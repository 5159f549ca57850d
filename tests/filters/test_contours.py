"""Contour lines and curved hatching (1990 §3.3-3.4): line positions and widths against analytic
level sets and skimage's marching squares, the paper's f_g blends, major/minor thinning,
hatching spacing, flat and NaN regions, and odd inputs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy import ndimage
from skimage import measure

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import (
    c1_discontinuity,
    contour_lines,
    contour_polylines,
    hatching,
    polylines_to_geojson,
)

PROFILES = ("linear", "smooth", "bilevel")


def ramp(g: float, theta_deg: float, shape=(40, 400), offset=0.37) -> np.ndarray:
    """s = g (x cos t + y sin t) + offset, x = column, y = row (pixel centres)."""
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    t = np.radians(theta_deg)
    return (g * (x * np.cos(t) + y * np.sin(t)) + offset).astype(np.float32)


def line_stats(row: np.ndarray, centres: np.ndarray, half_window: float):
    """Ink centroid and ink sum of the line near each expected centre along one row."""
    x = np.arange(row.size)
    out = []
    for c in centres:
        sel = np.abs(x - c) <= half_window
        ink = row[sel]
        out.append((float((x[sel] * ink).sum() / max(ink.sum(), 1e-9)), float(ink.sum())))
    return out


# ---------------------------------------------------------------------------------------------
# Positions and widths


@pytest.mark.parametrize("profile", ("linear", "smooth"))
@pytest.mark.parametrize("width", (1.0, 2.0, 3.0))
@pytest.mark.parametrize("theta", (0.0, 26.57, 45.0))
def test_ramp_centres_and_widths_over_16x_gradients(profile, width, theta):
    """Every line of a ramp sits within 0.5 px of its level and is ``width`` px wide (+-0.5),
    for gradients from 1/64 to 1/4 per pixel."""
    cos = np.cos(np.radians(theta))
    for g in (1 / 64, 1 / 32, 1 / 16, 1 / 8, 1 / 4):
        s = ramp(g, theta)
        ink = contour_lines(s, interval=1.0, width=width, profile=profile)
        spacing_x = 1 / (g * cos)  # along a row
        for r in range(3, s.shape[0] - 3, 5):
            shift = g * r * np.sin(np.radians(theta)) + 0.37
            n = np.arange(np.ceil(shift), np.floor(shift + g * cos * (s.shape[1] - 1)) + 1)
            xc = (n - shift) / (g * cos)
            xc = xc[(xc > spacing_x / 2 + 2) & (xc < s.shape[1] - spacing_x / 2 - 3)]
            assert xc.size >= 1
            for (cx, total), x0 in zip(line_stats(ink[r], xc, spacing_x / 2), xc, strict=True):
                assert abs(cx - x0) <= 0.5, (g, r, x0, cx)
                assert abs(total * cos - width) <= 0.5, (g, r, x0, total * cos)


def test_bilevel_is_a_step_of_the_right_mean_width():
    s = ramp(1 / 16, 0.0)
    ink = contour_lines(s, interval=1.0, width=3.0, profile="bilevel")
    assert set(np.unique(ink)) <= {0.0, 1.0}
    # 3 px wide lines every 16 px: 3/16 of the pixels
    assert ink[:, 8:-8].mean() == pytest.approx(3 / 16, abs=0.01)


@pytest.mark.parametrize("field_name", ("circles", "hyperbolas"))
def test_curved_fields_match_find_contours_and_the_analytic_level_sets(field_name):
    """At every marching-squares vertex of a sparse line, the raster line's ink centre along
    the normal is within 0.5 px, and the vertex itself is on the analytic level set."""
    n = 301
    y, x = np.mgrid[0:n, 0:n].astype(np.float64) - 150.0
    if field_name == "circles":
        s, grad = (x**2 + y**2) / 64.0, np.stack([2 * x, 2 * y], -1) / 64.0
    else:
        s, grad = x * y / 64.0, np.stack([y, x], -1) / 64.0
    q, d = 32.0, 1.5
    ink = contour_lines(s.astype(np.float32), interval=q, width=d)
    offsets = np.linspace(-3, 3, 61)
    checked = 0
    for level in np.arange(-12, 13) * q:
        for rc in measure.find_contours(s, level):
            for r, c in rc[::7]:
                gx = grad[round(r), round(c), 0]
                gy = grad[round(r), round(c), 1]
                gn = np.hypot(gx, gy)
                if gn == 0 or q / gn < 8 or min(r, c, n - 1 - r, n - 1 - c) < 5:
                    continue  # only sparse lines, away from the border
                ux, uy = gx / gn, gy / gn
                # analytic: the vertex is on the level set (first order)
                sv = x[0, 0] + c, y[0, 0] + r
                sval = sv[0] ** 2 + sv[1] ** 2 if field_name == "circles" else sv[0] * sv[1]
                assert abs(sval / 64.0 - level) / gn <= 0.5
                prof = ndimage.map_coordinates(
                    ink, [r + offsets * uy, c + offsets * ux], order=1, mode="nearest"
                )
                assert prof.max() >= 0.5  # no line is missing
                centre = (offsets * prof).sum() / prof.sum()
                assert abs(centre) <= 0.5, (level, r, c, centre)
                assert abs(prof.sum() * (offsets[1] - offsets[0]) - d) <= 0.5
                checked += 1
    assert checked > 200


def test_no_line_missing_above_g_eps():
    """Along a ramp whose gradient grows 16x, every level crossing gets full ink."""
    x = np.arange(600, dtype=np.float64)
    s = np.tile((x**2 / 4000.0).astype(np.float32), (8, 1))  # g = x / 2000: 0.015 .. 0.3
    ink = contour_lines(s, interval=0.25, width=1.5, g_eps=0.01)
    levels = np.arange(0.25, s.max(), 0.25)
    xs = np.sqrt(levels * 4000.0)
    for x0 in xs[(xs > 30) & (xs < 590)]:
        i = round(x0)
        assert ink[4, i - 1 : i + 2].max() >= 0.75, x0


# ---------------------------------------------------------------------------------------------
# The paper's blends (Eq. 10-15) against a direct transcription


def isotropic_eq9(s: np.ndarray) -> np.ndarray:
    """Eq. 9 divided by its value on a unit plane in the Sobel direction (interior pixels)."""
    p = np.pad(s.astype(np.float64), 1, mode="edge")
    a, b, c = p[:-2, :-2], p[:-2, 1:-1], p[:-2, 2:]
    d, e = p[1:-1, :-2], p[1:-1, 2:]
    f, g, h = p[2:, :-2], p[2:, 1:-1], p[2:, 2:]
    gx = np.abs(c + 2 * e + h - a - 2 * d - f)
    gy = np.abs(f + 2 * g + h - a - 2 * b - c)
    hi, lo = np.maximum(gx, gy), np.minimum(gx, gy)
    with np.errstate(invalid="ignore", divide="ignore"):
        aniso = np.where(hi > 0, (hi + lo / 2) / np.hypot(hi, lo), 1.0)
    return c1_discontinuity(s) / aniso


def test_gradient_is_exact_on_planes_in_every_direction():
    for theta in np.linspace(0, 360, 37):
        s = ramp(0.3, theta, shape=(12, 12))
        doubled = 2 * isotropic_eq9(s)[1:-1, 1:-1]
        np.testing.assert_allclose(doubled, 0.6, rtol=2e-4)
        # lines 2 px wide, 20 px apart: 4 px of ink along two periods, in every direction
        ink = contour_lines(ramp(0.05, theta, shape=(60, 60)), interval=1.0, width=2.0)
        t = np.radians(theta)
        u = np.arange(-20, 20, 0.05)
        prof = ndimage.map_coordinates(ink, [30 + u * np.sin(t), 30 + u * np.cos(t)], order=1)
        assert prof.sum() * 0.05 == pytest.approx(4.0, abs=0.1), theta


def _reference(s, q, d, g_eps, c_sparse, c_dense):
    """Eq. 13-15 transcribed, with the exact coverage of a pixel by a line of width d >= 1."""
    g = isotropic_eq9(s).astype(np.float64)
    k = np.floor((s - 0.0) / q + 0.5)  # Eq. 14
    with np.errstate(divide="ignore", invalid="ignore"):
        t_near = np.abs(s - k * q) / g
        t_far = q / g - t_near

        def f1(t):
            return np.clip(d / 2 + 0.5 - t, 0, 1)

        c = np.minimum(f1(np.nan_to_num(t_near, nan=0)) + f1(np.nan_to_num(t_far, nan=0)), 1)
        out = c.copy()
        sparse = g < g_eps
        out[sparse] = (g / g_eps * c + (1 - g / g_eps) * c_sparse)[sparse]  # Eq. 11
        dense = g >= q / d
        w = q / (d * g)
        out[dense] = (w * c + (1 - w) * c_dense)[dense]  # Eq. 15
    return out


@pytest.mark.parametrize("c_dense", (0.0, 0.5, 1.0))
def test_eq15_exactly_with_dense_spacing_equal_to_width(c_dense):
    y, x = np.mgrid[-1:1:200j, -1:1:200j]
    s = (x * y * 3 + 0.2 * np.sin(5 * x)).astype(np.float32)
    q, d, g_eps = 0.05, 1.5, 0.004
    ink = contour_lines(
        s, interval=q, width=d, g_eps=g_eps, c_sparse=0.25, c_dense=c_dense, dense_spacing=d
    )
    ref = _reference(s, q, d, g_eps, 0.25, c_dense)
    inner = (slice(1, -1), slice(1, -1))
    np.testing.assert_allclose(ink[inner], ref[inner], atol=2e-3)
    g = isotropic_eq9(s)
    assert (g < g_eps).sum() > 50 and (g >= q / d).sum() > 50  # both branches were exercised


def test_dense_regions_take_c_dense():
    s = ramp(2.0, 0.0, shape=(10, 50))  # lines 0.5 px apart: all dense
    for c_dense in (0.0, 0.5, 1.0):
        ink = contour_lines(s, interval=1.0, width=1.0, c_dense=c_dense)
        np.testing.assert_allclose(ink, c_dense, atol=1e-6)
    solid = contour_lines(s, interval=1.0, width=1.0)  # no dense handling: lines merge
    assert solid.min() == 1.0


def test_flat_regions_fade_to_c_sparse():
    s = ramp(1e-5, 0.0, shape=(10, 50))  # g = 1e-5 < g_eps = 1e-3
    for c_sparse in (0.0, 0.3):
        ink = contour_lines(s, interval=1.0, c_sparse=c_sparse)
        np.testing.assert_allclose(ink, c_sparse, atol=0.02)


# ---------------------------------------------------------------------------------------------
# Major / minor


def test_minor_lines_vanish_where_denser_than_their_width_majors_remain():
    x = np.arange(800, dtype=np.float64)
    s = np.tile((x**2 / 8000.0).astype(np.float32), (6, 1))  # g = x / 4000: 0 .. 0.2
    q, major = 0.05, 0.2
    both = contour_lines(s, interval=q, major_interval=major, width=1.0, major_width=2.0)
    majors = contour_lines(s, interval=major, width=2.0, g_eps=q / 1000)
    g = c1_discontinuity(s)
    crowded = q / g < 1.0  # minor spacing below the minor width
    assert crowded[3].sum() > 100
    np.testing.assert_allclose(both[crowded], majors[crowded], atol=1e-6)
    # majors are still drawn there
    lv = np.arange(major, s.max(), major)
    xs = np.sqrt(lv * 8000.0)
    for x0 in xs[crowded[3][np.clip(np.round(xs).astype(int), 0, 799)]]:
        assert both[3, round(x0)] >= 0.5
    # where minors are sparse (spacing > 2 widths) they are drawn at full ink
    lv = np.arange(q, s.max(), q)
    xs = np.sqrt(lv * 8000.0)
    sparse_x = xs[(q / (xs / 4000.0) > 2.5) & (xs > 20)]
    assert sparse_x.size > 5
    for x0 in sparse_x:
        assert both[3, round(x0) - 1 : round(x0) + 2].max() >= 0.5


# ---------------------------------------------------------------------------------------------
# Hatching


def _visible_lines(row: np.ndarray, width: float, share: float = 0.5) -> np.ndarray:
    """Centroids of the ink runs carrying at least ``share`` of a full line's ink."""
    labels, n = ndimage.label(row > 0.01)
    idx = np.arange(1, n + 1)
    total = ndimage.sum(row, labels, idx)
    x = np.arange(row.size)
    centre = ndimage.sum(row * x, labels, idx) / np.maximum(total, 1e-9)
    return centre[total >= share * width]


@pytest.mark.parametrize("share", (0.05, 0.5, 0.95))
@pytest.mark.parametrize("spacing", (6.0, 10.0))
def test_hatching_spacing_within_35_percent_over_16x_gradients(spacing, share):
    """Whatever share of a line's ink counts it as visible, neighbouring lines stay within
    +-35% of the spacing over every phase of the binary thinning (g grows 17x)."""
    x = np.arange(40, 680, dtype=np.float64)
    s = np.tile((x**2 / 3000.0).astype(np.float32), (5, 1))
    g = x / 1500.0
    assert g.max() / g.min() >= 16
    ink = hatching(s, spacing=spacing, width=1.5, interval=0.5)
    c = _visible_lines(ink[2], 1.5, share)
    c = c[(c > 3) & (c < ink.shape[1] - 4)]
    gaps = np.diff(c)
    assert gaps.size > 40
    assert np.all(np.abs(gaps / spacing - 1) <= 0.35), gaps / spacing


def test_hatching_paper_transition_keeps_the_mean_density():
    """transition=1 is Eq. 18: the in-between lines fade in linearly, so the ink per pixel
    stays width / spacing."""
    x = np.arange(40, 1064, dtype=np.float64)
    s = np.tile((x**2 / 3000.0).astype(np.float32), (3, 1))
    ink = hatching(s, spacing=8.0, width=1.0, interval=0.5, transition=1.0)[1]
    win = 64
    dens = np.convolve(ink, np.ones(win) / win, mode="valid")
    assert np.all(np.abs(dens * 8.0 - 1) < 0.2), dens.min() * 8


def test_hatching_lines_follow_the_field_levels():
    """On a ramp, hatch lines are level lines of the field: columns of a vertical ramp."""
    s = ramp(0.01, 0.0, shape=(30, 200))
    ink = hatching(s, spacing=8.0, width=1.0, interval=1.0)[:, 1:-1]  # corners extrapolate less
    np.testing.assert_allclose(ink, ink[0:1, :].repeat(30, 0), atol=1e-5)
    # g = 0.01 per px, p_d = 1: the interval p_n = 2^n with 8 < p_n / 0.01 <= 16 is 0.125,
    # 12.5 px apart; 12.5 / 8 > 4/3, so the lines halfway are in: 6.25 px
    c = _visible_lines(ink[0], 1.0)
    np.testing.assert_allclose(np.diff(c[1:]), 6.25, atol=0.05)
    lv = 0.01 * (c[1:] + 1) + 0.37  # the field at the line centres (column 0 was cropped)
    np.testing.assert_allclose(lv / 0.0625, np.round(lv / 0.0625), atol=0.05)


# ---------------------------------------------------------------------------------------------
# Holes, masks, flat data


def test_nan_hole_and_mask_leave_the_lines_around_them_unchanged():
    s = ramp(0.1, 30.0, shape=(80, 120))
    ref = contour_lines(s, interval=1.0, width=2.0)
    holed = s.copy()
    holed[30:50, 40:70] = np.nan
    hole = ~np.isfinite(holed)
    a = contour_lines(holed, interval=1.0, width=2.0)
    b = contour_lines(s, interval=1.0, width=2.0, mask=~hole)
    for ink in (a, b):
        assert np.all(ink[hole] == 0)
        np.testing.assert_allclose(ink[~hole], ref[~hole], atol=1e-5)
    inf = s.copy()
    inf[0, 0] = np.inf
    assert contour_lines(inf, interval=1.0)[0, 0] == 0


def test_constant_field_gives_no_ink():
    for value in (0.0, 5.0, 2.5):
        s = np.full((50, 60), value, np.float32)
        assert not contour_lines(s, interval=5.0).any()
        assert not contour_lines(s, levels=[value]).any()
        assert not hatching(s).any()


def test_near_flat_noise_gives_no_noise():
    rng = np.random.default_rng(1)
    s = (100.0 + 1e-5 * rng.standard_normal((200, 200))).astype(np.float32)
    assert contour_lines(s, interval=5.0).max() < 0.01


def test_srtm_tile_flat_sea_no_noise_no_crash(shared_data):
    hgt = np.fromfile(shared_data / "dem" / "N10W110.hgt", ">i2").reshape(1201, 1201)
    before = hgt.copy()
    land = hgt > 0
    near_land = ndimage.binary_dilation(land, iterations=3)
    for kw in ({"interval": 1.0}, {"interval": 5.0, "major_interval": 10.0}, {"levels": [2]}):
        ink = contour_lines(hgt, **kw)
        assert ink.dtype == np.float32 and ink.shape == hgt.shape
        assert np.all(np.isfinite(ink)) and ink.min() >= 0 and ink.max() <= 1
        assert not ink[~near_land].any()  # the open sea is blank
        assert ink[near_land].max() == 1.0  # the atoll's contours are drawn
    h = hatching(hgt, spacing=6.0)
    assert not h[~near_land].any() and np.all(np.isfinite(h))
    np.testing.assert_array_equal(hgt, before)


# ---------------------------------------------------------------------------------------------
# Equivalences and API


def test_levels_equal_the_regular_interval():
    y, x = np.mgrid[-1:1:120j, -1:1:120j]
    s = (x**2 - y**2 + 0.1 * x).astype(np.float32)
    lv = 0.3 + 0.1 * np.arange(-20, 20)
    a = contour_lines(s, interval=0.1, base=0.3, g_eps=0.0)
    b = contour_lines(s, levels=lv, g_eps=0.0)
    np.testing.assert_allclose(a, b, atol=1e-3)


def test_own_gradient_equals_the_default():
    y, x = np.mgrid[-1:1:50j, -1:1:70j]
    s = (3 * x * y + np.sin(4 * x)).astype(np.float32)
    inner = (slice(1, -1), slice(1, -1))
    a = contour_lines(s, interval=0.1, width=1.5)
    b = contour_lines(s, interval=0.1, width=1.5, gradient=isotropic_eq9(s))
    np.testing.assert_allclose(a[inner], b[inner], atol=2e-3)
    c = hatching(s, spacing=6.0, gradient=isotropic_eq9(s))
    np.testing.assert_allclose(c[inner], hatching(s, spacing=6.0)[inner], atol=2e-3)
    s = ramp(0.07, 20.0, shape=(50, 70))
    a = contour_lines(s, interval=1.0, width=1.5)
    doubled = contour_lines(s, interval=1.0, width=1.5, gradient=2 * isotropic_eq9(s))
    assert doubled.sum() == pytest.approx(a.sum() * 2, rel=0.05)  # t halves: lines twice as wide


def test_inputs_not_modified_and_read_only_ok():
    s = ramp(0.1, 10.0, shape=(20, 30))
    s.setflags(write=False)
    m = np.ones(s.shape, bool)
    m.setflags(write=False)
    before = s.copy()
    contour_lines(s, interval=1.0, mask=m)
    hatching(s, mask=m)
    np.testing.assert_array_equal(s, before)


def test_integer_dem_accepted():
    s = (np.arange(40)[None, :] * np.ones((10, 1))).astype(np.int16)
    ink = contour_lines(s, interval=10)
    assert ink.dtype == np.float32 and ink[:, 10].min() == 1.0


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({}, "exactly one of"),
        ({"interval": 1.0, "levels": [1]}, "exactly one of"),
        ({"interval": 0.0}, "interval"),
        ({"interval": np.nan}, "interval"),
        ({"levels": []}, "levels"),
        ({"levels": [1, np.inf]}, "levels"),
        ({"interval": 1.0, "width": -1}, "width"),
        ({"interval": 1.0, "profile": "cubic"}, "profile"),
        ({"interval": 1.0, "c_dense": 2.0}, "c_dense"),
        ({"interval": 1.0, "c_sparse": -0.1}, "c_sparse"),
        ({"interval": 1.0, "g_eps": -1.0}, "g_eps"),
        ({"interval": 1.0, "dense_spacing": 3.0}, "dense_spacing"),
        ({"levels": [1.0], "major_interval": 5.0}, "major_interval"),
        ({"interval": 1.0, "major_width": 3.0}, "major_width"),
        ({"interval": 1.0, "base": np.inf}, "base"),
        ({"interval": 1.0, "mask": np.ones((3, 3), bool)}, "mask"),
        ({"interval": 1.0, "gradient": np.ones((3, 3))}, "gradient"),
    ],
)
def test_contour_lines_rejects(kwargs, word):
    with pytest.raises(InputError, match=word):
        contour_lines(np.zeros((8, 9), np.float32), **kwargs)


@pytest.mark.parametrize(
    ("field", "kwargs", "word"),
    [
        (np.zeros((8, 9)), {"spacing": 0}, "spacing"),
        (np.zeros((8, 9)), {"interval": -2}, "interval"),
        (np.zeros((8, 9)), {"transition": 0}, "transition"),
        (np.zeros((8, 9)), {"transition": 1.5}, "transition"),
        (np.zeros((2, 3, 4)), {}, "field"),
        (np.zeros((0, 3)), {}, "field"),
        (np.array([["a"]]), {}, "field"),
    ],
)
def test_hatching_rejects(field, kwargs, word):
    with pytest.raises(InputError, match=word):
        hatching(field, **kwargs)


_fields = hnp.arrays(
    np.float32,
    hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=9),
    elements=st.one_of(
        st.floats(-1e6, 1e6, width=32),
        st.sampled_from([np.nan, np.inf, -np.inf, 0.0, 3e38, -3e38, 1e-38]),
    ),
)


@settings(max_examples=150, deadline=None)
@given(
    field=_fields,
    interval=st.floats(1e-3, 1e4),
    width=st.floats(0.1, 10),
    profile=st.sampled_from(PROFILES),
    c_dense=st.one_of(st.none(), st.floats(0, 1)),
    major=st.booleans(),
)
def test_contour_lines_odd_inputs_never_crash(field, interval, width, profile, c_dense, major):
    ink = contour_lines(
        field,
        interval=interval,
        width=width,
        profile=profile,
        c_dense=c_dense,
        major_interval=4 * interval if major else None,
    )
    assert ink.shape == field.shape and ink.dtype == np.float32
    assert np.all(np.isfinite(ink)) and ink.min() >= 0 and ink.max() <= 1
    assert np.all(ink[~np.isfinite(field)] == 0)
    lv = contour_lines(field, levels=[0.0, interval], width=width, profile=profile)
    assert np.all(np.isfinite(lv)) and lv.min() >= 0 and lv.max() <= 1


@settings(max_examples=100, deadline=None)
@given(
    field=_fields,
    spacing=st.floats(0.5, 50),
    interval=st.floats(1e-3, 1e4),
    transition=st.floats(0.01, 1),
)
def test_hatching_odd_inputs_never_crash(field, spacing, interval, transition):
    ink = hatching(field, spacing=spacing, interval=interval, transition=transition)
    assert ink.shape == field.shape and ink.dtype == np.float32
    assert np.all(np.isfinite(ink)) and ink.min() >= 0 and ink.max() <= 1


# ---------------------------------------------------------------------------------------------
# Vector export


def test_polylines_agree_with_find_contours_and_the_raster():
    y, x = np.mgrid[-1:1:151j, -1:1:151j]
    s = (x**2 + y**2).astype(np.float32)
    lines = contour_polylines(s, interval=0.25, major_interval=0.5)
    assert [ln.level for ln in lines] == sorted(ln.level for ln in lines)
    # levels 0 and 2 are the minimum's and the corners' own values: no line (not a ring
    # of one point); 1.25 to 1.75 are arcs across the corners
    assert {ln.level for ln in lines} == {0.25 * k for k in range(1, 8)}
    rings = [ln for ln in lines if ln.closed]
    # the circle of level 1 touches the square's edges at four cells: it may end there
    assert {ln.level for ln in rings} >= {0.25, 0.5, 0.75}
    assert {ln.level: ln.major for ln in lines} == {k / 4: k % 2 == 0 for k in range(1, 8)}
    for level in (0.25, 0.5, 0.75):
        # the same crossings as scikit-image's marching squares (an independent tracer)
        ref = np.concatenate(measure.find_contours(s, level))[:, ::-1]
        got = np.concatenate([ln.points for ln in lines if ln.level == level])
        key = lambda a: set(map(tuple, np.round(a, 6)))  # noqa: E731
        assert key(got) == key(ref)
    ink = contour_lines(s, interval=0.25, width=1.5)
    for ln in lines:
        r = np.sqrt(ln.level) * 75  # radius in px
        np.testing.assert_allclose(
            np.hypot(ln.points[:, 0] - 75, ln.points[:, 1] - 75), r, atol=0.5
        )
        vals = ndimage.map_coordinates(ink, [ln.points[:, 1], ln.points[:, 0]], order=1)
        assert vals.min() >= 0.5


def test_polylines_many_levels_are_bounded_by_their_crossings():
    """100000 levels are allowed where they cross few cells, and refused (before tracing)
    where they would make more than LIMITS["segments"] segments."""
    s = np.add.outer(np.arange(40.0), np.arange(50.0)).astype(np.float32)  # 0 .. 88
    lines = contour_polylines(s, levels=np.linspace(10.0, 10.5, 100_000))
    assert len({ln.level for ln in lines}) == 100_000
    assert all(not ln.closed for ln in lines)
    big = np.add.outer(np.arange(2000.0), np.arange(2000.0)).astype(np.float32)
    with pytest.raises(InputError, match="segments"):
        contour_polylines(big, levels=np.linspace(0.0, 3998.0, 100_000))


def test_polylines_respect_nan_and_transform():
    s = ramp(0.1, 0.0, shape=(20, 50))
    s[:, 20:30] = np.nan
    lines = contour_polylines(s, interval=1.0)
    for ln in lines:
        assert not np.any((ln.points[:, 0] > 19) & (ln.points[:, 0] < 30))
    geo = contour_polylines(s, interval=1.0, transform=(500000.0, 30.0, 0.0, 4e6, 0.0, -30.0))
    a, b = lines[0].points, geo[0].points
    np.testing.assert_allclose(b[:, 0], 500000.0 + (a[:, 0] + 0.5) * 30.0)
    np.testing.assert_allclose(b[:, 1], 4e6 - (a[:, 1] + 0.5) * 30.0)
    fc = polylines_to_geojson(geo, crs="EPSG:32613")
    assert fc["type"] == "FeatureCollection" and len(fc["features"]) == len(geo)
    f0 = fc["features"][0]
    assert f0["geometry"]["type"] == "LineString"
    assert f0["properties"]["level"] == geo[0].level
    assert fc["crs"]["properties"]["name"] == "EPSG:32613"


def test_polylines_empty_and_errors():
    assert contour_polylines(np.full((5, 5), np.nan), interval=1.0) == []
    with pytest.raises(InputError, match="levels"):
        contour_polylines(np.zeros((5, 5)), interval=1.0, levels=[1])
    with pytest.raises(InputError, match="transform"):
        contour_polylines(np.zeros((5, 5)), interval=1.0, transform=(1, 2, 3))
    with pytest.raises(InputError, match="at most"):
        contour_polylines(np.array([[0.0, 1e9]]), interval=1e-3)


def test_generalised_lines_do_not_depend_on_the_smoothing_strips(monkeypatch):
    """The smoothing runs in row strips (bounded memory): the same pixels as in one piece."""
    from sciviz_gbuf.filters import _contour_generalize

    rng = np.random.default_rng(5)
    z = np.cumsum(rng.normal(size=(120, 70)), axis=0).astype(np.float32)
    z[rng.random(z.shape) < 0.03] = np.nan
    whole = contour_lines(z, interval=2.0, generalize=True)
    monkeypatch.setattr(_contour_generalize, "STRIP_ROWS", 7)
    assert np.array_equal(contour_lines(z, interval=2.0, generalize=True), whole)
    assert not np.array_equal(contour_lines(z, interval=2.0), whole)  # it did generalise


def test_generalize_options_are_checked():
    z = np.zeros((5, 5), np.float32)
    with pytest.raises(InputError, match="min_ring: only used with generalize=True"):
        contour_lines(z, interval=1.0, min_ring=3.0)
    with pytest.raises(InputError, match="gradient: not used with generalize=True"):
        contour_lines(z, interval=1.0, generalize=True, gradient=z)
    with pytest.raises(InputError, match="generalize: expected True or False"):
        contour_lines(z, interval=1.0, generalize=1)
    with pytest.raises(InputError, match="min_ring: expected a number in"):
        contour_lines(z, interval=1.0, generalize=True, min_ring=-1.0)


# ------------------------------------------- the local linear fit: numba kernel vs scipy passes
@pytest.mark.parametrize("sigma", [1.0, 2.0, 4.0])
def test_local_linear_kernel_equals_the_scipy_passes(sigma):
    """The generalisation's fits (a, b, c) by the numba kernel and by fourteen
    ``correlate1d`` passes: equal within float64 rounding on rough heights with scattered
    nodata, a lake and the grid's edges; a plane is kept exactly (up to rounding) by both."""
    from sciviz_gbuf.filters import _contour_generalize as G

    rng = np.random.default_rng(5)
    z = np.cumsum(np.cumsum(rng.standard_normal((90, 131)), 0), 1) + 1500.0
    valid = rng.random(z.shape) > 0.03
    valid[30:45, 60:90] = False
    for fast, slow in zip(G.local_linear(z, valid, sigma),
                          G.local_linear_reference(z, valid, sigma), strict=True):  # fmt: skip
        np.testing.assert_array_equal(np.isfinite(fast), np.isfinite(slow))
        ok = np.isfinite(slow)
        np.testing.assert_allclose(fast[ok], slow[ok], rtol=1e-9, atol=1e-9)
    yy, xx = np.mgrid[0:40, 0:50]
    plane = 3.0 + 0.5 * xx - 0.25 * yy
    a, b, c = G.local_linear(plane, np.ones(plane.shape, bool), sigma)
    np.testing.assert_allclose(a, plane, atol=1e-9)
    np.testing.assert_allclose(b, 0.5, atol=1e-9)
    np.testing.assert_allclose(c, -0.25, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(
    hnp.arrays(
        np.float64, st.tuples(st.integers(1, 12), st.integers(1, 12)), elements=st.floats(-100, 100)
    ),
    st.data(),
)
def test_local_linear_kernel_on_odd_grids(z, data):
    from sciviz_gbuf.filters import _contour_generalize as G

    valid = data.draw(hnp.arrays(np.bool_, z.shape))
    for fast, slow in zip(G.local_linear(z, valid, 2.0), G.local_linear_reference(z, valid, 2.0),
                          strict=True):  # fmt: skip
        np.testing.assert_array_equal(np.isfinite(fast), np.isfinite(slow))
        ok = np.isfinite(slow)
        np.testing.assert_allclose(fast[ok], slow[ok], rtol=1e-7, atol=1e-7)


# --------------------------------- the blend of the fits: one numba pass vs the numpy statement
@pytest.mark.parametrize("interval", [0.5, 2.0, 20.0])
def test_smooth_strip_kernel_equals_the_array_statement(interval):
    """The generalised field and gradient by the blend kernel and by numpy's expressions: the
    same float32 values bit for bit (rough heights with nodata, a lake, an exactly flat sea,
    the grid's edges; intervals that ask for no, some and the widest smoothing)."""
    from sciviz_gbuf.filters import _contour_generalize as G

    rng = np.random.default_rng(7)
    z = (np.cumsum(np.cumsum(rng.standard_normal((70, 97)), 0), 1) * 3 + 1500).astype(np.float32)
    valid = rng.random(z.shape) > 0.03
    valid[20:30, 40:70] = False
    z[45:60, :] = 1500.0
    z[~valid] = np.nan
    for fast, slow in zip(G.smooth_strip(z, valid, interval),
                          G.smooth_strip_reference(z, valid, interval), strict=True):  # fmt: skip
        assert fast.dtype == slow.dtype == np.float32
        np.testing.assert_array_equal(fast, slow)


@settings(max_examples=40, deadline=None)
@given(
    hnp.arrays(
        np.float32,
        st.tuples(st.integers(1, 30), st.integers(1, 30)),
        elements=st.floats(-50, 50, width=32),
    ),
    st.data(),
)
def test_smooth_strip_kernel_on_odd_grids(z, data):
    from sciviz_gbuf.filters import _contour_generalize as G

    valid = data.draw(hnp.arrays(np.bool_, z.shape))
    z = np.where(valid, z, np.nan).astype(np.float32)
    for fast, slow in zip(G.smooth_strip(z, valid, 1.0), G.smooth_strip_reference(z, valid, 1.0),
                          strict=True):  # fmt: skip
        np.testing.assert_array_equal(fast, slow)


# -------------------------------------------- tiles of the smoothing and the cut cells' kernel
def test_smooth_field_by_tiles_equals_one_piece(monkeypatch):
    """The whole field smoothed tile by tile on two threads (tiles of 32 x 48 cells read with
    the smoothing's reach around them) equals one piece bit for bit: nodata near tile
    corners, a lake across tiles, flat ground and the grid's edges."""
    from sciviz_gbuf.filters import _contour_generalize as G

    rng = np.random.default_rng(11)
    z = (np.cumsum(np.cumsum(rng.standard_normal((150, 173)), 0), 1) * 2 + 900).astype(np.float32)
    valid = rng.random(z.shape) > 0.02
    valid[60:90, 40:110] = False
    z[100:120, :] = 900.0
    z[~valid] = np.nan
    whole = G.smooth_strip(z, valid, 5.0)
    monkeypatch.setattr(G, "STRIP_ROWS", 32)
    monkeypatch.setattr(G, "TILE_COLS", 48)
    tiled = G.smooth_field(z, valid, 5.0)
    for a, b in zip(tiled, whole, strict=True):
        np.testing.assert_array_equal(a, b)
    assert np.nanstd(whole[0] - z) > 0.1  # the smoothing did move heights


@pytest.mark.parametrize("interval", [0.05, 3.0, 12.0, 400.0])
def test_fused_route_equals_the_separate_kernels(interval, monkeypatch):
    """A tile whose windows are all full goes through ``fused_rows`` (the fits of widths 1,
    2, 4 and the blend in one pass of rows, the wider fits only on rows that ask for them):
    the same float32 bits as the separate kernels, over steep and flat rows in one tile,
    an exactly flat stretch, columns beyond FUSED_COLS and a last column block narrower
    than it."""
    from sciviz_gbuf.filters import _contour_generalize as G

    rng = np.random.default_rng(5)
    h, w = 90, G.FUSED_COLS + 77 + 2 * G.SMOOTH_RADIUS
    z = np.cumsum(np.cumsum(rng.standard_normal((h, w)), 0), 1) * 0.4 + 700
    z[:, : w // 3] *= 0.05  # gentle ground beside steep ground: rows with and without
    z[40:47, :] = 700.0  # the wide fits, and a flat stretch
    z = z.astype(np.float32)
    valid = np.ones(z.shape, bool)
    r = G.SMOOTH_RADIUS
    inner = (r, h - r, r, w - r)
    assert G._fused_ok(valid, inner)
    fused = G.smooth_strip(z, valid, interval, serial=True, inner=inner)
    reference = G.smooth_strip_reference(z, valid, interval)
    for a, b in zip(fused, reference, strict=True):
        np.testing.assert_array_equal(a, b[r : h - r, r : w - r])
    # the whole field by tiles (the sides' cells in tiles of their own, the others fused):
    # the same bits as one piece by the separate kernels
    monkeypatch.setattr(G, "STRIP_ROWS", 32)
    monkeypatch.setattr(G, "TILE_COLS", 100)
    for a, b in zip(G.smooth_field(z, valid, interval), reference, strict=True):
        np.testing.assert_array_equal(a, b)
    # one nodata cell in a window, or a window over the edge: the separate kernels
    valid[5, 40] = False
    assert not G._fused_ok(valid, inner)
    assert not G._fused_ok(np.ones(z.shape, bool), (r - 1, h - r, r, w - r))


@settings(max_examples=60, deadline=None)
@given(hnp.arrays(np.bool_, st.tuples(st.integers(1, 9), st.integers(1, 11))))
def test_cut_cells_is_the_dilated_nodata_and_the_edge(valid):
    from sciviz_gbuf.filters import _contour_generalize as G

    expected = ndimage.binary_dilation(~valid, structure=np.ones((3, 3), bool))
    expected[0, :] = expected[-1, :] = expected[:, 0] = expected[:, -1] = True
    np.testing.assert_array_equal(G.cut_cells(valid), expected)
