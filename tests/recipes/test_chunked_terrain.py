"""Out-of-core terrain operators (dask): bit-identical to the in-memory path whatever the
chunking, and each halo exactly as wide as its operator's reach (one cell less breaks it)."""

from __future__ import annotations

import dataclasses
import sys
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sciviz_gbuf import _dask
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import (
    c1_discontinuity,
    cast_shadows,
    color_bands,
    contour_lines,
    diagonal_depth_discontinuity,
    hillshade,
    normalize_gradient,
    openness,
    second_order,
    sky_view,
    sobel_gradient,
    suppress_zeroth_order,
)
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes import terrain_chunked
from sciviz_gbuf.recipes.terrain import topographic_map
from tests.helpers.paths import SHARED_DATA, shared_dem

da = pytest.importorskip("dask.array")

DATA = SHARED_DATA / "dem"
ODD = (7, 13)  # deliberately odd chunks: many chunk borders in both directions


def _dem(name: str):
    return shared_dem(name)


def _lazy(d, chunks):
    return dataclasses.replace(
        d,
        heights=da.from_array(d.heights, chunks=chunks),
        mask=da.from_array(d.mask, chunks=chunks),
    )


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True)


def _module(func):
    return sys.modules[func.__module__]


@pytest.fixture(scope="module")
def hugo():
    """76 x 55, half nodata with an irregular outline: every border rule is exercised."""
    return _dem("hugo_site.asc")


@pytest.fixture(scope="module")
def rough():
    """Rough terrain with scattered nodata: far cells matter to the sky view."""
    rng = np.random.default_rng(7)
    z = (rng.random((61, 58)) ** 6 * 400).astype(np.float32)
    z[rng.random(z.shape) < 0.04] = np.nan
    return z


# Each operator, its keyword arguments and the module constant that holds its halo.
OPERATORS = [
    (hillshade, {"dx": 10.0, "dy": 10.0}, "RADIUS"),
    (hillshade, {"dx": 10.0, "dy": 7.0, "variant": "multidirectional"}, "RADIUS"),
    (hillshade, {"dx": 10.0, "dy": 10.0, "variant": "igor", "algorithm": "zevenbergen_thorne"},
     "RADIUS"),
    (contour_lines, {"interval": 2.0, "major_interval": 10.0, "width": 1.5, "major_width": 3.0},
     "RADIUS"),
    (contour_lines, {"interval": 1.0, "c_dense": 0.5, "dense_spacing": 3.0}, "RADIUS"),
    (contour_lines, {"levels": [1675.0, 1682.5, 1700.0], "profile": "smooth"}, "RADIUS"),
    (sobel_gradient, {}, "RADIUS"),
    (second_order, {}, "RADIUS"),
    (c1_discontinuity, {}, "RADIUS"),
    (normalize_gradient, {"k_g": 2.0}, "RADIUS"),
    (diagonal_depth_discontinuity, {}, "RADIUS"),
]  # fmt: skip


@pytest.mark.parametrize(("func", "kwargs", "const"), OPERATORS)
def test_operator_bit_identical_and_halo_exact(hugo, monkeypatch, func, kwargs, const):
    z = hugo.heights
    if func is diagonal_depth_discontinuity:
        z = (z - np.nanmin(z)) / 10.0  # depth-like: differences of order 1
    ref = func(z, **kwargs)
    lazy = func(da.from_array(z, chunks=ODD), **kwargs)
    assert lazy.chunks == da.from_array(z, chunks=ODD).chunks
    assert _same(lazy.compute(), ref)
    # one cell of halo less and some chunk border shows
    monkeypatch.setattr(_module(func), const, getattr(_module(func), const) - 1)
    assert not _same(func(da.from_array(z, chunks=ODD), **kwargs).compute(), ref)


def test_mask_and_gradient_inputs_may_be_dask_or_numpy(hugo):
    z = hugo.heights
    m = np.isfinite(z) & (np.arange(z.shape[1]) % 5 != 0)
    g = sobel_gradient(z)
    ref = suppress_zeroth_order(second_order(z, mask=m), g, k_l=0.5, mask=m)
    lazy = suppress_zeroth_order(
        second_order(da.from_array(z, chunks=ODD), mask=m), da.from_array(g, chunks=(9, 5)),
        k_l=0.5, mask=da.from_array(m, chunks=(11, 4)),
    )  # fmt: skip
    assert _same(lazy.compute(), ref)
    ref = contour_lines(z, interval=2.0, gradient=g, mask=m)
    assert _same(contour_lines(da.from_array(z, chunks=ODD), interval=2.0, gradient=g,
                               mask=m).compute(), ref)  # fmt: skip


@pytest.mark.parametrize(
    "kwargs",
    [
        {"interval": 10.0},
        {"levels": [1670.0, 1690.0, 1700.0]},
        {},
        {"interval": 5.0, "sea_level": 1680.0, "vmin": 1600.0, "vmax": 1800.0},
    ],
)
def test_color_bands_bit_identical(hugo, kwargs):
    ref = color_bands(hugo.heights, **kwargs)
    lazy = color_bands(da.from_array(hugo.heights, chunks=ODD), **kwargs)
    assert lazy.shape == ref.shape
    assert _same(lazy.compute(), ref)


@pytest.mark.parametrize(
    ("dx", "dy", "radius"), [(1.0, 1.0, 10.5), (2.0, 1.0, 7.5), (1.0, 3.0, 9.0)]
)
def test_sky_view_bit_identical_and_halo_exact(rough, monkeypatch, dx, dy, radius):
    ref = sky_view(rough, dx=dx, dy=dy, radius=radius, directions=32)
    lazy = sky_view(da.from_array(rough, chunks=ODD), dx=dx, dy=dy, radius=radius, directions=32)
    assert _same(lazy.compute(), ref)
    mod = _module(sky_view)
    reach = mod.sky_view_reach
    monkeypatch.setattr(mod, "sky_view_reach", lambda *a: reach(*a) - 1)
    short = sky_view(da.from_array(rough, chunks=ODD), dx=dx, dy=dy, radius=radius, directions=32)
    assert not _same(short.compute(), ref)


@pytest.mark.parametrize("kind", ["positive", "negative"])
@pytest.mark.parametrize(("dx", "dy", "radius"), [(1.0, 1.0, 10.5), (2.0, 1.0, 7.5)])
def test_openness_bit_identical_and_halo_exact(rough, monkeypatch, kind, dx, dy, radius):
    ref = openness(rough, kind=kind, dx=dx, dy=dy, radius=radius, directions=16)
    lazy = openness(da.from_array(rough, chunks=ODD), kind=kind, dx=dx, dy=dy, radius=radius,
                    directions=16)  # fmt: skip
    assert _same(lazy.compute(), ref)
    mod = _module(openness)
    reach = mod.sky_view_reach
    monkeypatch.setattr(mod, "sky_view_reach", lambda *a: reach(*a) - 1)
    short = openness(da.from_array(rough, chunks=ODD), kind=kind, dx=dx, dy=dy, radius=radius,
                     directions=16)  # fmt: skip
    assert not _same(short.compute(), ref)


MAPS = [
    ("hugo_site.asc", ODD, {}),
    ("hugo_site.asc", ODD, {"interval": 2.0}),
    ("hugo_site.asc", ODD, {"variant": "multidirectional", "bands": "continuous", "width": 2.5}),
    ("pre_runout_DEM.asc", ODD, {"sky_view": True}),
    ("pre_runout_DEM.asc", (29, 41), {"relief": "vat"}),
    ("hugo_site.asc", ODD, {"relief": "openness", "bands": False}),
    ("pre_runout_DEM.asc", ODD, {"interval": 5.0, "major_interval": 25.0, "sea_level": 300.0}),
    ("SRTMGL3_40.09_-105.55_40.21_-105.35.asc", (13, 7), {}),
    ("SRTMGL3_40.09_-105.55_40.21_-105.35.asc", (31, 17), {"bands": [2000.0, 2500.0, 3000.0]}),
    ("N10W110.hgt", (149, 167), {}),
]


@pytest.mark.parametrize(("name", "chunks", "kwargs"), MAPS)
def test_topographic_map_bit_identical_on_shared_dems(name, chunks, kwargs):
    d = _dem(name)
    ref = topographic_map(d, **kwargs)
    lazy = topographic_map(_lazy(d, chunks), **kwargs)
    assert lazy.dtype == np.uint8 and lazy.shape == ref.shape
    assert lazy.chunks[:2] == da.from_array(d.heights, chunks=chunks).chunks
    assert _same(lazy.compute(), ref)


def _read_lazy(name: str, chunks):
    path = DATA / name
    if not path.is_file():
        pytest.skip(f"{path} not available")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return read_dem(path, chunks=chunks)


@pytest.mark.parametrize(("name", "chunks", "kwargs"), MAPS)
def test_windowed_map_of_a_file_is_bit_identical_with_independent_tasks(name, chunks, kwargs):
    """A DEM file read lazily is mapped by one task per chunk that reads its own window with
    the halo: the same pixels as in memory, and no task depends on another (so a worker's
    memory does not grow with the raster)."""
    d = _read_lazy(name, chunks)
    if _dask.windows_of(d.heights) is None:
        pytest.skip(f"{name}: not read in windows")
    ref = topographic_map(_dem(name), **kwargs)
    lazy = topographic_map(d, **kwargs)
    graph = dict(lazy.__dask_graph__())
    assert len(graph) == lazy.numblocks[0] * lazy.numblocks[1]  # one task a block, nothing else
    assert _same(lazy.compute(), ref)


@pytest.mark.parametrize("min_ring", [None, 4.0, 20.0])
def test_generalised_contours_with_rings_bit_identical(min_ring):
    """Many rings of 5-20 px across chunk borders: the ring rule decides each ring alike in
    memory and chunk by chunk (a ring at most ``min_ring`` px wide is seen whole within the
    halo)."""
    y, x = np.mgrid[0:96, 0:96].astype(np.float32)
    z = (np.sin(x / 2.1) * np.cos(y / 1.7) * 4.0 + np.sin(x / 5.0 + y / 7.0) * 6.0
         + 0.02 * x).astype(np.float32)  # fmt: skip
    kwargs = {"interval": 1.0, "generalize": True, "min_ring": min_ring}
    ref = contour_lines(z, **kwargs)
    assert _same(contour_lines(da.from_array(z, chunks=(23, 29)), **kwargs).compute(), ref)
    if min_ring is None:
        exact = contour_lines(z, interval=1.0)  # the rule removed something here
        assert (exact > 0).sum() > (ref > 0).sum()


@pytest.mark.parametrize(
    "kwargs",
    [
        {"interval": 40.0, "base": 10.0, "min_ring": 0.0},  # lines ~16 px apart: sigma 3.3
        {"interval": 5.0, "major_interval": 25.0, "min_ring": 0.0},  # the map's families
    ],
)
def test_generalised_contours_bit_identical_and_smoothing_halo(hugo, monkeypatch, kwargs):
    """Generalised lines of hugo (half nodata) chunk by chunk equal those in memory. The
    smoothing reads ``SMOOTH_RADIUS`` = 12 cells and the 3x3 operator one more; that last
    cell is read only through the 3x3 range test of a level (which flips only for a value
    within rounding of a level), so it is two cells less that visibly break the pixels."""
    kwargs = {**kwargs, "generalize": True}
    ref = contour_lines(hugo.heights, **kwargs)
    lazy = contour_lines(da.from_array(hugo.heights, chunks=(21, 25)), **kwargs)
    assert len(lazy.chunks[0]) > 1 and len(lazy.chunks[1]) > 1  # chunk borders both ways
    assert _same(lazy.compute(), ref)
    mod = _module(contour_lines)
    monkeypatch.setattr(mod, "SMOOTH_RADIUS", mod.SMOOTH_RADIUS - 2)
    short = contour_lines(da.from_array(hugo.heights, chunks=(21, 25)), **kwargs)
    assert not _same(short.compute(), ref)


def test_windowed_map_halo_is_exact(monkeypatch):
    d = _read_lazy("hugo_site.asc", ODD)
    assert _dask.windows_of(d.heights) is not None
    ref = topographic_map(_dem("hugo_site.asc"), contours=False, bands=False)
    assert _same(topographic_map(d, contours=False, bands=False).compute(), ref)
    monkeypatch.setattr(terrain_chunked, "RELIEF_HALO", terrain_chunked.RELIEF_HALO - 1)
    short = topographic_map(d, contours=False, bands=False)
    assert not _same(short.compute(), ref)


def test_windowed_and_overlap_maps_of_the_synthetic_dem_agree():
    from sciviz_gbuf.datasets import synthetic_dem

    d = synthetic_dem((300, 410), chunks=(64, 96))
    assert _dask.windows_of(d.heights) is not None
    kwargs = {"sky_view": True, "major_interval": 100.0}
    windowed = topographic_map(d, **kwargs).compute()
    z = d.heights.compute()
    plain = dataclasses.replace(d, heights=z, mask=np.isfinite(z))
    assert _same(windowed, topographic_map(plain, **kwargs))
    # a derived array (no window reader) takes the map_overlap path: the same pixels
    derived = dataclasses.replace(d, heights=d.heights + np.float32(0.0))
    assert _dask.windows_of(derived.heights) is None
    assert _same(topographic_map(derived, **kwargs).compute(), windowed)


def test_topographic_map_relief_halo_is_exact(hugo, monkeypatch):
    ref = topographic_map(hugo, contours=False, bands=False)
    lazy = topographic_map(_lazy(hugo, ODD), contours=False, bands=False)
    assert _same(lazy.compute(), ref)
    # the nodata ring fill reads 2 cells beyond the hillshade window: a halo of 2 is not enough
    monkeypatch.setattr(terrain_chunked, "RELIEF_HALO", terrain_chunked.RELIEF_HALO - 1)
    short = topographic_map(_lazy(hugo, ODD), contours=False, bands=False)
    assert not _same(short.compute(), ref)


def test_plain_dask_array_is_a_dem_on_metre_pixels(rough):
    ref = topographic_map(rough)
    lazy = topographic_map(da.from_array(rough, chunks=ODD))
    assert _same(lazy.compute(), ref)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    rows=st.integers(1, 23),
    cols=st.integers(1, 23),
    seed=st.integers(0, 2**16),
    holes=st.floats(0.0, 0.6),
)
def test_any_chunking_gives_the_same_map(rows, cols, seed, holes):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:37, 0:41].astype(np.float32)
    z = (50 * np.sin(x / 6) * np.cos(y / 7) + 3 * rng.standard_normal((37, 41))).astype(np.float32)
    z[rng.random(z.shape) < holes] = np.nan
    ref = topographic_map(z, major_interval=20.0)
    lazy = topographic_map(da.from_array(z, chunks=(rows, cols)), major_interval=20.0)
    assert _same(lazy.compute(), ref)


def test_graph_is_lazy_and_global_pass_only_when_needed(rough):
    calls = []

    def source(block):
        calls.append(block.shape)
        return block

    z = da.from_array(rough, chunks=ODD).map_blocks(
        source, dtype=np.float32, meta=np.empty((0, 0), np.float32)
    )
    given = {"interval": 5.0, "major_interval": 25.0, "vmin": 0.0, "vmax": 400.0}
    lazy = topographic_map(z, **given, z_factor=1.0)
    assert calls == [], "all parameters given: building the map must not read the heights"
    lazy.compute()
    assert calls
    n_chunks = z.numblocks[0] * z.numblocks[1]
    for kwargs in ({}, given):  # default range, intervals or z factor: one pass, nothing more
        calls.clear()
        topographic_map(z, **kwargs)
        assert len(calls) == n_chunks


def test_bad_parameters_raise_before_any_computation(rough):
    z = da.from_array(rough, chunks=ODD)
    with pytest.raises(InputError, match="altitude"):
        hillshade(z, altitude=120.0)
    with pytest.raises(InputError, match="interval"):
        contour_lines(z, interval=-1.0)
    with pytest.raises(InputError, match="mask"):
        hillshade(z, mask=np.ones((3, 3), bool))
    with pytest.raises(InputError, match="radius"):
        sky_view(z, radius=float("nan"))
    with pytest.raises(InputError, match="heights"):
        hillshade(da.zeros((4, 4, 2), chunks=2))
    with pytest.raises(InputError, match="bands"):
        topographic_map(z, bands="purple")


def test_unbounded_operators_are_refused(rough):
    z = da.from_array(rough, chunks=ODD)
    with pytest.raises(InputError, match="chunk"):
        cast_shadows(z)
    with pytest.raises(InputError, match="shadows"):
        topographic_map(z, shadows=True)


def test_synthetic_dem_does_not_depend_on_chunking():
    from sciviz_gbuf.datasets import synthetic_dem

    a = synthetic_dem((90, 130), chunks=(7, 13)).heights.compute()
    b = synthetic_dem((90, 130), chunks=4096).heights.compute()
    assert _same(a, b)
    assert 100.0 < float(np.ptp(a)) and np.isfinite(a).all()


def test_local_cluster_to_cog_equals_the_in_memory_map(tmp_path):
    """The issue's scale test at CI size: a synthetic DEM generated chunk by chunk, mapped on a
    2-worker LocalCluster with a memory limit, streamed into a COG: every pixel as in memory.
    (Peak memory at 20000 x 20000 is measured by benchmarks/bench_dask.py; at this size the
    workers' memory is mostly numba's compiler on a fresh clone, not data.)"""
    pytest.importorskip("distributed")
    rasterio = pytest.importorskip("rasterio")
    from sciviz_gbuf.datasets import synthetic_dem
    from sciviz_gbuf.writers.cog import local_client, write_cog

    dem = synthetic_dem((1100, 1300), chunks=(301, 257))
    z = dem.heights.compute()
    ref = topographic_map(dataclasses.replace(dem, heights=z, mask=np.isfinite(z)))
    client = local_client(2, memory_limit="2GB")
    try:
        out = write_cog(topographic_map(dem), tmp_path / "map.tif", dem=dem, client=client)
    finally:
        cluster = client.cluster
        client.close()
        cluster.close()
    with rasterio.open(out) as src:
        assert src.transform.to_gdal() == pytest.approx(dem.transform)
        pixels = np.moveaxis(src.read(), 0, 2)
    assert _same(pixels, ref)


@pytest.mark.parametrize("style", ["texture", "local_relief"])
def test_whole_grid_relief_styles_are_refused_chunk_by_chunk(style):
    d = _dem("hugo_site.asc")
    with pytest.raises(InputError, match="whole map"):
        topographic_map(_lazy(d, ODD), relief=style)
