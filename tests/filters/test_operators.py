"""The 3x3 discontinuity operators against a slow, literal reference, plus analytic properties
and odd inputs (hypothesis)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import (
    c1_discontinuity,
    diagonal_depth_discontinuity,
    diagonal_normal_discontinuity,
    normalize_gradient,
    second_order,
    sobel_gradient,
    suppress_zeroth_order,
)

# --------------------------------------------------------------------------- slow reference
OFFS = {  # Saito's Fig. 1: A B C / D X E / F G H
    "A": (-1, -1), "B": (-1, 0), "C": (-1, 1),
    "D": (0, -1), "E": (0, 1),
    "F": (1, -1), "G": (1, 0), "H": (1, 1),
}  # fmt: skip


def _valid(img, mask, r, c):
    h, w = img.shape
    if not (0 <= r < h and 0 <= c < w):
        return False
    return bool(np.isfinite(img[r, c])) and (mask is None or bool(mask[r, c]))


OPPOSITE = {"A": "H", "B": "G", "C": "F", "D": "E", "E": "D", "F": "C", "G": "B", "H": "A"}


# For an axis neighbour missing together with its opposite: the two diagonals beside it; for
# a diagonal one: the two axis neighbours beside it (plane through X and them).
BESIDE = {"B": "AC", "D": "AF", "E": "CH", "G": "FH", "A": "BD", "C": "BE", "F": "DG", "H": "EG"}


def _window(img, mask, r, c, extrapolate=True):
    """The documented border rule, written out: an invalid neighbour becomes 2X - opposite
    (when the opposite one is valid and ``extrapolate``); else an axis neighbour the mean of
    the two valid diagonal ones beside it, a diagonal one ``p + q - X`` of its two axis
    neighbours (after this rule); else the centre value X."""
    x = float(img[r, c])
    big = float(np.finfo(np.float32).max)
    nb = {}
    for k in "BDEGACFH":  # axis neighbours first: the diagonals use them
        dr, dc = OFFS[k]
        odr, odc = OFFS[OPPOSITE[k]]
        if _valid(img, mask, r + dr, c + dc):
            nb[k] = float(img[r + dr, c + dc])
        elif extrapolate and _valid(img, mask, r + odr, c + odc):
            nb[k] = float(np.clip(2 * x - float(img[r + odr, c + odc]), -big, big))
        elif extrapolate and k in "BDEG":
            s1, s2 = (OFFS[b] for b in BESIDE[k])
            if _valid(img, mask, r + s1[0], c + s1[1]) and _valid(img, mask, r + s2[0], c + s2[1]):
                mean = 0.5 * float(img[r + s1[0], c + s1[1]]) + 0.5 * float(
                    img[r + s2[0], c + s2[1]]
                )
                nb[k] = float(np.clip(mean, -big, big))
            else:
                nb[k] = x
        elif extrapolate:
            p, q = BESIDE[k]
            nb[k] = float(np.clip(nb[p] + nb[q] - x, -big, big))
        else:
            nb[k] = x
    return x, nb


def reference(name, img, mask=None, k=None, aux=None):
    h, w = img.shape
    neutral = 1.0 if name == "diag_depth" else 0.0
    out = np.full((h, w), neutral)
    for r in range(h):
        for c in range(w):
            if not _valid(img, mask, r, c) or (aux is not None and not np.isfinite(aux[r, c])):
                continue
            x, n = _window(img, mask, r, c, extrapolate=name not in ("normalize", "suppress"))
            A, B, C, D, E, F, G, H = (n[q] for q in "ABCDEFGH")
            if name == "sobel":
                v = (abs(A + 2 * B + C - F - 2 * G - H) + abs(C + 2 * E + H - A - 2 * D - F)) / 8
            elif name == "second":
                v = (8 * x - A - B - C - D - E - F - G - H) / 3
            elif name == "c1":
                v = (
                    sum(
                        wt * abs(n[q] - x)
                        for q, wt in zip("ABCDEFGH", (1, 2, 1, 2, 2, 1, 2, 1), strict=True)
                    )
                    / 8
                )
            elif name == "diag_depth":
                v = (1 - min(abs(A - H), 2) / 2) ** 2 * (1 - min(abs(C - F), 2) / 2) ** 2
            elif name == "normalize":
                vals = [x, *n.values()]
                lo, hi = min(vals), max(vals)
                v = (x - lo) / (hi - lo) if hi - lo > k else (x - lo) / k
            elif name == "suppress":
                gmax = max([x, *n.values()])
                v = aux[r, c] if gmax <= k else aux[r, c] / (gmax / k) ** 2
            out[r, c] = v
    return out


def reference_diag_normal(n, mask=None):
    h, w = n.shape[:2]
    ok = np.isfinite(n).all(axis=2) & (np.ones((h, w), bool) if mask is None else mask)
    out = np.ones((h, w))
    for r in range(h):
        for c in range(w):
            if not ok[r, c]:
                continue

            def nb(rr, cc, r=r, c=c):
                inside = 0 <= rr < h and 0 <= cc < w
                return n[rr, cc] if inside and ok[rr, cc] else n[r, c]

            ah = float(np.dot(nb(r - 1, c - 1), nb(r + 1, c + 1)))
            cf = float(np.dot(nb(r - 1, c + 1), nb(r + 1, c - 1)))
            out[r, c] = min(1.0, max(-1.0, (ah + cf) / 2))
    return out


def _random_case(seed, h=23, w=31):
    rng = np.random.default_rng(seed)
    img = rng.normal(size=(h, w)).astype(np.float32) * 3
    img[rng.random((h, w)) < 0.05] = np.nan
    img[rng.random((h, w)) < 0.02] = np.inf
    mask = rng.random((h, w)) > 0.2
    return img, mask


# --------------------------------------------------------------------------- vs reference
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("use_mask", [False, True])
def test_operators_match_reference(seed, use_mask):
    img, mask = _random_case(seed)
    m = mask if use_mask else None
    np.testing.assert_allclose(sobel_gradient(img, mask=m), reference("sobel", img, m), 1e-5, 1e-5)
    np.testing.assert_allclose(second_order(img, mask=m), reference("second", img, m), 1e-5, 1e-5)
    np.testing.assert_allclose(c1_discontinuity(img, mask=m), reference("c1", img, m), 1e-5, 1e-5)
    small = img / 4  # differences of order 1, as for a normalised z-buffer
    np.testing.assert_allclose(
        diagonal_depth_discontinuity(small, mask=m), reference("diag_depth", small, m), 1e-5, 1e-5
    )
    g = sobel_gradient(img, mask=m)
    for k_g in (0.5, 10.0):
        np.testing.assert_allclose(
            normalize_gradient(g, k_g=k_g, mask=m),
            reference("normalize", g, m, k=k_g),
            1e-5,
            1e-5,
        )
    lap = second_order(img, mask=m)
    np.testing.assert_allclose(
        suppress_zeroth_order(lap, g, k_l=2.0, mask=m),
        reference("suppress", g, m, k=2.0, aux=lap),
        1e-5,
        1e-5,
    )


@pytest.mark.parametrize("use_mask", [False, True])
def test_diagonal_normal_matches_reference(use_mask):
    rng = np.random.default_rng(5)
    n = rng.normal(size=(17, 19, 3)).astype(np.float32)
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    n[rng.random((17, 19)) < 0.05] = np.nan
    mask = rng.random((17, 19)) > 0.2 if use_mask else None
    np.testing.assert_allclose(
        diagonal_normal_discontinuity(n, mask=mask), reference_diag_normal(n, mask), 1e-5, 1e-5
    )


def test_large_image_rows_and_columns_match_reference_at_borders():
    # Wide and tall images exercise the vectorised interior and both border columns / rows.
    for shape in [(1, 40), (40, 1), (2, 3), (3, 2), (5, 70)]:
        img, mask = _random_case(7, *shape)
        np.testing.assert_allclose(
            sobel_gradient(img, mask=mask), reference("sobel", img, mask), 1e-5, 1e-5
        )
        np.testing.assert_allclose(c1_discontinuity(img), reference("c1", img), 1e-5, 1e-5)


# --------------------------------------------------------------------------- analytic
def _ramp(h, w, sx, sy, z0=100.0):
    yy, xx = np.mgrid[:h, :w].astype(np.float64)
    return (z0 + sx * xx + sy * yy).astype(np.float32)


@pytest.mark.parametrize(("sx", "sy"), [(0.7, 0.0), (0.0, -2.5), (1.5, 0.5)])
def test_sobel_is_the_per_pixel_slope_and_second_order_vanishes_on_a_plane(sx, sy):
    img = _ramp(20, 30, sx, sy)
    g = sobel_gradient(img)[1:-1, 1:-1]
    np.testing.assert_allclose(g, abs(sx) + abs(sy), rtol=1e-4)  # Eq. 1 is per pixel
    np.testing.assert_allclose(second_order(img)[1:-1, 1:-1], 0.0, atol=1e-3)
    np.testing.assert_allclose(diagonal_depth_discontinuity(img / 100)[1:-1, 1:-1] <= 1.0, True)


def test_step_gives_profile_and_convex_edge_has_positive_second_order():
    step = np.zeros((20, 20), np.float32)
    step[:, 10:] = 50.0
    p = normalize_gradient(sobel_gradient(step), k_g=10.0)
    assert p[2:-2, 9:11].min() == pytest.approx(1.0)  # both sides of the step peak
    assert p[:, :8].max() == 0.0 and p[:, 12:].max() == 0.0
    roof = -np.abs(np.arange(21, dtype=np.float32) - 10)[None, :].repeat(9, 0) * 2  # ridge
    lap = second_order(roof)
    assert lap[4, 10] > 0 and np.abs(lap[4, 1:9]).max() < 1e-5  # convex = positive
    # Eq. 4 keeps first-order edges and suppresses the double line of a 0th-order step.
    g = sobel_gradient(roof)
    np.testing.assert_allclose(suppress_zeroth_order(lap, g, k_l=2.0)[4, 10], lap[4, 10])
    e = suppress_zeroth_order(second_order(step), sobel_gradient(step), k_l=2.0)
    assert np.abs(e).max() < 0.02 * np.abs(second_order(step)).max()


def test_c1_and_diagonal_respond_to_a_depth_step_only():
    z = np.full((12, 12), 0.2, np.float32)
    z[:, 6:] = 0.9
    c1 = c1_discontinuity(z)
    assert c1[1:-1, 5:7].min() == pytest.approx(0.7 * 4 / 8)
    assert c1[:, :4].max() == 0 and c1[:, 8:].max() == 0
    iz = diagonal_depth_discontinuity(z)
    assert iz[:, 5:7].max() < 0.5 and iz[:, :4].min() == 1.0


def test_diagonal_normals_right_angle_crease_gives_zero():
    n = np.zeros((10, 10, 3), np.float32)
    n[:, :5] = (1, 0, 0)
    n[:, 5:] = (0, 0, 1)
    i_n = diagonal_normal_discontinuity(n)
    np.testing.assert_allclose(i_n[1:-1, 4:6], 0.0, atol=1e-6)
    np.testing.assert_allclose(i_n[:, :3], 1.0)


# --------------------------------------------------------------------------- border rule
def test_background_never_creates_or_hides_an_edge():
    rng = np.random.default_rng(3)
    img = _ramp(30, 30, 0.3, 0.2)
    yy, xx = np.mgrid[:30, :30]
    mask = (yy - 15) ** 2 + (xx - 15) ** 2 < 100
    a = img.copy()
    b = img.copy()
    b[~mask] = rng.normal(size=(~mask).sum()) * 1e6  # wild background values
    b[~mask][::3] = np.nan
    for op in (sobel_gradient, second_order, c1_discontinuity):
        ra, rb = op(a, mask=mask), op(b, mask=mask)
        np.testing.assert_array_equal(ra, rb)  # background values are never read
        assert (ra[~mask] == 0).all()
    # A plane gives its interior response right up to the coverage border and image border.
    # (all but the few pixels where a neighbour and its opposite are both uncovered)
    g_plane = sobel_gradient(img, mask=mask)
    assert np.mean(np.abs(g_plane[mask] - 0.5) < 1e-4) > 0.98
    assert np.mean(np.abs(second_order(img, mask=mask)[mask]) < 1e-3) > 0.98
    np.testing.assert_allclose(second_order(img)[[0, -1]], 0.0, atol=1e-3)
    # A covered step next to the background is still seen at full strength.
    s = np.where(xx < 15, 0.0, 40.0).astype(np.float32)
    g = sobel_gradient(s, mask=mask)
    assert g[15, 14] == pytest.approx(sobel_gradient(s)[15, 14])
    # Constant covered values against a background: no response anywhere.
    flat = np.where(mask, 7.0, np.nan).astype(np.float32)
    for op in (sobel_gradient, second_order, c1_discontinuity):
        assert np.abs(op(flat)).max() == 0.0
    assert (diagonal_depth_discontinuity(flat) == 1.0).all()


def test_inputs_are_not_modified_and_errors_name_the_parameter():
    img, mask = _random_case(1)
    keep = img.copy()
    sobel_gradient(img, mask=mask)
    np.testing.assert_array_equal(img, keep)
    with pytest.raises(InputError, match="image"):
        sobel_gradient(np.zeros((3, 3, 3)))
    with pytest.raises(InputError, match="image"):
        second_order(np.zeros((0, 4)))
    with pytest.raises(InputError, match="mask"):
        c1_discontinuity(np.zeros((3, 3)), mask=np.ones((2, 3), bool))
    with pytest.raises(InputError, match="k_g"):
        normalize_gradient(np.zeros((3, 3)), k_g=0)
    with pytest.raises(InputError, match="k_l"):
        suppress_zeroth_order(np.zeros((3, 3)), np.zeros((3, 3)), k_l=math.nan)
    with pytest.raises(InputError, match="gradient"):
        suppress_zeroth_order(np.zeros((3, 3)), np.zeros((3, 4)))
    with pytest.raises(InputError, match="normal"):
        diagonal_normal_discontinuity(np.zeros((3, 3)))
    with pytest.raises(InputError, match="image"):
        sobel_gradient(np.array([["a"]]))


# --------------------------------------------------------------------------- odd inputs
_floats = st.one_of(
    st.floats(width=32, allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, 1.0, -1.0, 3.4e38, -3.4e38, 1e-45]),
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    img=hnp.arrays(
        np.float32,
        st.tuples(st.integers(1, 6), st.integers(1, 7)),
        elements=_floats,
    ),
    data=st.data(),
)
def test_odd_images_never_crash_or_leave_range(img, data):
    mask = data.draw(hnp.arrays(np.bool_, img.shape))
    use = data.draw(st.booleans())
    m = mask if use else None
    covered = np.isfinite(img) & (mask if use else True)
    g = sobel_gradient(img, mask=m)
    for out in (g, second_order(img, mask=m), c1_discontinuity(img, mask=m)):
        assert out.dtype == np.float32 and out.shape == img.shape
        assert not np.isnan(out[covered]).any()
    assert (g[covered] >= 0).all()
    p = normalize_gradient(np.nan_to_num(g, posinf=3e38), k_g=10.0, mask=m)
    assert ((p >= 0) & (p <= 1)).all()
    iz = diagonal_depth_discontinuity(img, mask=m)
    assert ((iz >= 0) & (iz <= 1)).all()
    e = suppress_zeroth_order(second_order(img, mask=m), g, k_l=2.0, mask=m)
    assert not np.isnan(e[covered & np.isfinite(g)]).any()
