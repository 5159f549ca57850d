"""Relief styles of topographic maps (``relief='vat'`` etc.): RVT's VAT blend against an
independent derivation on planes, flat ground left exactly as the bands colour it, valleys
dark and ridges light whatever the sun, and the command line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.recipes._relief import RELIEFS, relief_flat, relief_shade, relief_style
from sciviz_gbuf.recipes.terrain import topographic_map
from tests.helpers.cli import assert_clean_failure, run_cli

STYLES = list(RELIEFS)


def test_style_names_and_refusals():
    assert relief_style(True) == "hillshade" and relief_style(False) is None
    assert relief_style("local-relief") == "local_relief" and relief_style("vat") == "vat"
    for bad in ("VAT", "shade", 1, 0.5):
        with pytest.raises(InputError, match="relief"):
            relief_style(bad)
    with pytest.raises(InputError, match="relief"):
        topographic_map(np.zeros((8, 8)), relief="bogus")


def _gdal_hillshade(p, q, azimuth=315.0, altitude=45.0):
    """GDAL's hillshade of a plane with gradient (dz/dx east, dz/dy north)."""
    az, alt = math.radians(azimuth), math.radians(altitude)
    # aspect convention of gdaldem: light from azimuth, x east, y north
    lx, ly, lz = math.sin(az) * math.cos(alt), math.cos(az) * math.cos(alt), math.sin(alt)
    return max(0.0, (lz - p * lx - q * ly) / math.sqrt(1 + p * p + q * q))


@pytest.mark.parametrize(("p", "q"), [(0.3, -0.2), (-0.6, 0.1), (0.05, 0.9)])
def test_vat_on_a_plane_is_rvts_blend_of_its_analytic_layers(p, q):
    """On a plane every layer is known: slope atan|g|, openness 90 deg, the sky view from the
    plane's horizon angle in each of the 16 directions; the VAT value follows RVT's blender
    (luminosity 50 %, overlay 50 %, multiply 25 %)."""
    h, w = 80, 80
    i, j = np.mgrid[0:h, 0:w].astype(np.float64)
    z = 100.0 + p * j - q * i  # rows run south: height rises north with q
    got = relief_shade(z, "vat", dx=1.0, dy=1.0, azimuth=315.0, altitude=45.0, z_factor=1.0)
    hs = _gdal_hillshade(p, q)
    slope = math.degrees(math.atan(math.hypot(p, q)))
    sky = 1 - np.mean(
        [
            max(0.0, math.sin(math.atan(p * math.sin(a) + q * math.cos(a))))
            for a in np.radians(np.arange(16) * 22.5)
        ]
    )
    s = 1 - min(max(slope / 50, 0), 1)
    o = (90 - 68) / 25
    base = 0.5 * s + 0.5 * hs
    over = 1 - 2 * (1 - base) * (1 - o) if base > 0.5 else 2 * base * o
    base = 0.5 * over + 0.5 * base
    want = base * (0.75 + 0.25 * min(max((sky - 0.7) / 0.3, 0), 1))
    inner = got[15:-15, 15:-15]  # every ray of 10 cells stays inside the plane
    np.testing.assert_allclose(inner, want, atol=2e-3)


@pytest.mark.parametrize("style", STYLES)
def test_flat_ground_keeps_the_band_colours(style):
    """Flat ground is lit exactly as ``relief=False`` leaves it, whatever the style."""
    z = np.full((40, 60), 250.0)
    z[10:20, 25:35] = np.nan  # a hole of nodata changes nothing around it
    opts = {"contours": False, "interval": 100.0, "major_interval": 500.0}
    lit = topographic_map(z, relief=style, **opts)
    plain = topographic_map(z, relief=False, **opts)
    assert (lit[10:20, 25:35, 3] == 0).all()
    assert np.abs(lit.astype(int) - plain.astype(int)).max() <= 1


def _valley():
    """A V valley along the rows (north-south) at column 40 between ridges at 0 and 80: with
    the sun from the north both slopes are lit alike."""
    j = np.arange(81, dtype=np.float64)
    z = 10.0 * np.abs(j - 40.0)[None, :] * np.ones((60, 1))
    return z


@pytest.mark.parametrize("style", ["openness", "texture", "local_relief"])
def test_valleys_dark_and_ridges_light_with_the_sun_along_the_valley(style):
    z = _valley()
    sh = relief_shade(z, style, dx=10.0, dy=10.0, azimuth=0.0, altitude=45.0, z_factor=1.0)
    hs = relief_shade(z, "hillshade", dx=10.0, dy=10.0, azimuth=0.0, altitude=45.0)
    row = 30
    # the hillshade is the same on both slopes and at the bottom: it shows no valley
    assert abs(hs[row, 30] - hs[row, 50]) < 1e-6
    assert sh[row, 40] < sh[row, 30] - 0.02 and sh[row, 40] < sh[row, 50] - 0.02
    flat = relief_flat(style, 10.0, 10.0, azimuth=0.0, altitude=45.0)
    assert 0 < flat <= 1


def test_map_with_each_style_is_distinct_and_draws_nodata_transparent(tmp_path):
    rng = np.random.default_rng(2)
    from scipy import ndimage

    z = ndimage.gaussian_filter(rng.normal(size=(120, 160)), 4) * 400 + 1000
    z[:10, :10] = np.nan
    imgs = {s: topographic_map(z, relief=s, contours=False) for s in STYLES}
    for s, img in imgs.items():
        assert img.shape == (120, 160, 4) and (img[:10, :10, 3] == 0).all(), s
        assert (img[20:, 20:, 3] == 255).all()
    for a in STYLES:
        for b in STYLES:
            if a < b:
                diff = np.abs(imgs[a][..., :3].astype(int) - imgs[b][..., :3].astype(int))
                assert diff.mean() > 1.0, (a, b)


def test_topo_relief_flag(tmp_path):
    dem = tmp_path / "dem.asc"
    z = np.add.outer(np.arange(40.0), np.arange(50.0)) * 3.0
    header = "ncols 50\nnrows 40\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n"
    dem.write_text(header + "\n".join(" ".join(f"{v:g}" for v in r) for r in z))
    out = tmp_path / "vat.png"
    proc = run_cli(["topo", str(dem), "-o", str(out), "--relief", "vat", "--contours", "none"])
    assert proc.returncode == 0, proc.stderr
    assert out.is_file()
    bad = run_cli(["topo", str(dem), "-o", str(tmp_path / "x.png"), "--relief", "sunny"])
    assert_clean_failure(bad, names="--relief", outputs=[tmp_path / "x.png"])
    both = run_cli(["topo", str(dem), "-o", str(tmp_path / "y.png"), "--relief", "vat",
                    "--no-relief"])  # fmt: skip
    assert_clean_failure(both, names="--no-relief", outputs=[tmp_path / "y.png"])
