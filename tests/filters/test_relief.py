"""Texture shading and the local relief model: analytic eigenfunctions, planes and paraboloids,
the reference implementation's formula, nodata, dask chunks and odd inputs."""

from __future__ import annotations

import dask.array as da
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy import ndimage

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import local_relief, texture_shade


def _cosines(h, w, m, n):
    i = np.arange(h)[:, None]
    j = np.arange(w)[None, :]
    return np.cos(np.pi * m * (i + 0.5) / h) * np.cos(np.pi * n * (j + 0.5) / w)


def _hills(size=512, seed=1):
    g = np.random.default_rng(seed).normal(size=(size, size))
    return ndimage.gaussian_filter(g, size / 64) * 3000 + ndimage.gaussian_filter(g, 3) * 50


def _texshade_reference(x, alpha):
    """Fasih's ``texshade`` formula: zero padding to a power of two, ``H = |f|^alpha`` with
    ``f`` in cycles per sample (written from its description, numpy FFT)."""
    n = [2 ** int(np.ceil(np.log2(v))) for v in x.shape]
    fy = np.fft.fftfreq(n[0])[:, None]
    fx = np.fft.rfftfreq(n[1])[None, :]
    spectrum = np.fft.rfft2(x, n) * np.hypot(fx, fy) ** alpha
    return np.fft.irfft2(spectrum, n)[: x.shape[0], : x.shape[1]]


# ----------------------------------------------------------------------------- texture shading
@pytest.mark.parametrize("alpha", [0.0, 0.5, 1.0, 2.0])
@pytest.mark.parametrize(("m", "n"), [(1, 1), (5, 7), (12, 3)])
def test_texture_of_a_cosine_is_the_cosine_times_k_to_the_alpha(alpha, m, n):
    h, w, dx, dy = 90, 140, 2.0, 3.0
    z = 40.0 * _cosines(h, w, m, n) + 500.0 * (alpha == 0)
    k = np.hypot(np.pi * m / (h * dy), np.pi * n / (w * dx))
    got = texture_shade(z, detail=alpha, dx=dx, dy=dy)
    want = (z - 500.0 * (alpha == 0)) * k**alpha + 500.0 * (alpha == 0)
    assert got.dtype == np.float32 and got.shape == z.shape
    # float32 input: its rounding (6e-8 relative) is amplified by up to |k_max|^alpha
    noise = 6e-8 * np.abs(z).max() * np.hypot(np.pi / dx, np.pi / dy) ** alpha * 4
    np.testing.assert_allclose(got, want, atol=2e-5 * np.abs(want).max() + noise)


def test_texture_of_a_plane_is_zero_and_of_the_heights_alpha_zero_the_heights():
    i, j = np.mgrid[0:50, 0:70]
    plane = 1200.0 + 3.0 * j - 1.5 * i
    assert np.abs(texture_shade(plane, detail=0.7, dx=10.0, dy=10.0)).max() < 1e-3
    np.testing.assert_allclose(texture_shade(plane, detail=0.0), plane, rtol=1e-6)


def test_texture_detail_two_is_the_negative_laplacian():
    """alpha = 2 on a smooth field: -(z_xx + z_yy) by central differences."""
    z = 100.0 * _cosines(128, 128, 3, 2) + 50.0 * _cosines(128, 128, 1, 4)
    t = texture_shade(z, detail=2.0, dx=1.0, dy=1.0)
    lap = (np.roll(z, 1, 0) + np.roll(z, -1, 0) + np.roll(z, 1, 1) + np.roll(z, -1, 1)) - 4 * z
    inner = (slice(2, -2), slice(2, -2))
    np.testing.assert_allclose(t[inner], -lap[inner], atol=0.01 * np.abs(lap).max())


@pytest.mark.parametrize("alpha", [0.5, 1.0])
def test_texture_agrees_with_the_reference_formula_away_from_the_edge(alpha):
    """Up to the constant (2 pi / dx)^alpha of k in radians per metre against f in cycles per
    sample; the edges differ by design (mirror against zero padding)."""
    z = _hills()
    dx = 2.0
    ours = texture_shade(z, detail=alpha, dx=dx, dy=dx)
    ref = _texshade_reference(z - z.mean(), alpha) * (2 * np.pi / dx) ** alpha
    inner = (slice(96, -96), slice(96, -96))
    a, b = ours[inner].ravel(), ref[inner].ravel()
    assert np.corrcoef(a, b)[0, 1] > 0.999
    assert abs(np.median(a / b) - 1) < 0.01


def test_texture_is_dark_in_valleys_and_bright_on_ridges():
    j = np.arange(200)[None, :] * np.ones((60, 1))
    ridges = 30.0 * np.cos(2 * np.pi * j / 40)  # ridges at j = 0, 40, ...; valleys at 20, 60
    t = texture_shade(ridges, detail=0.5)
    assert (t[:, 40] > 0).all() and (t[:, 60] < 0).all()


def test_texture_nodata_is_nan_and_the_input_is_untouched():
    z = _hills(128).astype(np.float32)
    z[40:60, 30:70] = np.nan
    z[5, 5] = np.inf
    before = z.copy()
    t = texture_shade(z, detail=0.5)
    np.testing.assert_array_equal(z, before)
    assert np.isnan(t[40:60, 30:70]).all() and np.isnan(t[5, 5])
    assert np.isfinite(t[~np.isnan(t)]).all() and np.isfinite(t).sum() == z.size - 801
    mask = np.ones(z.shape, bool)
    mask[0, :] = False
    assert np.isnan(texture_shade(np.where(np.isfinite(z), z, 0), mask=mask)[0]).all()


@pytest.mark.parametrize("chunks", [(64, 96), (37, 200), (300, 13)])
def test_texture_on_dask_chunks_is_the_whole_grid_bit_for_bit(chunks):
    z = _hills(300, seed=3).astype(np.float32) + np.arange(300, dtype=np.float32)[None, :] * 2
    z[100:140, 20:90] = np.nan  # a nodata hole across chunk borders
    z[0, :] = np.nan
    mask = np.ones(z.shape, bool)
    mask[250:, 250:] = False
    whole = texture_shade(z, detail=0.5, dx=30.0, dy=25.0, mask=mask)
    lazy = texture_shade(da.from_array(z, chunks=chunks), detail=0.5, dx=30.0, dy=25.0,
                         mask=da.from_array(mask, chunks=chunks))  # fmt: skip
    assert isinstance(lazy, da.Array) and lazy.chunks == da.from_array(z, chunks=chunks).chunks
    np.testing.assert_array_equal(lazy.compute(), whole)


def test_texture_near_nodata_has_no_rim():
    """Nodata is filled smoothly for the transform: the texture of a plane with a hole is
    still (nearly) zero around the hole, as the texture of the plane is zero."""
    i, j = np.mgrid[0:120, 0:160].astype(np.float64)
    plane = 500.0 + 2.0 * j - 1.0 * i
    plane[40:80, 60:100] = np.nan
    t = texture_shade(plane, detail=0.5)
    assert np.nanmax(np.abs(t)) < 1e-3 * np.abs(texture_shade(_hills(128), detail=0.5)).max()


def test_texture_refuses_bad_parameters_by_name():
    z = np.zeros((4, 4))
    for params, word in [
        ({"detail": -0.1}, "detail"),
        ({"detail": float("nan")}, "detail"),
        ({"dx": 0.0}, "dx"),
        ({"z_factor": float("inf")}, "z_factor"),
        ({"mask": np.ones((3, 3), bool)}, "mask"),
    ]:
        with pytest.raises(InputError, match=word):
            texture_shade(z, **params)
    with pytest.raises(InputError, match="2-D"):
        texture_shade(np.zeros(5))


# ----------------------------------------------------------------------------- local relief
def test_local_relief_of_a_plane_is_zero_where_the_window_is_whole():
    h, w, dx, dy = 80, 120, 2.0, 3.0
    i, j = np.mgrid[0:h, 0:w]
    plane = 300.0 + 0.4 * j * dx - 0.2 * i * dy
    lr = local_relief(plane, dx=dx, dy=dy)  # 20 cells
    assert np.abs(lr[20:-20, 20:-20]).max() < 1e-3
    # at the edge the window is cut off: the mean is that of one side, the relief not zero
    assert abs(lr[40, 0]) > 1.0


@pytest.mark.parametrize(("radius", "dx", "dy", "r"), [(None, 1.0, 1.0, 20), (9.0, 3.0, 3.0, 3)])
def test_local_relief_of_a_paraboloid_is_the_window_variance(radius, dx, dy, r):
    a = 0.02
    i, j = np.mgrid[0:100, 0:100]
    x, y = (j - 50) * dx, (i - 50) * dy
    lr = local_relief(a * (x**2 + y**2), radius=radius, dx=dx, dy=dy)
    want = -a * (r * (r + 1) / 3) * (dx**2 + dy**2)
    np.testing.assert_allclose(lr[r:-r, r:-r], want, rtol=1e-4)


def test_local_relief_leaves_nodata_out_of_the_mean():
    rng = np.random.default_rng(5)
    z = rng.normal(size=(40, 50)) * 10
    z[10:20, 5:15] = np.nan
    lr = local_relief(z, radius=4.0)
    for r, c in [(12, 18), (25, 10), (0, 0), (39, 49)]:
        win = z[max(r - 4, 0) : r + 5, max(c - 4, 0) : c + 5]
        assert lr[r, c] == pytest.approx(z[r, c] - np.nanmean(win), abs=1e-4)
    assert np.isnan(lr[10:20, 5:15]).all()


def test_local_relief_on_dask_chunks_is_the_whole_grid_bit_for_bit():
    z = _hills(300).astype(np.float32)
    z[100:110, 40:200] = np.nan
    whole = local_relief(z, radius=12.0, dx=1.5, dy=1.5)
    lazy = local_relief(da.from_array(z, chunks=64), radius=12.0, dx=1.5, dy=1.5)
    np.testing.assert_array_equal(lazy.compute(), whole)


def test_local_relief_refuses_bad_parameters_by_name():
    z = np.zeros((4, 4))
    for params, word in [
        ({"radius": 0.0}, "radius"),
        ({"radius": -1.0}, "radius"),
        ({"radius": 1e9}, "radius"),
        ({"dy": float("nan")}, "dy"),
    ]:
        with pytest.raises(InputError, match=word):
            local_relief(z, **params)


# ----------------------------------------------------------------------------- odd inputs
@settings(max_examples=60, deadline=None)
@given(
    z=arrays(
        np.float32,
        st.tuples(st.integers(1, 9), st.integers(1, 9)),
        elements=st.one_of(st.floats(-1e4, 1e4, width=32), st.just(np.nan), st.just(np.inf)),
    ),
    alpha=st.floats(0, 2),
)
def test_odd_grids_give_finite_values_on_data_and_nan_on_nodata(z, alpha):
    bad = ~np.isfinite(z)
    for out in (texture_shade(z, detail=alpha), local_relief(z, radius=2.0)):
        assert out.shape == z.shape and out.dtype == np.float32
        assert np.isnan(out[bad]).all()
        assert np.isfinite(out[~bad]).all()
