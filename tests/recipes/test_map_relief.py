"""The relief of a topographic map on low-relief DEMs: the automatic z factor (``z_factor=None``)
lifts a gentle DEM's relief to the contrast of hilly ground, leaves steep DEMs at z = 1, an
explicit ``z_factor`` wins, and the chunked map computes the same factor (same pixels)."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes import _map
from tests.helpers.paths import SHARED_DATA

RELIEF_ONLY = {"contours": False, "bands": False}


def _shared(name: str):
    path = SHARED_DATA / "dem" / name
    if not path.is_file():
        pytest.skip(f"{path} not available")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the SRTM .asc has no CRS
        return read_dem(path)


def _scaled(d, factor: float):
    return dataclasses.replace(d, heights=(d.heights * np.float32(factor)).astype(np.float32))


def relief_contrast(rgba: np.ndarray) -> float:
    """Standard deviation of a relief-only map's grey level (0-1) over its valid cells."""
    valid = rgba[..., 3] > 0
    return float(rgba[..., 0][valid].std() / 255.0)


def hills(relief_m: float, shape=(96, 128), spacing=10.0):
    """Smooth random hills on 10 m cells, ``relief_m`` metres from the lowest to the highest."""
    rng = np.random.default_rng(4)
    z = ndimage.gaussian_filter(rng.standard_normal(shape), 6)
    z = (z - z.min()) / (z.max() - z.min()) * relief_m + 300.0
    return read_dem(z.astype(np.float32), spacing=spacing)


def test_rule():
    target = math.tan(math.radians(_map.RELIEF_SLOPE))
    assert _map.relief_z_factor(None, target / 4.0) == pytest.approx(4.0)
    assert _map.relief_z_factor(None, 0.5) == 1.0  # steeper than 10 degrees: the true relief
    assert _map.relief_z_factor(None, 1e-6) == _map.RELIEF_Z_MAX  # a plain: at most 20 times
    assert _map.relief_z_factor(None, float("nan")) == 1.0  # nothing but flat cells
    assert _map.relief_z_factor(2.5, 1e-6) == 2.5  # a given factor wins


@pytest.mark.parametrize("source", ["pre_runout_DEM.asc", "hugo_site.asc", "synthetic"])
def test_low_relief_dem_gets_the_contrast_of_normal_relief(source):
    """The DEM flattened 20 times: at z = 1 its relief is washed out (a tenth of the contrast
    or less), automatically it has at least 40 % of the contrast of the DEM as it is."""
    d = hills(100.0) if source == "synthetic" else _shared(source)  # hills: 14 degrees
    low = _scaled(d, 0.05)
    normal = relief_contrast(sg.topographic_map(d, z_factor=1.0, **RELIEF_ONLY))
    washed = relief_contrast(sg.topographic_map(low, z_factor=1.0, **RELIEF_ONLY))
    auto = relief_contrast(sg.topographic_map(low, **RELIEF_ONLY))
    assert normal > 0.03, normal  # a relief to compare with
    assert washed < 0.1 * normal, (washed, normal)  # the measure can fail
    assert auto > 0.4 * normal, (auto, normal)


@pytest.mark.parametrize("source", ["pre_runout_DEM.asc", "synthetic"])
def test_steep_dem_keeps_its_true_relief(source):
    """Median slope over 10 degrees (pre_runout: 22; the hills: 27): z = 1, the same
    pixels as an explicit ``z_factor=1``, also with the sky view."""
    d = hills(200.0) if source == "synthetic" else _shared(source)
    for extra in ({}, {"sky_view": True, "contours": False}):
        assert np.array_equal(sg.topographic_map(d, **extra),
                              sg.topographic_map(d, z_factor=1.0, **extra))  # fmt: skip


def test_explicit_z_factor_wins():
    low = hills(20.0)  # median slope 3 degrees: the automatic factor is about 3.5
    auto = sg.topographic_map(low)
    for z in (1.0, 3.0):
        given = sg.topographic_map(low, z_factor=z)
        assert not np.array_equal(given, auto)
        hs = sg.filters.hillshade(low.heights, dx=10.0, dy=10.0, z_factor=z)
        grey = sg.topographic_map(low, z_factor=z, **RELIEF_ONLY)[..., 0].astype(float)
        inner = (slice(2, -2), slice(2, -2))
        order = np.argsort(hs[inner].ravel())  # the map is monotone in that hillshade
        assert np.all(np.diff(grey[inner].ravel()[order]) >= -1)
    with pytest.raises(InputError, match="z_factor"):
        sg.topographic_map(low, z_factor=float("nan"))
    with pytest.raises(InputError, match="z_factor"):
        sg.topographic_map(low, z_factor="steep")


def test_automatic_factor_is_the_rule_on_the_median_ground_slope():
    """The automatic map equals the map at the z factor of the rule for the median ground
    slope (rise over run, metres over metres): the same DEM on 10 m and on 30 m cells gets
    factors three times apart."""
    for spacing in (10.0, 30.0):
        low = hills(20.0, spacing=spacing)
        z = low.heights.astype(np.float64)
        gy, gx = np.gradient(z, spacing)
        slope = float(np.median(np.hypot(gx, gy)))  # central differences: close to the rule's
        expected = math.tan(math.radians(_map.RELIEF_SLOPE)) / slope
        assert 1.0 < expected < _map.RELIEF_Z_MAX
        layers = _map.map_layers(
            low.heights, dx=spacing, dy=spacing, interval=None, major_interval=None,
            contours=False, width=1.0, major_width=2.0, dense_spacing=4.0, generalize=True,
            bands=False, cmap=None, sea_level=None, relief=True, azimuth=315.0,
            altitude=45.0, z_factor=None, variant="regular", shadows=False, sky_view=False,
        )  # fmt: skip
        assert layers["z_factor"] == pytest.approx(expected, rel=0.15)
        assert np.array_equal(
            sg.topographic_map(low), sg.topographic_map(low, z_factor=layers["z_factor"])
        )


def test_chunked_map_uses_the_same_automatic_factor():
    da = pytest.importorskip("dask.array")
    low = hills(20.0)
    lazy = dataclasses.replace(
        low, heights=da.from_array(low.heights, chunks=(23, 37)),
        mask=da.from_array(low.mask, chunks=(23, 37)),
    )  # fmt: skip
    for kwargs in ({}, {"interval": 1.0, "vmin": 300.0, "vmax": 320.0}, {"sky_view": True}):
        ref = sg.topographic_map(low, **kwargs)
        assert not np.array_equal(ref, sg.topographic_map(low, z_factor=1.0, **kwargs))
        assert np.array_equal(sg.topographic_map(lazy, **kwargs).compute(), ref)


# -- the bird's-eye relief ---------------------------------------------------------------------
BIRD = {"size": 240, "supersample": 1}


def sh_contrast(layers: dict) -> float:
    """Spread of a bird's-eye relief shade over its fully covered pixels."""
    return float(layers["sh"][layers["alpha"] >= 1.0].std())


def test_birdseye_low_relief_gets_the_contrast_of_normal_relief():
    """As for plan-view maps: the hills flattened 20 times are washed out at z = 1 (the shade of
    the geometry as rendered), automatically their shade has at least 40 % of the contrast
    of the hills as they are; the geometry is the same in both (only the shade changes)."""
    from sciviz_gbuf.recipes.birdseye import birdseye_gbuffer, birdseye_layers

    d = hills(100.0)
    normal = sh_contrast(birdseye_layers(birdseye_gbuffer(d, **BIRD), z_factor=1.0))
    gb = birdseye_gbuffer(_scaled(d, 0.05), **BIRD)
    washed = birdseye_layers(gb, z_factor=1.0)
    auto = birdseye_layers(gb)
    assert normal > 0.05, normal
    assert sh_contrast(washed) < 0.15 * normal, (sh_contrast(washed), normal)
    assert sh_contrast(auto) > 0.4 * normal, (sh_contrast(auto), normal)
    assert np.array_equal(auto["alpha"], washed["alpha"])
    assert np.array_equal(auto["cn"], washed["cn"])


def test_birdseye_steep_ground_keeps_its_true_relief():
    from sciviz_gbuf.recipes.birdseye import birdseye_gbuffer, birdseye_layers

    gb = birdseye_gbuffer(hills(200.0), **BIRD)
    assert np.array_equal(birdseye_layers(gb)["sh"], birdseye_layers(gb, z_factor=1.0)["sh"])


def test_exaggerated_normals_are_those_of_the_exaggerated_surface():
    """The shade's normals at z factor 3 are the normals VTK renders for the heights times 3
    (a tilted plane: one normal everywhere)."""
    from sciviz_gbuf.recipes.birdseye import (
        birdseye_gbuffer,
        exaggerated_normals,
        rendered_ground_slope,
    )

    y, x = np.mgrid[0:60, 0:80].astype(np.float32)
    plane = read_dem((0.3 * x + 0.1 * y).astype(np.float32), spacing=10.0)
    flat_gb = birdseye_gbuffer(plane, **BIRD)
    tall_gb = birdseye_gbuffer(_scaled(plane, 3.0), **BIRD)

    def median_normal(n, gb):
        return np.median(n[gb.mask].reshape(-1, 3), axis=0)

    want = median_normal(tall_gb.world_normal(), tall_gb)
    got = median_normal(exaggerated_normals(flat_gb.world_normal(), 3.0), flat_gb)
    np.testing.assert_allclose(got, want, atol=2e-3)
    # the slope of the rendered plane, rise over run: hypot(0.3, 0.1) / 10 m
    slope = rendered_ground_slope(flat_gb.world_normal(), flat_gb.mask)
    assert slope == pytest.approx(math.hypot(0.03, 0.01), rel=1e-3)


def test_birdseye_z_factor_is_checked():
    with pytest.raises(InputError, match="z_factor"):
        sg.birdseye_map(hills(20.0), z_factor=float("nan"), **BIRD)
