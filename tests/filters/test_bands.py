"""Colour bands: discrete tints at the right edges, continuous ramps, topo-bathymetry, nodata."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters.bands import BATHYMETRIC, HYPSOMETRIC, color_bands


def ramp(lo: float, hi: float, n: int = 200) -> np.ndarray:
    return np.tile(np.linspace(lo, hi, n, dtype=np.float32), (4, 1))


def test_regular_bands_change_colour_exactly_at_the_band_edges():
    h = ramp(0.0, 99.9, 1000)  # 0.1 m per column
    rgba = color_bands(h, interval=20.0)
    colours = np.unique(rgba[0, :, :3], axis=0)
    assert len(colours) == 5
    change = np.nonzero(np.any(np.diff(rgba[0, :, :3], axis=0) != 0, axis=1))[0] + 1
    np.testing.assert_allclose(h[0, change], [20, 40, 60, 80], atol=0.06)
    # each band has the colour of its middle on the continuous ramp
    cont = color_bands(np.array([[10.0, 30.0, 50.0, 70.0, 90.0]]), vmin=0, vmax=99.9)
    band = color_bands(np.array([[1.0, 21.0, 41.0, 61.0, 81.0]]), interval=20.0, vmin=0, vmax=99.9)
    np.testing.assert_allclose(band, cont, atol=1e-6)


def test_explicit_levels_and_base():
    h = ramp(0.0, 10.0, 101)
    rgba = color_bands(h, levels=[2.0, 5.0, 9.0], cmap="gray")
    grey = rgba[0, :, 0]
    for a, b in ((0, 19), (21, 49), (51, 89), (91, 100)):
        assert np.ptp(grey[a : b + 1]) == 0  # one colour per band
    assert grey[19] < grey[21] < grey[51] < grey[91]
    shifted = color_bands(h, interval=4.0, base=1.0, cmap="gray")[0, :, 0]
    edges = np.nonzero(np.diff(shifted))[0] + 1
    np.testing.assert_allclose(h[0, edges], [1.0, 5.0, 9.0], atol=0.1)


def test_continuous_ramp_follows_the_colour_map():
    h = ramp(-5.0, 5.0)
    rgba = color_bands(h, cmap="gray", vmin=-5, vmax=5)
    g = rgba[0, :, 0]
    assert np.all(np.diff(g) >= 0) and g[0] < 0.01 and g[-1] > 0.99
    viridis = color_bands(h, cmap=matplotlib.colormaps["viridis"])[0]
    np.testing.assert_allclose(viridis[0, :3], matplotlib.colormaps["viridis"](0.0)[:3], atol=2e-3)


def test_sea_level_splits_sea_and_land_maps():
    h = ramp(-4000.0, 3000.0, 701)
    rgba = color_bands(h, sea_level=0.0)
    sea, land = rgba[0, h[0] < 0, :3], rgba[0, h[0] >= 0, :3]
    assert np.all(sea[:, 2] > sea[:, 0])  # blue under the sea
    np.testing.assert_allclose(sea[0], BATHYMETRIC(0.0)[:3], atol=2e-3)  # deepest: dark end
    np.testing.assert_allclose(land[0], HYPSOMETRIC(0.0)[:3], atol=2e-3)  # shore: lowland
    np.testing.assert_allclose(land[-1], HYPSOMETRIC(1.0)[:3], atol=2e-3)
    banded = color_bands(h, interval=500.0, sea_level=0.0)
    assert np.all(banded[0, h[0] < 0, 2] > banded[0, h[0] < 0, 0])


def test_nodata_is_transparent_and_inputs_untouched():
    h = ramp(0.0, 10.0)
    h[1, 5:50] = np.nan
    m = np.ones(h.shape, bool)
    m[2, :10] = False
    before = h.copy()
    rgba = color_bands(h, interval=2.0, mask=m)
    assert rgba.dtype == np.float32 and rgba.shape == (*h.shape, 4)
    nodata = ~np.isfinite(h) | ~m
    assert np.all(rgba[nodata] == 0) and np.all(rgba[~nodata, 3] == 1)
    np.testing.assert_array_equal(h, before, strict=True)
    assert not color_bands(np.full((3, 3), np.nan)).any()


def test_constant_image():
    rgba = color_bands(np.full((5, 5), 7.0))
    np.testing.assert_allclose(rgba[..., :3], np.broadcast_to(rgba[0, 0, :3], (5, 5, 3)))


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"interval": 0}, "interval"),
        ({"interval": 1.0, "levels": [1]}, "not both"),
        ({"levels": []}, "levels"),
        ({"levels": [np.nan]}, "levels"),
        ({"cmap": "no_such_map"}, "cmap"),
        ({"sea_cmap": 3}, "sea_cmap"),
        ({"vmin": 5.0, "vmax": 1.0}, "vmin"),
        ({"sea_level": np.inf}, "sea_level"),
        ({"base": np.nan}, "base"),
        ({"mask": np.ones((2, 2), bool)}, "mask"),
    ],
)
def test_rejects(kwargs, word):
    with pytest.raises(InputError, match=word):
        color_bands(ramp(0.0, 1.0, 10), **kwargs)


@settings(max_examples=100, deadline=None)
@given(
    h=hnp.arrays(
        np.float32,
        hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=8),
        elements=st.one_of(
            st.floats(-1e6, 1e6, width=32), st.sampled_from([np.nan, np.inf, -np.inf, 3e38])
        ),
    ),
    interval=st.one_of(st.none(), st.floats(1e-3, 1e5)),
    sea=st.one_of(st.none(), st.floats(-10, 10)),
)
def test_odd_inputs(h, interval, sea):
    rgba = color_bands(h, interval=interval, sea_level=sea)
    assert rgba.shape == (*h.shape, 4) and np.all(np.isfinite(rgba))
    assert rgba.min() >= 0 and rgba.max() <= 1
    assert set(np.unique(rgba[..., 3])) <= {0.0, 1.0}


# ------------------------------------------------------------------ the fused map composite
@settings(max_examples=40, deadline=None)
@given(
    shape=st.tuples(st.integers(1, 40), st.integers(1, 70)),
    kind=st.sampled_from(["interval", "ramp", "levels"]),
    sea=st.sampled_from([None, 0.0, 900.0]),
    layers=st.tuples(st.booleans(), st.booleans(), st.booleans(), st.booleans(), st.booleans()),
    seed=st.integers(0, 2**16),
)
def test_vectorised_composite_is_the_reference_bit_for_bit(shape, kind, sea, layers, seed):
    """``map_image_fast`` (table rows found, colours gathered and lit in separate loops that
    vectorise, one 32-bit word a pixel) writes the bytes of ``map_image``, the per-pixel
    statement it replaces (CONTRIBUTING rule 8): every band mode, with and without a sea,
    relief, shadows, sky view and ink, NaN heights and a NaN relief."""
    from sciviz_gbuf.filters import _band_kernels as bk
    from sciviz_gbuf.filters.bands import _check_tables, band_tables

    rng = np.random.default_rng(seed)
    bands, relief, lit, sky, ink = layers
    z = (rng.random(shape) * 3000 - 500).astype(np.float32)
    z[rng.random(shape) < 0.1] = np.nan
    z.flat[0] = 1000.0  # at least one valid height for the tables
    tables = band_tables(
        z[np.isfinite(z)],
        interval=100.0 if kind == "interval" else None,
        levels=[-100.0, 0.0, 250.0, 1200.0, 2400.0] if kind == "levels" else None,
        base=0.0, cmap=None, vmin=None, vmax=None, sea_level=sea, sea_cmap=None,
    )  # fmt: skip
    none = np.zeros((0, 0), np.float32)

    def layer(on, scale=1.0):
        return (rng.random(shape) * scale).astype(np.float32) if on else none

    rel = layer(relief, 1.6)
    if relief:
        rel.flat[-1] = np.nan
    args = (
        z, bands, *_check_tables(tables), relief, rel, np.float32(0.8), layer(lit),
        layer(sky), layer(ink), np.array([0.1, 0.5, 0.9], np.float32),
    )  # fmt: skip
    want = np.empty((*shape, 4), np.uint8)
    got = np.empty((*shape, 4), np.uint8)
    bk.map_image(*args, want)
    bk.map_image_fast(*args, got)
    np.testing.assert_array_equal(got, want)


def test_color_bands_out_is_written_and_returned():
    """``out=``: the same colours written into the caller's array (every stale value
    overwritten, nodata included), and the array returned; bad arrays are refused."""
    rng = np.random.default_rng(4)
    z = (rng.random((37, 41)) * 900).astype(np.float32)
    z[5:9, 3:12] = np.nan
    expected = color_bands(z, interval=100.0)
    out = np.full((37, 41, 4), 7.0, np.float32)
    assert color_bands(z, interval=100.0, out=out) is out
    np.testing.assert_array_equal(out, expected)
    for bad, match in (
        (np.empty((37, 41, 3), np.float32), "shape"),
        (np.empty((37, 41, 4), np.float64), "float32"),
        (np.empty((41, 37, 4), np.float32).transpose(1, 0, 2), "C-contiguous"),
        ([[0.0]], "numpy array"),
    ):
        with pytest.raises(InputError, match=match):
            color_bands(z, interval=100.0, out=bad)
