"""GDAL-compatible hillshade: analytic planes and cones, and real ``gdaldem hillshade`` output."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import _hillshade_kernels as K
from sciviz_gbuf.filters import hillshade

VARIANTS = ("regular", "combined", "multidirectional", "igor")
ALGORITHMS = ("horn", "zevenbergen_thorne")
METRES_PER_DEGREE = 111120.0  # gdaldem's documented -s for metres over lat/long


def plane(shape, dx, dy, east_slope, north_slope):
    """Heights ``east_slope * east + north_slope * north``; row 0 is north, column 0 west."""
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    return east_slope * cols * dx + north_slope * (-rows * dy)


def light_vector(azimuth, altitude):
    """Unit vector towards the light in (east, north, up); azimuth clockwise from north."""
    az, alt = np.radians(azimuth), np.radians(altitude)
    return np.array([np.sin(az) * np.cos(alt), np.cos(az) * np.cos(alt), np.sin(alt)])


# ---------------------------------------------------------------------------------------------
# analytic


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("altitude", [0.0, 20.0, 45.0, 90.0])
def test_flat_ground_is_sin_altitude(algorithm, altitude):
    z = np.full((6, 7), 123.0)
    for variant in ("regular", "multidirectional"):
        sh = hillshade(z, altitude=altitude, algorithm=algorithm, variant=variant)
        np.testing.assert_allclose(sh, np.sin(np.radians(altitude)), atol=1e-6)
    # combined multiplies by the slope and igor only darkens slopes: flat ground is white
    for variant in ("combined", "igor"):
        np.testing.assert_allclose(hillshade(z, altitude=altitude, variant=variant), 1.0)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize(
    ("east_slope", "north_slope", "azimuth", "altitude"),
    [
        (0.3, -0.2, 315.0, 45.0),
        (-0.7, 0.1, 100.0, 30.0),
        (1.5, 0.9, 200.0, 60.0),
        (0.0, 2.0, 0, 10),
    ],
)
def test_plane_shade_is_the_cosine_of_incidence(
    algorithm, east_slope, north_slope, azimuth, altitude
):
    dx, dy = 2.0, 3.0
    z = plane((9, 11), dx, dy, east_slope, north_slope)
    normal = np.array([-east_slope, -north_slope, 1.0])
    expected = max(0.0, normal @ light_vector(azimuth, altitude) / np.linalg.norm(normal))
    sh = hillshade(z, dx=dx, dy=dy, azimuth=azimuth, altitude=altitude, algorithm=algorithm)
    # planes are reproduced exactly, borders included (GDAL extrapolates linearly there) but for
    # the four corners, where GDAL repeats the centre column instead of extrapolating it
    corners = np.zeros(z.shape, bool)
    corners[[0, 0, -1, -1], [0, -1, 0, -1]] = True
    np.testing.assert_allclose(sh[~corners], expected, atol=2e-5)
    # z_factor scales the heights; dx, dy scale the grid
    np.testing.assert_allclose(
        hillshade(z / 2, dx=dx, dy=dy, z_factor=2.0, azimuth=azimuth, altitude=altitude),
        sh,
        atol=2e-5,
    )
    np.testing.assert_allclose(
        hillshade(z * 3, dx=3 * dx, dy=3 * dy, azimuth=azimuth, altitude=altitude), sh, atol=2e-5
    )


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("azimuth", [0.0, 135.0, 315.0])
def test_plane_facing_the_sun_is_fully_lit(azimuth, algorithm):
    light = light_vector(azimuth, 35.0)
    z = plane((5, 6), 1.0, 1.0, -light[0] / light[2], -light[1] / light[2])
    sh = hillshade(z, azimuth=azimuth, altitude=35.0, algorithm=algorithm)
    np.testing.assert_allclose(sh[1:-1, :], 1.0, atol=1e-5)  # corners: see the test above
    # facing away: GDAL clamps at 0 (Byte 1)
    np.testing.assert_allclose(hillshade(-z, azimuth=azimuth, altitude=35.0)[1:-1, :], 0.0)


def test_azimuth_315_lights_north_west_slopes_of_a_cone():
    rows, cols = np.mgrid[0:41, 0:41]
    north, east = 20.0 - rows, cols - 20.0  # row 0 is north
    z = 100.0 - 2.0 * np.hypot(east, north)
    diagonal = (np.abs(north) == np.abs(east)) & (np.abs(north) < 20)  # corners: see above
    nw = diagonal & (north > 3) & (east < 0)
    se = diagonal & (north < -3) & (east > 0)
    ne = diagonal & (north > 3) & (east > 0)
    sw = diagonal & (north < -3) & (east < 0)
    # the north-west flank's normal is (-sqrt2, sqrt2, 1) / sqrt5: it faces the light
    lit = np.array([-np.sqrt(2), np.sqrt(2), 1.0]) / np.sqrt(5.0) @ light_vector(315, 45)
    sh = hillshade(z)
    np.testing.assert_allclose(sh[nw], lit, atol=5e-3)
    assert (sh[se] == 0).all()  # the opposite flank is in its own shade (slope 63 > 45 degrees)
    assert sh[nw].min() > sh[ne].max() > sh[se].max()
    np.testing.assert_allclose(np.sort(sh[ne]), np.sort(sh[sw]), atol=1e-5)  # lit side-on, alike
    # the light from the south-east swaps them
    np.testing.assert_allclose(hillshade(z, azimuth=135.0)[se], lit, atol=5e-3)
    # igor: shadowness is slope / 90 times how squarely the slope faces away from the light
    igor = hillshade(z, variant="igor")
    np.testing.assert_allclose(igor[se], 1 - np.degrees(np.arctan(2.0)) / 90, atol=5e-3)
    np.testing.assert_allclose(igor[nw], 1.0, atol=5e-3)


def test_nodata_nan_mask_and_tiny_grids():
    z = plane((8, 9), 1.0, 1.0, 0.4, 0.1)
    m = np.ones(z.shape, bool)
    m[3, 4] = m[0, 0] = False
    holes = np.where(m, z, np.nan)
    a = hillshade(z, mask=m)
    b = hillshade(holes)
    np.testing.assert_array_equal(np.isnan(a), ~m)
    np.testing.assert_array_equal(a, b)
    # nodata neighbours take the centre's height (GDAL -compute_edges), so they flatten the slope
    assert a[3, 3] != pytest.approx(hillshade(z)[3, 3])
    # +-inf are nodata too
    assert np.isnan(hillshade(np.where(m, z, np.inf))[3, 4])
    # no 3x3 neighbourhood: GDAL writes nodata everywhere
    assert np.isnan(hillshade(np.ones((1, 5)))).all()
    assert np.isnan(hillshade(np.ones((4, 1)))).all()
    assert np.isfinite(hillshade(np.ones((2, 2)))).all()


@pytest.mark.parametrize(
    ("heights", "kwargs"),
    [
        (np.zeros(5), {}),
        (np.zeros((2, 3, 4)), {}),
        (np.zeros((3, 3)), {"dx": 0.0}),
        (np.zeros((3, 3)), {"dy": -1.0}),
        (np.zeros((3, 3)), {"dx": np.nan}),
        (np.zeros((3, 3)), {"altitude": -1.0}),
        (np.zeros((3, 3)), {"altitude": 90.5}),
        (np.zeros((3, 3)), {"azimuth": np.inf}),
        (np.zeros((3, 3)), {"z_factor": np.nan}),
        (np.zeros((3, 3)), {"algorithm": "sobel"}),
        (np.zeros((3, 3)), {"variant": "swiss"}),
        (np.zeros((3, 3)), {"mask": np.ones((3, 4), bool)}),
        (np.array([["a", "b"], ["c", "d"]]), {}),
    ],
)
def test_bad_parameters_raise_input_error(heights, kwargs):
    with pytest.raises(InputError):
        hillshade(heights, **kwargs)


@settings(max_examples=60, deadline=None)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(1, 6), st.integers(1, 6)),
        elements=st.one_of(
            st.floats(-1e4, 1e4), st.just(np.nan), st.just(np.inf), st.just(-np.inf), st.just(7.0)
        ),
    ),
    st.sampled_from(VARIANTS),
    st.sampled_from(ALGORITHMS),
    st.floats(0, 90),
    st.floats(-720, 720),
)
def test_never_crashes_stays_in_range_and_input_untouched(z, variant, algorithm, altitude, azimuth):
    before = z.copy()
    mask = np.isfinite(z) | (z > 0)
    sh = hillshade(z, variant=variant, algorithm=algorithm, altitude=altitude, azimuth=azimuth)
    sh_m = hillshade(z, mask=mask, variant=variant, algorithm=algorithm, dx=0.5, dy=2.0)
    for s in (sh, sh_m):
        assert s.dtype == np.float32 and s.shape == z.shape
        finite = s[~np.isnan(s)]
        assert ((finite >= 0) & (finite <= 1)).all()
    assert np.isnan(sh[~np.isfinite(z)]).all()
    np.testing.assert_array_equal(z, before)


# ---------------------------------------------------------------------------------------------
# the vectorised float32 kernel against GDAL's per-cell statement (float64)

_ALG = {"horn": 0, "zevenbergen_thorne": 1}
_VAR = {"regular": 0, "combined": 1, "multidirectional": 2, "igor": 3}


def _both(z, variant, algorithm, dx=3.0, dy=2.0, zf=1.7, az=300.0, alt=40.0):
    z32 = np.ascontiguousarray(z, np.float32)
    args = (1.0 / dx, -1.0 / dy, zf, az, alt, _ALG[algorithm], _VAR[variant])
    return K.hillshade_kernel(z32, *args), K.hillshade_reference_kernel(z32, *args)


def rough_dem(n=300, seed=0, holes=True):
    rng = np.random.default_rng(seed)
    z = np.cumsum(np.cumsum(rng.standard_normal((n, n + 17)), 0), 1) * 0.5 + 1500.0
    z[120:135, :] = 1500.0  # flat ground: the multidirectional and igor special cases
    if holes:
        z[rng.random(z.shape) < 0.02] = np.nan  # scattered nodata
        z[40:70, 200:260] = np.nan  # a lake
        z[:, 5] = np.nan  # a nodata column next to the border
    return z


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_fast_kernel_equals_the_per_cell_statement(variant, algorithm):
    for holes in (False, True):
        fast, ref = _both(rough_dem(holes=holes), variant, algorithm)
        np.testing.assert_array_equal(np.isnan(fast), np.isnan(ref))
        assert np.nanmax(np.abs(fast - ref)) <= 2e-5  # 1 grey level is 4e-3
        assert np.nanstd(ref) > 0.05  # not a flat answer
    # cells next to nodata and on the border are the reference's own float64 values
    z = rough_dem()
    fast, ref = _both(z, variant, algorithm)
    near = ndimage_dilate(np.isnan(z))
    near[[0, -1], :] = near[:, [0, -1]] = True
    np.testing.assert_array_equal(fast[near], ref[near])


def ndimage_dilate(m):
    from scipy import ndimage

    return ndimage.binary_dilation(m, np.ones((3, 3), bool))


@settings(max_examples=80, deadline=None)
@given(
    arrays(
        np.float32,
        st.tuples(st.integers(1, 7), st.integers(1, 9)),
        elements=st.one_of(
            st.floats(-(2.0**100), 2.0**100, width=32), st.just(np.nan), st.just(0.0), st.just(3e38)
        ),
    ),
    st.sampled_from(VARIANTS),
    st.sampled_from(ALGORITHMS),
)
def test_fast_kernel_on_odd_grids(z, variant, algorithm):
    """Tiny grids, huge heights (float32 overflow in the gradient), nodata anywhere: the same
    cells are nodata and the values agree (overflowing cells go to the per-cell path)."""
    fast, ref = _both(z, variant, algorithm, dx=1.0, dy=1.0)
    np.testing.assert_array_equal(np.isnan(fast), np.isnan(ref))
    np.testing.assert_allclose(fast, ref, atol=2e-5)


def test_out_is_written_and_returned():
    z = rough_dem(100)
    expected = hillshade(z, dx=3.0, variant="multidirectional")
    out = np.full(z.shape, 7.0, np.float32)  # stale values must all be overwritten
    got = hillshade(z, dx=3.0, variant="multidirectional", out=out)
    assert got is out
    np.testing.assert_array_equal(out, expected)
    tiny = np.full((1, 4), 7.0, np.float32)
    assert np.isnan(hillshade(np.ones((1, 4)), out=tiny)).all()


@pytest.mark.parametrize(
    "out",
    [
        np.zeros((100, 117), np.float64),
        np.zeros((100, 116), np.float32),
        np.zeros((117, 100), np.float32).T,
        [[0.0]],
    ],
)
def test_bad_out_is_refused(out):
    z = rough_dem(100)
    with pytest.raises(InputError, match="out"):
        hillshade(z, out=out)


def test_out_may_not_alias_the_heights():
    z = rough_dem(50).astype(np.float32)
    with pytest.raises(InputError, match="shares memory"):
        hillshade(z, out=z)
    ro = np.zeros(z.shape, np.float32)
    ro.flags.writeable = False
    with pytest.raises(InputError, match="writeable"):
        hillshade(z, out=ro)


# ---------------------------------------------------------------------------------------------
# against gdaldem (GDAL's Byte output: 0 = nodata, 1..255 = shade)


def read_asc(path: Path) -> tuple[np.ndarray, float]:
    """ESRI ASCII grid -> (heights with NaN at NODATA_value, cell size)."""
    header = {}
    with open(path) as f:
        for _ in range(6):
            key, value = f.readline().split()
            header[key.lower()] = float(value)
    z = np.loadtxt(path, skiprows=6, dtype=np.float64, ndmin=2)
    z[z == header["nodata_value"]] = np.nan
    return z, header["cellsize"]


def write_asc(path: Path, z: np.ndarray, dx: float, dy: float) -> None:
    """ESRI ASCII grid with GDAL's ``dx``/``dy`` header lines (NaN -> -9999)."""
    header = f"ncols {z.shape[1]}\nnrows {z.shape[0]}\nxllcorner 0\nyllcorner 0\n"
    header += f"dx {dx!r}\ndy {dy!r}\nNODATA_value -9999\n"
    np.savetxt(path, np.where(np.isnan(z), -9999, z), fmt="%.17g", header=header, comments="")


def gdaldem_hillshade(src: Path, out: Path, shape, *, algorithm, variant, z, s, az, alt):
    """Run ``gdaldem hillshade -compute_edges`` and read its raw ENVI Byte output."""
    cmd = [
        "gdaldem",
        "hillshade",
        "-q",
        "-compute_edges",
        "-of",
        "ENVI",
        "-z",
        str(z),
        "-s",
        str(s),
    ]
    if algorithm == "zevenbergen_thorne":
        cmd += ["-alg", "ZevenbergenThorne"]
    if variant != "regular":
        cmd.append(f"-{variant}")
    if variant != "multidirectional":  # GDAL refuses -az with -multidirectional
        cmd += ["-az", str(az)]
    if variant != "igor":  # ... and -alt with -igor
        cmd += ["-alt", str(alt)]
    subprocess.run([*cmd, str(src), str(out)], check=True, capture_output=True)
    return np.fromfile(out, dtype=np.uint8).reshape(shape)


def as_gdal_bytes(shade: np.ndarray, variant: str) -> np.ndarray:
    """GDAL's float -> Byte: round(1 + 254 * shade) (255 * shade for -igor); 0 = nodata."""
    scale, offset = (255.0, 0.0) if variant == "igor" else (254.0, 1.0)
    return np.where(np.isnan(shade), 0, np.rint(shade * scale + offset)).astype(np.int16)


def load_case(name: str, data: Path, tmp_path: Path):
    """(GDAL input file, heights with NaN nodata, dx, dy, gdaldem -s, z, az, alt) of one case."""
    if name.endswith(".asc"):
        z, cell = read_asc(data / "dem" / name)
        s = METRES_PER_DEGREE if cell < 0.01 else 1.0  # the SRTMGL3 grid is in degrees
        return data / "dem" / name, z, cell * s, cell * s, s, 1.5, 290.0, 40.0
    if name.endswith(".hgt"):
        z = np.fromfile(data / "dem" / name, dtype=">i2").reshape(1201, 1201).astype(np.float64)
        z[z == -32768] = np.nan
        cell = 1.0 / 1200.0 * METRES_PER_DEGREE
        # almost flat: exaggerate so that the comparison sees real slopes
        return data / "dem" / name, z, cell, cell, METRES_PER_DEGREE, 20.0, 315.0, 45.0
    from matplotlib.cbook import get_sample_data

    dem = get_sample_data("jacksboro_fault_dem.npz")
    z = dem["elevation"].astype(np.float64)
    ddx, ddy = float(dem["dx"]), float(dem["dy"])
    if name == "jacksboro_anisotropic":  # dx != dy: GDAL's general (not same-resolution) path
        ddy *= 1.7
    src = tmp_path / "jacksboro.asc"
    write_asc(src, z, ddx, ddy)
    s = METRES_PER_DEGREE
    return src, z, ddx * s, ddy * s, s, 2.0, 45.0, 30.0


CASES = (
    "hugo_site.asc",
    "pre_runout_DEM.asc",
    "SRTMGL3_40.09_-105.55_40.21_-105.35.asc",
    "N10W110.hgt",
    "jacksboro",
    "jacksboro_anisotropic",
)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("case", CASES)
def test_matches_gdaldem(case, variant, algorithm, shared_data, tmp_path):
    if shutil.which("gdaldem") is None:
        pytest.skip("gdaldem (gdal-bin) is not installed")
    src, z, dx, dy, s, zf, az, alt = load_case(case, shared_data, tmp_path)
    before = z.copy()
    how = {"algorithm": algorithm, "variant": variant}
    gdal = gdaldem_hillshade(src, tmp_path / "o.raw", z.shape, z=zf, s=s, az=az, alt=alt, **how)
    ours = hillshade(z, dx=dx, dy=dy, azimuth=az, altitude=alt, z_factor=zf, **how)
    np.testing.assert_array_equal(z, before)
    valid = gdal != 0
    np.testing.assert_array_equal(np.isnan(ours), ~valid)  # nodata at the same cells
    diff = np.abs(as_gdal_bytes(ours, variant) - gdal.astype(np.int16))[valid]
    assert diff.mean() <= 0.5, diff.mean()
    assert diff.max() <= 1, diff.max()
    # the comparison is not vacuous: the output spans a range of grey levels
    assert np.ptp(gdal[valid]) > 20
