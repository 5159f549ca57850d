"""The fused edge pass against the straightforward per-pixel kernels it replaces, bit for bit.

``_edge_kernels.edge_pass`` (row buffers, vectorised row passes, background spans skipped)
must give exactly what ``pair_edge_kernel`` and ``edge_map_kernel`` give; the union-find line
cleaning exactly what two ``scipy.ndimage.label`` calls give; the one-pass finish exactly what
``GBuffer.downsample`` + clip give. Checked on odd random buffers (hypothesis: NaN, inf, one
row or column, masks that disagree with the depth) and on captures of real scenes.
"""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.filters import _edge_kernels as K
from sciviz_gbuf.filters import edges as E
from tests.filters.test_edges_acceptance import view

MODES = (K.MODE_DIAGONAL, K.MODE_C1)


def _reference(sz, depth, normal, m, par, inv_d, inv_w, jump, crease):
    """The per-pixel kernels: pairs with and without creases, and the 2003 edge map with the
    depth's creases added to its inner edges (as ``edges.edge_map`` combined them)."""
    h, w = sz.shape
    out = {}
    for do_crease in (True, False):
        p = np.empty((h, w), np.float32)
        c = np.empty((h, w), np.float32)
        K.pair_edge_kernel(
            sz, depth, normal, m, par, inv_d, inv_w, jump, crease, 0.5 * crease, do_crease, p, c
        )
        out["pairs", do_crease] = (p, c)
    for mode in MODES:
        em = np.empty((h, w, 4), np.float32)
        K.edge_map_kernel(
            sz, depth, normal, m, par, inv_d, jump, crease, 0.5 * crease, mode == K.MODE_C1, em
        )
        out[mode] = (np.maximum(em[..., 0], np.abs(out["pairs", True][1])), em[..., 3])
    return out


def _fused(sz, depth, normal, m, par, inv_d, inv_w, jump, crease):
    h, w = sz.shape
    out = {}
    for key, do_crease, mode in (
        (("pairs", True), True, K.MODE_PAIRS),
        (("pairs", False), False, K.MODE_PAIRS),
        *((mode, True, mode) for mode in MODES),
    ):
        a = np.full((h, w), 7.0, np.float32)  # garbage: every pixel must be written
        b = np.full((h, w), 7.0, np.float32)
        K.edge_pass(
            sz, depth, normal, m, par, inv_d, inv_w, jump, crease, 0.5 * crease, do_crease,
            mode, a, b, 0.0, 0.0, np.zeros((1, 1), np.float32),
        )  # fmt: skip
        out[key] = (a, b)
    return out


def _assert_same(*args) -> None:
    ref, new = _reference(*args), _fused(*args)
    for key in ref:
        for r, n in zip(ref[key], new[key], strict=True):
            np.testing.assert_array_equal(n, r, err_msg=str(key))


@st.composite
def buffers(draw):
    h = draw(st.integers(1, 9))
    w = draw(st.integers(1, 9))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[:h, :w].astype(np.float64)
    # planes, folds and steps (what edges are made of), plus noise
    sz = (
        draw(st.floats(-3, 3)) * cols
        + draw(st.floats(-3, 3)) * rows
        + draw(st.floats(0, 4)) * np.abs(cols - draw(st.floats(0, w)))
        + draw(st.floats(0, 20)) * (rows > draw(st.floats(0, h)))
        + draw(st.floats(0, 0.5)) * rng.standard_normal((h, w))
    )
    depth = 10.0 + rng.random((h, w)) * draw(st.floats(0, 5))
    normal = rng.standard_normal((h, w, 3))
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    if draw(st.booleans()):  # facets: a few distinct normals
        normal = normal.reshape(-1, 3)[rng.integers(0, min(3, h * w), (h, w))]
    mask = rng.random((h, w)) > draw(st.floats(0, 0.6))
    holes = rng.random((h, w))
    sz[holes < 0.05] = np.nan
    sz[(holes > 0.05) & (holes < 0.08)] = np.inf
    depth[rng.random((h, w)) < 0.03] = np.nan
    normal[rng.random((h, w)) < 0.03] = np.nan
    return (
        np.ascontiguousarray(sz, np.float32),
        np.ascontiguousarray(depth, np.float32),
        np.ascontiguousarray(normal, np.float32),
        mask,
        draw(st.booleans()),
        draw(st.floats(1e-3, 1.0)),
        draw(st.floats(1.0, 100.0)),
        draw(st.floats(0.05, 4.0)),
        draw(st.floats(1.0, 120.0)),
    )


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(buffers())
def test_fused_pass_equals_the_per_pixel_kernels_on_odd_buffers(args):
    _assert_same(*args)


def _scenes(shared_data):
    cube = pv.Cube().triangulate()
    sphere = pv.Sphere(theta_resolution=60, phi_resolution=60)
    noisy = sphere.copy()
    noisy.points = noisy.points + np.random.default_rng(3).normal(0, 0.004, noisy.points.shape)
    noisy.point_data.clear()
    torus = pv.ParametricTorus().triangulate().decimate(0.9)
    stl = pv.read(shared_data / "meshes" / "vtkdata_42400-IDGH.stl")
    return {"cube": cube, "noisy_sphere": noisy, "decimated_torus": torus, "cad_stl": stl}


@pytest.fixture(scope="module")
def captures(shared_data):
    out = []
    for name, mesh in _scenes(shared_data).items():
        for ss, parallel in ((1, False), (2, False), (1, True)):
            gb = sg.capture(
                mesh, window_size=(160, 120), supersample=ss, camera=view(mesh, 35.0, 30.0),
                parallel_projection=parallel,
            )  # fmt: skip
            out.append((f"{name}-ss{ss}-{'par' if parallel else 'persp'}", gb))
    return out


@pytest.mark.parametrize("jump, crease", [(1.0, 30.0), (2.5, 20.0), (0.5, 60.0)])
def test_fused_pass_equals_the_per_pixel_kernels_on_captures(captures, jump, crease):
    for _, gb in captures:
        _assert_same(*E._kernel_inputs(gb), *E._camera_terms(gb), jump, crease)


def _outline(mask: np.ndarray) -> np.ndarray:
    """Covered pixels with a 4-neighbour inside the image that is not covered."""
    out = np.zeros_like(mask)
    out[:, :-1] |= ~mask[:, 1:]
    out[:, 1:] |= ~mask[:, :-1]
    out[:-1, :] |= ~mask[1:, :]
    out[1:, :] |= ~mask[:-1, :]
    return out & mask


def _reference_clean(gb, profile, crease, min_length):
    """The cleaning as two labellings of the whole image (the code it replaced)."""
    eight = np.ones((3, 3), dtype=bool)
    strong = (profile >= 0.5) | (np.abs(crease) >= 0.5)
    pieces, n = ndimage.label(strong, structure=eight)
    keep = np.ones(n + 1, dtype=bool)
    length = min_length * gb.supersample
    if n and length > 0:
        sizes = np.bincount(pieces.ravel(), minlength=n + 1)
        outline = np.zeros(n + 1, dtype=bool)
        outline[pieces[_outline(np.asarray(gb.mask, dtype=bool))]] = True
        keep = (sizes >= length) | outline
    keep[0] = False
    kept = keep[pieces]
    ink = (profile > 0.0) | (crease != 0.0)
    lines, _ = ndimage.label(ink & ~(strong & ~kept), structure=eight)
    anchored = np.zeros(lines.max() + 1, dtype=bool)
    anchored[lines[kept]] = True
    anchored[0] = False
    stay = anchored[lines]
    zero = np.float32(0.0)
    return np.where(stay, profile, zero), np.where(stay, crease, zero)


@pytest.mark.parametrize("min_length", [0.0, 5.0, 20.0])
def test_union_find_cleaning_equals_whole_image_labelling(captures, min_length):
    dropped = 0
    for name, gb in captures:
        p, c = (x.copy() for x in E._pair_edges(gb, 1.0, 30.0))
        ref_p, ref_c = _reference_clean(gb, p, c, min_length)
        new_p, new_c = E._clean(gb, p.copy(), c.copy(), min_length)
        np.testing.assert_array_equal(new_p, ref_p, err_msg=name)
        np.testing.assert_array_equal(new_c, ref_c, err_msg=name)
        dropped += int(((p != 0) & (new_p == 0)).sum())
        # the scratch ids are left zeroed for the next call
        assert not E._scratch("ids", gb.shape, np.int32, zero=True).any()
    if min_length > 0:
        assert dropped > 0  # the noisy and decimated scans do have specks to drop


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 12), st.integers(1, 12), st.integers(0, 2**32 - 1), st.floats(0.0, 9.0))
def test_union_find_cleaning_on_random_ink(h, w, seed, min_length):
    rng = np.random.default_rng(seed)
    profile = np.where(rng.random((h, w)) < 0.3, rng.random((h, w)), 0).astype(np.float32)
    crease = np.where(rng.random((h, w)) < 0.3, rng.uniform(-1, 1, (h, w)), 0).astype(np.float32)
    mask = rng.random((h, w)) < 0.7
    gb = sg.GBuffer(
        depth=np.ones((h, w), np.float32), sz=np.ones((h, w), np.float32),
        normal=np.zeros((h, w, 3), np.float32), world=np.zeros((h, w, 3), np.float32),
        object_id=np.zeros((h, w), np.int32), cell_id=np.zeros((h, w), np.int64), mask=mask,
        camera=sg.capture(pv.Cube(), window_size=(w, h)).camera,
    )  # fmt: skip
    ref = _reference_clean(gb, profile, crease, min_length)
    new = E._clean(gb, profile.copy(), crease.copy(), min_length)
    np.testing.assert_array_equal(new[0], ref[0])
    np.testing.assert_array_equal(new[1], ref[1])


def test_one_pass_finish_equals_downsample_and_clip(captures):
    def reference(gb, ink, width):
        size = max(1, round(width * gb.supersample))
        return np.clip(gb.downsample(E._dilate(ink, size) if size > 1 else ink), 0.0, 1.0)

    for name, gb in captures:
        _, crease = E._pair_edges(gb, 1.0, 30.0)
        signed = crease.copy()
        signed[::7, ::5] = np.nan
        signed[1::9, ::4] *= 3.0  # outside [-1, 1]: clipped
        unsigned = np.abs(signed)
        for width in (0.5, 1.0, 2.0):
            np.testing.assert_array_equal(
                E._finish(gb, unsigned, width=width)[0], reference(gb, unsigned, width), name
            )
            pos = reference(gb, np.maximum(signed, 0.0), width)
            neg = reference(gb, np.maximum(-signed, 0.0), width)
            np.testing.assert_array_equal(E._finish_signed(gb, signed, width), pos - neg, name)


@pytest.mark.parametrize(
    "kw",
    [{}, {"crease_angle": 45.0}, {"min_length": 0.0}, {"width": 2.0, "depth_jump": 2.0}],
)
def test_profile_and_crease_edges_are_the_separate_calls(captures, kw):
    for name, gb in captures[::2]:
        prof, inner = E.profile_and_crease_edges(gb, **kw)
        own = {k: v for k, v in kw.items() if k != "crease_angle"}
        np.testing.assert_array_equal(prof, E.profile_edges(gb, **own), name)
        np.testing.assert_array_equal(inner, E.internal_edges(gb, **kw), name)
        _, crease = E.profile_and_crease_edges(gb, signed=False, **kw)
        np.testing.assert_array_equal(crease, E.crease_edges(gb, **kw), name)


def _reference_enhance(shaded, em, inner_c, prof_c):
    """The array expressions ``enhance`` was written in."""
    img = np.asarray(shaded, dtype=np.float32)
    base = np.nan_to_num(img.astype(np.float32), nan=1.0, copy=False)
    np.clip(base, 0.0, 1.0, out=base)
    out = np.repeat(base[..., None], 3, axis=2) if base.ndim == 2 else base
    inner = np.clip(np.nan_to_num(em[..., :1], nan=0.0), 0.0, 1.0)
    alpha = np.clip(np.nan_to_num(em[..., 3:], nan=0.0), 0.0, 1.0)
    out += (np.asarray(inner_c, np.float32) - out) * inner
    out += (np.asarray(prof_c, np.float32) - out) * alpha
    return out


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 20), st.integers(1, 20), st.integers(0, 2**32 - 1), st.booleans())
def test_enhance_kernel_equals_the_array_expressions(h, w, seed, grey):
    rng = np.random.default_rng(seed)
    shaded = rng.uniform(-0.5, 1.5, (h, w) if grey else (h, w, 3)).astype(np.float32)
    em = rng.uniform(-0.5, 1.5, (h, w, 4)).astype(np.float32)
    for a in (shaded, em):
        flat = a.reshape(-1)
        flat[rng.random(flat.size) < 0.1] = np.nan
        flat[rng.random(flat.size) < 0.05] = np.inf
        flat[rng.random(flat.size) < 0.05] = -np.inf
    inner_c, prof_c = rng.random(3), rng.random(3)
    np.testing.assert_array_equal(
        E.enhance(shaded, em, inner_c, prof_c), _reference_enhance(shaded, em, inner_c, prof_c)
    )


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(buffers(), st.floats(1.0, 120.0))
def test_second_crease_angle_equals_a_second_pass(args, crease2):
    *ins, jump, crease = args
    h, w = ins[0].shape
    none = np.zeros((1, 1), np.float32)

    def one(angle):
        a, b = np.empty((h, w), np.float32), np.empty((h, w), np.float32)
        K.edge_pass(*ins, jump, angle, 0.5 * angle, True, K.MODE_PAIRS, a, b, 0.0, 0.0, none)
        return a, b

    a, b, c = (np.full((h, w), 7.0, np.float32) for _ in range(3))
    K.edge_pass(
        *ins, jump, crease, 0.5 * crease, True, K.MODE_PAIRS, a, b, crease2, 0.5 * crease2, c
    )
    p1, c1 = one(crease)
    _, c2 = one(crease2)
    np.testing.assert_array_equal(a, p1)
    np.testing.assert_array_equal(b, c1)
    np.testing.assert_array_equal(c, c2)


def test_scratch_images_are_kept_per_thread_up_to_a_bound():
    a = E._scratch("t", (64, 64), np.float32)
    assert E._scratch("t", (64, 64), np.float32) is a  # kept
    assert E._scratch("t", (64, 65), np.float32) is not a  # another shape: replaced
    side = int((E._SCRATCH_MAX_BYTES // 4) ** 0.5) + 1
    big = E._scratch("t_big", (side, side), np.float32)
    assert E._scratch("t_big", (side, side), np.float32) is not big  # too large to keep
    zeros = E._scratch("t_zero_big", (side, side), np.int32, zero=True)
    assert not zeros[::97, ::89].any()
