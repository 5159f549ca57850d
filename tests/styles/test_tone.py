"""Gooch and toon styles and local enhancement (sciviz_gbuf.styles.tone / .local).

Properties checked against the N.L of each pixel recomputed here from the captured normals:
Gooch et al. 1998 hue ordering, Lake et al. 2000 flat shade patches, the 2003 edge map colours
(Nienhaus & Döllner §5.1) and Saito & Takahashi 1990 §5.2 selection by id.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
import pyvista as pv
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from sciviz_gbuf.core import capture
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import edge_map, id_edges, internal_edges, profile_edges
from sciviz_gbuf.styles.illustration import LIGHT
from sciviz_gbuf.styles.local import local_style
from sciviz_gbuf.styles.tone import gooch, toon

L_UNIT = np.asarray(LIGHT, dtype=np.float64) / np.linalg.norm(LIGHT)


@cache
def sphere_gb(supersample: int = 1):
    sphere = pv.Sphere(theta_resolution=200, phi_resolution=200)
    return capture(sphere, window_size=(160, 160), camera="xy", supersample=supersample)


@cache
def cube_gb():
    return capture(pv.Cube(), window_size=(160, 160), camera="iso")


@cache
def two_object_gb(supersample: int = 2):
    scene = [pv.Sphere(center=(-1, 0, 0), radius=0.8), pv.Cube(center=(1, 0, 0))]
    return capture(scene, window_size=(200, 120), camera="xy", supersample=supersample)


def n_dot_l(gb, light=L_UNIT):
    """N.L per output pixel (mean over each pixel's buffer samples), float64."""
    nl = np.nan_to_num(gb.normal.astype(np.float64), nan=0.0) @ light
    return gb.downsample(np.where(gb.mask, nl, np.nan).astype(np.float32)).astype(np.float64)


def clean_pixels(gb):
    """Fully covered output pixels with no ink of the edge map (no profile, no inner edge)."""
    em = edge_map(gb)
    cover = gb.downsample(gb.mask.astype(np.float32))
    return (cover == 1.0) & (em[..., 3] == 0.0) & (em[..., 0] == 0.0)


# ----------------------------------------------------------------------------- determinism
def test_same_gbuffer_gives_identical_images():
    gb = two_object_gb()
    for make in (
        lambda: gooch(gb),
        lambda: toon(gb, levels=4),
        lambda: toon(gb, levels=4, smooth=0.15),
        lambda: local_style(gooch(gb), toon(gb), gb, ids=[1]),
    ):
        a, b = make(), make()
        assert a.dtype == np.float32 and a.shape == (*gb.output_shape, 3)
        assert np.array_equal(a, b)


# ----------------------------------------------------------------------------- gooch
def test_gooch_matches_the_1998_equation_on_surface_pixels():
    gb = sphere_gb(1)
    img = gooch(gb, edges=False)
    base, warm, cool = np.full(3, 0.75), np.array([0.4, 0.4, 0.0]), np.array([0.0, 0.0, 0.4])
    k_cool, k_warm = cool + 0.2 * base, warm + 0.6 * base
    t = (1.0 + n_dot_l(gb)) / 2.0
    want = t[..., None] * k_warm + (1.0 - t[..., None]) * k_cool
    m = gb.mask
    assert np.abs(img[m] - want[m]).max() < 1e-5
    assert np.array_equal(img[~m], np.ones(((~m).sum(), 3), dtype=np.float32))  # paper


def test_gooch_warmth_increases_with_n_dot_l_on_a_sphere():
    gb = sphere_gb(2)
    img = gooch(gb)
    nl = n_dot_l(gb)
    ok = clean_pixels(gb)
    warmth = (img[..., 0] - img[..., 2])[ok]
    nl = nl[ok]
    edges = np.arange(-1.0, 1.0001, 0.1)
    which = np.digitize(nl, edges)
    means = [warmth[which == b].mean() for b in np.unique(which) if (which == b).sum() >= 20]
    # the visible half of a sphere lit from the upper left spans N.L in about [-0.5, 1]
    assert len(means) >= 12
    assert np.all(np.diff(means) > 0.03)  # 0.1 of N.L is 0.05 of t, 0.04 of R - B (defaults)
    warm_side, cool_side = nl > 0.8, nl < -0.2
    assert warm_side.sum() > 500 and cool_side.sum() > 50
    assert np.all(img[..., 0][ok][warm_side] > img[..., 2][ok][warm_side])
    assert np.all(img[..., 2][ok][cool_side] > img[..., 0][ok][cool_side])


@pytest.mark.parametrize(("supersample", "width", "least"), [(1, 1.0, 200), (2, 2.0, 100)])
def test_gooch_profiles_black_and_absent_without_edges(supersample, width, least):
    gb = sphere_gb(supersample)
    ink = profile_edges(gb) > 0.9
    # the outline is ~ 2 pi 45 output pixels; supersampled, one-buffer-pixel lines are often
    # below 0.9 ink once reduced
    assert ink.sum() > least
    # supersampled with width 1 the 2003 profile (box-filtered, ~1 output pixel) covers only
    # half of these pixels fully (alpha 0.5 .. 1), hence width 2 there
    assert gooch(gb, width=width)[ink].max() < 0.1
    assert gooch(gb, edges=False)[ink].max() > 0.3  # the black comes from the edge map


def test_gooch_convex_creases_white_on_a_cube():
    gb = cube_gb()
    convex = internal_edges(gb) > 0.9
    # where the profile of the outline overlaps the crease, black is drawn last (2003 §5.1)
    convex &= edge_map(gb)[..., 3] < 0.05
    assert convex.sum() > 60  # three visible convex edges of the cube
    assert gooch(gb)[convex].min() > 0.9
    assert gooch(gb, edges=False)[convex].min() < 0.9  # white only from the inner edges


# ----------------------------------------------------------------------------- toon
@pytest.mark.parametrize("k", [2, 3, 5])
def test_toon_has_k_flat_colours_ordered_by_n_dot_l(k):
    gb = sphere_gb(1)
    img = toon(gb, levels=k)
    ok = clean_pixels(gb)
    s = np.maximum(n_dot_l(gb), 0.0)[ok]
    cols, inverse = np.unique(img[ok].reshape(-1, 3), axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    assert len(cols) == k
    order = np.argsort(cols.sum(axis=1))  # darkest first
    lo = np.array([s[inverse == i].min() for i in order])
    hi = np.array([s[inverse == i].max() for i in order])
    assert np.all(hi[:-1] < lo[1:])  # no overlap: brighter colour <=> larger N.L
    # the thresholds are at j / k (nearest lookup of a k-texel texture)
    tau = np.arange(1, k) / k
    assert np.all(hi[:-1] <= tau + 1e-5) and np.all(lo[1:] >= tau - 1e-5)
    assert np.all(np.diff(cols[order], axis=0) > 0)  # every channel brighter (toon_shades)
    np.testing.assert_allclose(cols[order][-1], (0.9, 0.55, 0.3), atol=1e-6)


def test_toon_colour_table_and_shade_sequence():
    gb = sphere_gb(1)
    ok = clean_pixels(gb)
    table = np.array([[0.1, 0.2, 0.6], [0.2, 0.6, 0.2], [0.9, 0.9, 0.1]], dtype=np.float32)
    img = toon(gb, levels=table)
    s = np.maximum(n_dot_l(gb), 0.0)
    # pixels clearly inside one texel take that texel's colour exactly
    for i in range(3):
        inside = ok & (s > i / 3 + 1e-4) & (s < (i + 1) / 3 - 1e-4)
        assert inside.sum() > 100
        assert np.array_equal(img[inside], np.broadcast_to(table[i], (inside.sum(), 3)))
    shades = toon(gb, levels=[0.2, 1.0], base=(1.0, 0.5, 0.0))
    assert {tuple(c) for c in np.unique(shades[ok].reshape(-1, 3), axis=0)} == {
        (np.float32(0.2), np.float32(0.1), np.float32(0.0)),
        (np.float32(1.0), np.float32(0.5), np.float32(0.0)),
    }


def test_toon_smooth_mixes_only_near_thresholds_and_stays_monotone():
    gb = sphere_gb(1)
    k, smooth = 3, 0.12
    hard = toon(gb, levels=k, edges=False)
    soft = toon(gb, levels=k, smooth=smooth, edges=False)
    m = gb.downsample(gb.mask.astype(np.float32)) == 1.0
    s = np.maximum(n_dot_l(gb), 0.0)
    texels = np.unique(hard[m].reshape(-1, 3), axis=0)
    is_texel = (soft[..., None, :] == texels[None, None]).all(axis=-1).any(axis=-1)
    dist = np.min(np.abs(s[..., None] - np.arange(1, k)[None, None] / k), axis=-1)
    between = m & ~is_texel
    assert between.sum() > 300
    assert dist[between].max() < smooth / 2 + 1e-5  # intermediate colours only in the ramps
    assert np.all(~is_texel[m & (dist < 0.45 * smooth)])  # ... and everywhere inside them
    assert np.array_equal(
        soft[m & (dist > smooth / 2 + 1e-4)], hard[m & (dist > smooth / 2 + 1e-4)]
    )
    # monotone in N.L over the whole sphere ...
    bright = soft.sum(axis=-1)[m]
    by_nl = bright[np.argsort(s[m], kind="stable")]
    assert np.all(np.diff(by_nl) >= -1e-6)
    # ... and along the image line from the highlight through the centre to the dark rim
    h, w = gb.output_shape
    centre = np.array([(h - 1) / 2, (w - 1) / 2])
    nl = n_dot_l(gb)
    hi = np.unravel_index(np.nanargmax(np.where(m, nl, np.nan)), nl.shape)
    direction = centre - np.array(hi)
    direction /= np.linalg.norm(direction)
    steps = np.arange(0, 200)
    rows = np.round(hi[0] + steps * direction[0]).astype(int)
    cols = np.round(hi[1] + steps * direction[1]).astype(int)
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    rows, cols = rows[inside], cols[inside]
    keep = m[rows, cols]
    line = soft.sum(axis=-1)[rows[keep], cols[keep]]
    assert len(line) > 60 and line[0] - line[-1] > 1.0
    assert np.all(np.diff(line) <= 1e-6)


def test_toon_profiles_black_inner_edges_optional():
    gb = cube_gb()
    ink = profile_edges(gb) > 0.9
    # black all along but at the corners, where the converging lines are thinned to their
    # skeleton (a clump of black lines, see thin_edge_map)
    assert (toon(gb)[ink].max(axis=-1) < 0.1).mean() > 0.93
    convex = (internal_edges(gb) > 0.9) & (edge_map(gb)[..., 3] < 0.05)
    assert (toon(gb)[convex].max(axis=-1) < 0.1).mean() > 0.93  # black crease lines by default
    no_inner = toon(gb, inner_color=None)
    assert np.array_equal(no_inner[convex], toon(gb, edges=False)[convex])  # not drawn
    assert (no_inner[ink].max(axis=-1) < 0.1).mean() > 0.93  # profiles still are
    assert toon(gb, inner_color=(0.0, 1.0, 0.0))[convex][:, 1].min() > 0.9


# ----------------------------------------------------------------------------- local_style
def test_local_style_selects_object_by_coverage():
    gb = two_object_gb(2)
    k = gb.supersample
    h, w = gb.output_shape
    red = np.zeros((h, w, 3), np.float32)
    red[..., 0] = 1.0
    blue = np.zeros((h, w, 3), np.float32)
    blue[..., 2] = 1.0
    out = local_style(red, blue, gb, ids=1)
    sel = (gb.mask & (gb.object_id == 1))[: h * k, : w * k].reshape(h, k, w, k)
    full, none = sel.all(axis=(1, 3)), ~sel.any(axis=(1, 3))
    mixed = ~full & ~none
    assert full.sum() > 800 and (none & (gb.downsample(gb.object_id) == 0)).sum() > 800
    assert np.array_equal(out[full], red[full])
    assert np.array_equal(out[none], blue[none])  # object 0 and the background: base
    assert mixed.sum() > 50
    r = out[mixed][:, 0]
    assert np.all((r > 0) & (r < 1))
    np.testing.assert_allclose(out[mixed].sum(axis=-1), 1.0, atol=1e-6)
    # mixing happens only on the outline of object 1
    outline = ndimage.binary_dilation((id_edges(gb) > 0) | (profile_edges(gb) > 0), iterations=1)
    assert np.all(outline[mixed])
    # with real styles: object 1 Gooch, object 0 toon
    g, t = gooch(gb), toon(gb)
    both = local_style(g, t, gb, ids=[1])
    assert np.array_equal(both[full], g[full]) and np.array_equal(both[none], t[none])


def test_local_style_cells():
    gb = two_object_gb(1)
    cells = [int(c) for c in np.unique(gb.cell_id[gb.object_id == 1])[:2]]
    base = np.zeros((*gb.output_shape, 3), np.float32)
    out = local_style(np.ones_like(base), base, gb, ids=cells, kind="cell")
    want = gb.mask & np.isin(gb.cell_id, cells)
    assert want.sum() > 100
    assert np.array_equal(out[..., 0] == 1.0, want)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"ids": 2}, "ids"),  # only objects 0 and 1
        ({"ids": -1}, "ids"),
        ({"ids": []}, "ids"),
        ({"ids": 1.5}, "ids"),
        ({"ids": "1"}, "ids"),
        ({"ids": True}, "ids"),
        ({"ids": 1, "kind": "face"}, "kind"),
    ],
)
def test_local_style_bad_ids_and_kind(kwargs, name):
    gb = two_object_gb(1)
    img = np.zeros((*gb.output_shape, 3), np.float32)
    with pytest.raises(InputError, match=name):
        local_style(img, img, gb, **kwargs)


def test_local_style_bad_shapes():
    gb = two_object_gb(1)
    img = np.zeros((*gb.output_shape, 3), np.float32)
    with pytest.raises(InputError, match="styled"):
        local_style(img[:-1], img, gb, ids=0)
    with pytest.raises(InputError, match="base"):
        local_style(img, img[..., :2], gb, ids=0)
    with pytest.raises(InputError, match="gb"):
        local_style(img, img, None, ids=0)


# ----------------------------------------------------------------------------- bad parameters
@pytest.mark.parametrize(
    ("func", "kwargs", "name"),
    [
        (gooch, {"base": (1.2, 0.5, 0.5)}, "base"),
        (gooch, {"warm": (-0.1, 0.4, 0.0)}, "warm"),
        (gooch, {"cool": (0.0, 0.0, np.nan)}, "cool"),
        (gooch, {"cool": (0.0, 0.4)}, "cool"),
        (gooch, {"alpha": -0.1}, "alpha"),
        (gooch, {"alpha": np.nan}, "alpha"),
        (gooch, {"beta": 1.5}, "beta"),
        (gooch, {"light": (0.0, 0.0, 0.0)}, "light"),
        (gooch, {"light": (1.0, 2.0)}, "light"),
        (gooch, {"light": (np.inf, 0.0, 1.0)}, "light"),
        (gooch, {"inner_color": (2.0, 1.0, 1.0)}, "inner_color"),
        (gooch, {"profile_color": "black"}, "profile_color"),
        (gooch, {"background": (1.0, 1.0, 1.1)}, "background"),
        (gooch, {"edges": "yes"}, "edges"),
        (gooch, {"operator": "sobel"}, "operator"),
        (toon, {"levels": 0}, "levels"),
        (toon, {"levels": -2}, "levels"),
        (toon, {"levels": 10_000}, "levels"),
        (toon, {"levels": 2.5}, "levels"),
        (toon, {"levels": True}, "levels"),
        (toon, {"levels": []}, "levels"),
        (toon, {"levels": [0.5, 1.5]}, "levels"),
        (toon, {"levels": [[0.1, 0.2], [0.3, 0.4]]}, "levels"),
        (toon, {"smooth": -0.1}, "smooth"),
        (toon, {"smooth": np.nan}, "smooth"),
        (toon, {"smooth": 2.0}, "smooth"),
        (toon, {"light": (0.0, 0.0)}, "light"),
        (toon, {"base": (0.5, 0.5, -1.0)}, "base"),
        (toon, {"inner_color": (0.0, 0.0, 5.0)}, "inner_color"),
        (toon, {"crease_angle": 0.0}, "crease_angle"),
    ],
)
def test_bad_parameters_raise_input_error_naming_them(func, kwargs, name):
    with pytest.raises(InputError, match=name):
        func(sphere_gb(1), **kwargs)


def test_not_a_gbuffer():
    with pytest.raises(InputError, match="gb"):
        gooch(np.zeros((4, 4, 3)))
    with pytest.raises(InputError, match="gb"):
        toon("scene")


# ----------------------------------------------------------------------------- hypothesis
unit = st.floats(0.0, 1.0)
rgb = st.tuples(unit, unit, unit)
lights = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 1e-3)


@settings(max_examples=25, deadline=None)
@given(light=lights, base=rgb, warm=rgb, cool=rgb, alpha=unit, beta=unit, edges=st.booleans())
def test_gooch_outputs_stay_in_unit_range(light, base, warm, cool, alpha, beta, edges):
    gb = two_object_gb(2)
    img = gooch(
        gb, light=light, base=base, warm=warm, cool=cool, alpha=alpha, beta=beta, edges=edges
    )
    assert img.dtype == np.float32 and img.shape == (*gb.output_shape, 3)
    assert np.isfinite(img).all() and img.min() >= 0.0 and img.max() <= 1.0


@settings(max_examples=25, deadline=None)
@given(
    light=lights,
    levels=st.one_of(
        st.integers(1, 8),
        st.lists(unit, min_size=1, max_size=6),
        st.lists(rgb, min_size=1, max_size=6),
    ),
    base=rgb,
    smooth=st.floats(0.0, 1.0),
    edges=st.booleans(),
)
def test_toon_outputs_stay_in_unit_range(light, levels, base, smooth, edges):
    gb = two_object_gb(2)
    img = toon(gb, light=light, levels=levels, base=base, smooth=smooth, edges=edges)
    assert img.dtype == np.float32 and img.shape == (*gb.output_shape, 3)
    assert np.isfinite(img).all() and img.min() >= 0.0 and img.max() <= 1.0
