"""read_dem: ESRI ASCII, SRTM .hgt, .npy/.npz, GeoTIFF, USGS .dem, arrays, DataArrays; surfaces."""

from __future__ import annotations

import math
import struct
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sciviz_gbuf.datasets import metres_per_degree
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import DEM, read_dem

SRTM_ASC = "SRTMGL3_40.09_-105.55_40.21_-105.35.asc"


def asc_rows(path) -> tuple[dict[str, str], list[list[str]]]:
    """Header and rows of an ESRI ASCII grid, parsed here by hand (no package code)."""
    lines = path.read_text().splitlines()
    header = {ln.split()[0].lower(): ln.split()[1] for ln in lines[:6]}
    return header, [ln.split() for ln in lines[6:] if ln.strip()]


def write_asc(path, values: np.ndarray, *, cellsize=10.0, xll=100.0, yll=200.0, nodata=-9999):
    """A minimal ESRI ASCII grid writer for round trips (rows north to south)."""
    h, w = values.shape
    head = f"ncols {w}\nnrows {h}\nxllcorner {xll}\nyllcorner {yll}\ncellsize {cellsize}\n"
    body = "\n".join(" ".join(repr(float(v)) for v in row) for row in values)
    path.write_text(head + f"NODATA_value {nodata}\n" + body + "\n")


# --- ESRI ASCII grids -------------------------------------------------------------------------


def test_asc_hugo_site_values_and_nodata(shared_data):
    path = shared_data / "dem" / "hugo_site.asc"
    header, rows = asc_rows(path)
    dem = read_dem(path)
    assert isinstance(dem, DEM)
    assert dem.shape == (55, 76) == (int(header["nrows"]), int(header["ncols"]))
    assert dem.heights.dtype == np.float32
    text = np.array(rows, dtype=float)
    np.testing.assert_array_equal(np.isnan(dem.heights), text == -9999)
    np.testing.assert_array_equal(dem.mask, text != -9999)
    assert int(dem.mask.sum()) == 4180 - 2028  # MANIFEST: 2028 NODATA cells
    # first valid cell in file order: row 2, column 36 holds 1708 (north row first)
    assert float(rows[2][36]) == 1708 and dem.heights[2, 36] == 1708
    assert dem.transform == (0.0, 10.0, 0.0, 550.0, 0.0, -10.0)
    assert dem.pixel_size == (10.0, 10.0)
    assert not dem.geographic and dem.crs is None
    assert dem.source == str(path)
    assert dem.bounds == (0.0, 760.0, 0.0, 550.0)


def test_asc_pre_runout_last_column_nodata(shared_data):
    path = shared_data / "dem" / "pre_runout_DEM.asc"
    _, rows = asc_rows(path)
    dem = read_dem(path)
    assert dem.shape == (122, 80)
    assert np.isnan(dem.heights[:, -1]).all() and dem.mask[:, :-1].all()
    assert dem.heights[0, 0] == np.float32(rows[0][0]) == np.float32(479.9628)
    assert dem.heights[0, 78] == np.float32(rows[0][78])
    assert dem.heights[-1, 0] == np.float32(rows[-1][0]) == np.float32(200.9864)
    # north up: the first text row is higher ground than the last one here
    assert np.nanmean(dem.heights[0]) > np.nanmean(dem.heights[-1])
    x0, dx, _, y0, _, dy = dem.transform
    assert x0 == pytest.approx(361015.59563119) and dx == 10.0 and dy == -10.0
    assert y0 == pytest.approx(70223.434086869 + 122 * 10)


def test_asc_degrees_get_metres_with_warning(shared_data):
    path = shared_data / "dem" / SRTM_ASC
    header, rows = asc_rows(path)
    with pytest.warns(UserWarning, match="taken as degrees"):
        dem = read_dem(path)
    assert dem.geographic and dem.shape == (144, 240)
    assert dem.heights[0, 0] == float(rows[0][0]) == 2569
    assert dem.heights[-1, -1] == float(rows[-1][-1])
    cell = float(header["cellsize"])
    lat = float(header["yllcorner"]) + 144 * cell / 2
    assert lat == pytest.approx(40.1504, abs=1e-4)
    m_lon, m_lat = metres_per_degree(lat)
    assert dem.pixel_size == pytest.approx((cell * m_lon, cell * m_lat), rel=1e-12)
    # spherical cross-check (111320 m per degree x cos(latitude)): within 0.5 %
    assert dem.pixel_size[0] == pytest.approx(cell * 111320 * math.cos(math.radians(lat)), rel=5e-3)
    assert dem.pixel_size == pytest.approx((71.005, 92.531), abs=1e-3)
    # explicit geographic=True: no warning; geographic=False: taken as metres, on request only
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_dem(path, geographic=True).pixel_size == dem.pixel_size
        assert read_dem(path, geographic=False).pixel_size == pytest.approx((cell, cell))


def test_asc_prj_geographic_and_projected(tmp_path):
    values = np.arange(12, dtype=float).reshape(3, 4)
    write_asc(tmp_path / "g.asc", values, cellsize=0.01, xll=5.0, yll=45.0)
    (tmp_path / "g.prj").write_text('GEOGCS["WGS 84",DATUM["WGS_1984"]]\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a .prj answers the question: no guessing warning
        geo = read_dem(tmp_path / "g.asc")
    assert geo.geographic and geo.crs.startswith('GEOGCS["WGS 84"')
    m_lon, m_lat = metres_per_degree(45.015)
    assert geo.pixel_size == pytest.approx((0.01 * m_lon, 0.01 * m_lat))
    write_asc(tmp_path / "p.asc", values, cellsize=0.01, xll=5.0, yll=45.0)
    (tmp_path / "p.prj").write_text('PROJCS["UTM 32N",GEOGCS["WGS 84"],UNIT["metre",1]]')
    proj = read_dem(tmp_path / "p.asc")
    assert not proj.geographic and proj.pixel_size == (0.01, 0.01)


def test_asc_centre_keys_dx_dy_and_case(tmp_path):
    path = tmp_path / "c.asc"
    path.write_text(
        "NCOLS 3\nNROWS 2\nXLLCENTER 10\nYLLCENTER 20\nDX 2\nDY 4\nnodata_VALUE -1\n1 2 3\n4 -1 6\n"
    )
    dem = read_dem(path)
    assert dem.transform == (9.0, 2.0, 0.0, 26.0, 0.0, -4.0)
    assert dem.pixel_size == (2.0, 4.0)
    np.testing.assert_array_equal(dem.mask, [[True, True, True], [True, False, True]])
    assert dem.heights[1, 2] == 6


def test_asc_wrong_row_count_names_file_and_counts(tmp_path):
    path = tmp_path / "short.asc"
    write_asc(path, np.ones((3, 4)))
    path.write_text(path.read_text().replace("nrows 3", "nrows 5"))
    with pytest.raises(InputError, match=r"short\.asc.*nrows=5 x ncols=4 = 20.*holds 12"):
        read_dem(path)


def test_asc_bad_header(tmp_path):
    path = tmp_path / "bad.asc"
    path.write_text("ncols 2\n1 2\n3 4\n")
    with pytest.raises(InputError, match=r"bad\.asc.*not an ESRI ASCII grid"):
        read_dem(path)


@settings(max_examples=25, deadline=None)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(1, 7), st.integers(1, 7)),
        elements=st.integers(-500, 9000),
    ),
    st.data(),
)
def test_asc_and_npy_round_trip_odd_arrays(tmp_path_factory, values, data):
    tmp = tmp_path_factory.mktemp("rt")
    holes = data.draw(arrays(np.bool_, values.shape))
    values = np.where(holes, -9999.0, values)
    write_asc(tmp / "a.asc", values, cellsize=2.5)
    dem = read_dem(tmp / "a.asc")
    np.testing.assert_array_equal(dem.mask, ~holes)
    np.testing.assert_array_equal(dem.heights[~holes], values[~holes])
    assert dem.pixel_size == (2.5, 2.5) and dem.shape == values.shape
    np.save(tmp / "a.npy", values)
    npy = read_dem(tmp / "a.npy", nodata=-9999, spacing=(3.0, 4.0))
    np.testing.assert_array_equal(npy.heights, dem.heights)
    assert npy.pixel_size == (3.0, 4.0)
    assert npy.transform == (0.0, 3.0, 0.0, 4.0 * values.shape[0], 0.0, -4.0)


# --- SRTM .hgt ----------------------------------------------------------------------------------


def test_hgt_tile_georeference_and_values(shared_data):
    path = shared_data / "dem" / "N10W110.hgt"
    raw = path.read_bytes()
    dem = read_dem(path)
    assert dem.shape == (1201, 1201) and dem.geographic and dem.crs == "EPSG:4326"
    for r, c in [(0, 0), (600, 600), (1200, 1200), (123, 987)]:
        (expected,) = struct.unpack(">h", raw[2 * (r * 1201 + c) : 2 * (r * 1201 + c) + 2])
        assert dem.heights[r, c] == expected
    d = 1 / 1200
    assert dem.transform == pytest.approx((-110 - d / 2, d, 0, 11 + d / 2, 0, -d), abs=1e-12)
    assert dem.bounds == pytest.approx((-110 - d / 2, -109 + d / 2, 10 - d / 2, 11 + d / 2))
    m_lon, m_lat = metres_per_degree(10.5)
    assert dem.pixel_size == pytest.approx((d * m_lon, d * m_lat), rel=1e-9)
    assert dem.heights.max() <= 9 + 1e-6  # MANIFEST: Clipperton atoll up to 9 m


def test_hgt_round_trip_voids_and_southern_name(tmp_path):
    values = np.zeros((1201, 1201), dtype=">i2")
    values[0, 0], values[5, 7], values[1200, 3] = -32768, 1234, -20
    path = tmp_path / "s05e012.hgt"
    values.tofile(path)
    dem = read_dem(path)
    assert np.isnan(dem.heights[0, 0]) and int(dem.mask.sum()) == 1201**2 - 1
    assert dem.heights[5, 7] == 1234 and dem.heights[1200, 3] == -20
    x0, _, _, y0, _, _ = dem.transform
    assert x0 == pytest.approx(12 - 0.5 / 1200) and y0 == pytest.approx(-4 + 0.5 / 1200)
    assert path.read_bytes() == values.tobytes()  # input untouched


def test_hgt_truncated_and_unnamed(tmp_path):
    path = tmp_path / "N10W110.hgt"
    path.write_bytes(b"\0" * 1000)
    with pytest.raises(InputError, match=r"N10W110\.hgt: 1000 bytes is not an SRTM"):
        read_dem(path)
    np.zeros((1201, 1201), ">i2").tofile(tmp_path / "tile.hgt")
    with pytest.raises(InputError, match=r"tile\.hgt.*by its name"):
        read_dem(tmp_path / "tile.hgt")


# --- numpy: .npz, .npy, arrays ----------------------------------------------------------------


def test_npz_jacksboro_north_up_in_degrees():
    from matplotlib import cbook

    data = cbook.get_sample_data("jacksboro_fault_dem.npz")
    path = data.fid.name if hasattr(data, "fid") else data.name
    with np.load(path) as f:
        elev = f["elevation"]
    with pytest.warns(UserWarning, match="taken as degrees"):
        dem = read_dem(path)
    assert dem.shape == (344, 403) and dem.geographic
    np.testing.assert_array_equal(dem.heights, elev.astype(np.float32))
    west, east, south, north = dem.bounds
    assert (west, east) == pytest.approx((-84.41375, -84.07791666666667))
    assert (south, north) == pytest.approx((36.44625, 36.73291666666667))  # ymin > ymax in file
    m_lon, m_lat = metres_per_degree((south + north) / 2)
    assert dem.pixel_size == pytest.approx((m_lon / 1200, m_lat / 1200))


def test_array_spacing_transform_and_errors():
    a = np.arange(6, dtype=np.int16).reshape(2, 3)
    dem = read_dem(a)
    assert dem.pixel_size == (1.0, 1.0) and dem.source is None and not dem.geographic
    assert dem.transform == (0.0, 1.0, 0.0, 2.0, 0.0, -1.0)
    assert read_dem(a, spacing=5).pixel_size == (5.0, 5.0)
    geo = read_dem(a, transform=(7.0, 0.5, 0.0, 50.0, 0.0, -0.5), crs="EPSG:4326")
    assert geo.geographic and geo.crs == "EPSG:4326"
    m_lon, m_lat = metres_per_degree(49.5)
    assert geo.pixel_size == pytest.approx((0.5 * m_lon, 0.5 * m_lat))
    assert np.isnan(read_dem(a, nodata=4).heights[1, 1])
    f = np.array([[1.0, np.inf], [np.nan, 2.0]])
    np.testing.assert_array_equal(read_dem(f).mask, [[True, False], [False, True]])
    assert np.isfinite(f).sum() == 2 and f[0, 1] == np.inf  # input untouched
    with pytest.raises(InputError, match="2-D"):
        read_dem(np.zeros((2, 2, 2)))
    with pytest.raises(InputError, match="numeric"):
        read_dem(np.array([["a", "b"]]))
    with pytest.raises(InputError, match="spacing"):
        read_dem(a, spacing=(1, -1))
    with pytest.raises(InputError, match="not both"):
        read_dem(a, spacing=1, transform=(0, 1, 0, 0, 0, -1))
    with pytest.raises(InputError, match="needs a transform"):
        read_dem(a, geographic=True)


def test_file_errors(tmp_path, shared_data):
    with pytest.raises(InputError, match=r"nothere\.asc: no such DEM file"):
        read_dem(tmp_path / "nothere.asc")
    (tmp_path / "x.xyz").write_text("1 2 3")
    with pytest.raises(InputError, match=r"x\.xyz: unknown DEM extension '\.xyz'"):
        read_dem(tmp_path / "x.xyz")
    np.save(tmp_path / "v.npy", np.zeros(5))
    with pytest.raises(InputError, match=r"v\.npy: expected a non-empty 2-D array"):
        read_dem(tmp_path / "v.npy")
    with pytest.raises(InputError, match=r"hugo_site\.asc: spacing= is for sources without"):
        read_dem(shared_data / "dem" / "hugo_site.asc", spacing=2)


# --- GeoTIFF ------------------------------------------------------------------------------------


def test_geotiff_round_trip(tmp_path):
    rasterio = pytest.importorskip("rasterio")

    def from_origin(west, north, xsize, ysize):
        return rasterio.Affine(xsize, 0.0, west, 0.0, -ysize, north)

    values = np.array([[1.5, 2.5, -1.0], [4.0, 5.0, 6.0]], dtype=np.float32)
    path = tmp_path / "utm.tif"
    profile = dict(driver="GTiff", width=3, height=2, count=1, dtype="float32", nodata=-1.0)
    with rasterio.open(
        path, "w", crs="EPSG:32613", transform=from_origin(450000, 4440000, 30, 20), **profile
    ) as dst:
        dst.write(values, 1)
    dem = read_dem(path)
    assert dem.crs == "EPSG:32613" and not dem.geographic
    assert dem.transform == (450000.0, 30.0, 0.0, 4440000.0, 0.0, -20.0)
    assert dem.pixel_size == (30.0, 20.0)
    np.testing.assert_array_equal(dem.mask, [[True, True, False], [True, True, True]])
    assert dem.heights[0, 1] == 2.5 and dem.heights[1, 0] == 4.0

    geo_path = tmp_path / "geo.tif"
    with rasterio.open(
        geo_path, "w", crs="EPSG:4326", transform=from_origin(-105.5, 40.2, 0.001, 0.001), **profile
    ) as dst:
        dst.write(values, 1)
    geo = read_dem(geo_path)
    m_lon, m_lat = metres_per_degree(40.199)
    assert geo.geographic and geo.pixel_size == pytest.approx((0.001 * m_lon, 0.001 * m_lat))


@pytest.mark.parametrize(
    ("dtype", "nodata", "layout"),
    [
        ("float32", -9999.0, {"tiled": True, "blockxsize": 16, "blockysize": 16,
                              "compress": "deflate"}),
        ("float32", None, {}),  # strips
        ("int16", None, {"tiled": True, "blockxsize": 32, "blockysize": 32}),
        ("uint16", 0, {"compress": "lzw"}),
        ("float64", float("nan"), {}),
    ],
)  # fmt: skip
@pytest.mark.parametrize("threads", ["1", "3"])
def test_large_geotiff_read_by_threads_equals_a_plain_read(
    tmp_path, monkeypatch, dtype, nodata, layout, threads
):
    """A raster past the threshold is read by row windows on threads: the heights of a plain
    whole-band read, as float32 with NaN at nodata, whatever the type, block layout and
    compression (windows cut at blocks, a last short one)."""
    rasterio = pytest.importorskip("rasterio")
    from sciviz_gbuf.readers import _dem_files

    monkeypatch.setattr(_dem_files, "PARALLEL_READ_CELLS", 100)
    monkeypatch.setenv("NUMBA_NUM_THREADS", threads)
    rng = np.random.default_rng(3)
    values = (rng.random((77, 45)) * 3000).astype(dtype)
    if nodata is not None:
        values[rng.random(values.shape) < 0.1] = nodata
    path = tmp_path / "big.tif"
    profile = {"driver": "GTiff", "width": 45, "height": 77, "count": 1, "dtype": dtype,
               "nodata": nodata, "crs": "EPSG:32613",
               "transform": rasterio.Affine(10.0, 0, 4e5, 0, -10.0, 4.4e6), **layout}  # fmt: skip
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(values, 1)
    expected = values.astype(np.float32)
    if nodata is not None:
        expected[(values == nodata) | np.isnan(values.astype(np.float64))] = np.nan
    got = read_dem(path)
    assert got.heights.dtype == np.float32
    np.testing.assert_array_equal(got.heights, expected)
    np.testing.assert_array_equal(got.mask, np.isfinite(expected))


@pytest.mark.filterwarnings("ignore:Dataset has no geotransform")
def test_geotiff_rgb_and_ungeoreferenced(tmp_path):
    rasterio = pytest.importorskip("rasterio")
    rgb = tmp_path / "photo.tif"
    with rasterio.open(rgb, "w", driver="GTiff", width=4, height=3, count=3, dtype="uint8") as dst:
        dst.write(np.zeros((3, 3, 4), np.uint8))
    with pytest.raises(InputError, match=r"photo\.tif: 3 uint8 bands look like an RGB"):
        read_dem(rgb)
    plain = tmp_path / "plain.tif"
    with rasterio.open(
        plain, "w", driver="GTiff", width=4, height=3, count=1, dtype="int16"
    ) as dst:
        dst.write(np.arange(12, dtype=np.int16).reshape(3, 4), 1)
    with pytest.warns(UserWarning, match="without georeference"):
        dem = read_dem(plain, spacing=2)
    assert dem.pixel_size == (2.0, 2.0) and dem.crs is None and dem.heights[2, 3] == 11


def test_geotiff_without_rasterio(tmp_path, monkeypatch):
    path = tmp_path / "dem.tif"
    path.write_bytes(b"II*\0")
    monkeypatch.setitem(sys.modules, "rasterio", None)
    with pytest.raises(InputError, match=r"dem\.tif: reading GeoTIFF needs rasterio.*\[geo\]"):
        read_dem(path)


# --- USGS ASCII DEM (.dem) ------------------------------------------------------------------


def _d24(v: float) -> str:
    """A Fortran D24.15 field, as USGS writes them (D exponents, which VTK turns into E)."""
    return f"{v:24.15E}".replace("E", "D")


def write_usgs_dem(
    path,
    elev: np.ndarray,
    starts,
    counts,
    *,
    x0: float = 500000.0,
    y0: float = 4000000.0,
    res=(30.0, 30.0, 0.5),
    plane_unit: int = 2,
    elevation_unit: int = 2,
    ground_system: int = 1,
    zone: int = 13,
    datum_code: int | None = None,
    row_ids_one: bool = False,
    datum_elevations=None,
) -> None:
    """A USGS ASCII DEM written by hand from the format's fixed columns (no package code).

    ``elev`` holds integers in units of ``res[2]``, row 0 **south**, column 0 west (the file's own
    profile order); profile ``c`` holds rows ``starts[c]`` .. ``starts[c] + counts[c] - 1``. The
    type A record is 1024 bytes: label (144), DEM level, pattern, ground system, zone (4 x I6),
    15 projection parameters (D24.15), ground unit, elevation unit, polygon sides (3 x I6), the
    SW, NW, NE, SE corners (8 x D24.15), min/max elevation (2 x D24.15), rotation (D24.15),
    accuracy (I6), x/y/z resolution (3 x E12.6), rows and columns of profiles (2 x I6).
    Each type B record: row, column, number of elevations, 1 (4 x I6), x and y of the first
    sample, datum elevation, min and max (5 x D24.15), then the elevations (I6), padded to 1024.
    ``datum_code`` goes to bytes 891-892 (the 1992 format's horizontal datum); ``row_ids_one``
    writes row id 1 in every profile, as the 7.5-minute quads do (the start is in y alone);
    ``datum_elevations[c]`` is profile c's local datum elevation (the file's elevations are
    then ``elev - datum / dz``).
    """
    nrows, ncols = elev.shape
    dx, dy, dz = res
    xe, yn = x0 + (ncols - 1) * dx, y0 + (nrows - 1) * dy
    inside = np.concatenate(
        [elev[s : s + n, c] for c, (s, n) in enumerate(zip(starts, counts, strict=True))]
    )
    a = f"{'SYNTHETIC TEST DEM':<144}{1:6d}{1:6d}{ground_system:6d}{zone:6d}" + _d24(0.0) * 15
    a += f"{plane_unit:6d}{elevation_unit:6d}{4:6d}"
    a += "".join(_d24(v) for v in (x0, y0, x0, yn, xe, yn, xe, y0))
    a += _d24(inside.min() * dz) + _d24(inside.max() * dz) + _d24(0.0) + f"{0:6d}"
    a += "".join(f"{v:12.6E}" for v in (dx, dy, dz)) + f"{1:6d}{ncols:6d}"
    assert len(a) == 864
    if datum_code is not None:
        a = f"{a:<890}{datum_code:2d}"
    records = [f"{a:<1024}"]
    for c, (s, n) in enumerate(zip(starts, counts, strict=True)):
        col = elev[s : s + n, c]
        datum = 0.0 if datum_elevations is None else float(datum_elevations[c])
        stored = np.where(col == -32767, col, col - round(datum / dz))
        b = f"{1 if row_ids_one else s + 1:6d}{c + 1:6d}{n:6d}{1:6d}"
        b += "".join(
            _d24(v) for v in (x0 + c * dx, y0 + s * dy, datum, col.min() * dz, col.max() * dz)
        )
        b += "".join(f"{int(v):6d}" for v in stored)
        records.append(b + " " * (-len(b) % 1024))
    path.write_text("".join(records))


def ramp_dem(nrows: int, ncols: int):
    """Elevations rising 3 units per column east and 7 per row north; ragged profile ends."""
    r, c = np.mgrid[0:nrows, 0:ncols]
    elev = 200 + 3 * c + 7 * r  # row 0 south
    starts = [k % 3 for k in range(ncols)]
    counts = [nrows - s - (k % 2) for k, s in enumerate(starts)]
    inside = np.zeros((nrows, ncols), bool)
    for k, (s, n) in enumerate(zip(starts, counts, strict=True)):
        inside[s : s + n, k] = True
    return elev, starts, counts, inside


@pytest.mark.parametrize("ncols", [120, 7])  # >= 100: vtkDEMReader; fewer: the scanned values
def test_usgs_dem_ramps_orientation_fill_and_georeference(tmp_path, ncols):
    elev, starts, counts, inside = ramp_dem(6, ncols)
    path = tmp_path / "ramp.dem"
    write_usgs_dem(path, elev, starts, counts)
    dem = read_dem(path)
    assert dem.shape == (6, ncols) and dem.heights.dtype == np.float32
    # north up: file row r (south first) is DEM row 5 - r; heights in metres (0.5 m units)
    np.testing.assert_array_equal(dem.mask, inside[::-1])
    np.testing.assert_array_equal(dem.heights[dem.mask], (0.5 * elev[::-1])[inside[::-1]])
    assert np.isnan(dem.heights[~dem.mask]).all() and (~dem.mask).sum() > 0
    # the lowest sample (header minimum, 100 m, where VTK also fills) stays a valid height
    assert dem.heights[5, 0] == 100.0 and dem.mask[5, 0]
    assert np.nanmean(np.diff(dem.heights, axis=1)) == pytest.approx(1.5)  # east: +3 x 0.5 m
    assert np.nanmean(np.diff(dem.heights, axis=0)) == pytest.approx(-3.5)  # down = south
    # corner transform: south-west sample at (500000, 4000000), 30 m cells
    assert dem.transform == (499985.0, 30.0, 0.0, 4000000 + 5.5 * 30, 0.0, -30.0)
    # UTM zone 13 (the writer's header), no datum code: NAD27, as GDAL reads such files
    assert dem.pixel_size == (30.0, 30.0) and not dem.geographic and dem.crs == "EPSG:26713"
    assert dem.source == str(path)


def test_usgs_dem_feet_and_arc_seconds(tmp_path):
    elev, starts, counts, inside = ramp_dem(4, 5)
    feet = tmp_path / "feet.dem"
    write_usgs_dem(feet, elev, starts, counts, res=(10.0, 10.0, 1.0), elevation_unit=1)
    dem = read_dem(feet)
    np.testing.assert_allclose(dem.heights[dem.mask], (0.3048 * elev[::-1])[inside[::-1]], 1e-6)
    wide = tmp_path / "feet_wide.dem"  # (vtkDEMReader multiplied by 0.305)
    elev_w, starts_w, counts_w, inside_w = ramp_dem(4, 100)
    write_usgs_dem(wide, elev_w, starts_w, counts_w, res=(10.0, 10.0, 1.0), elevation_unit=1)
    wide_dem = read_dem(wide)
    np.testing.assert_allclose(
        wide_dem.heights[wide_dem.mask], (0.3048 * elev_w[::-1])[inside_w[::-1]], rtol=1e-6
    )
    arc = tmp_path / "arc.dem"  # 3" cells, south-west sample at 105.5 W, 40.1 N
    write_usgs_dem(
        arc, elev, starts, counts, x0=-105.5 * 3600, y0=40.1 * 3600, res=(3.0, 3.0, 1.0),
        plane_unit=3,
    )  # fmt: skip
    geo = read_dem(arc)
    d = 3 / 3600
    assert geo.geographic
    assert geo.transform == pytest.approx((-105.5 - d / 2, d, 0, 40.1 + 3.5 * d, 0, -d))
    m_lon, m_lat = metres_per_degree(40.1 + 1.5 * d)
    assert geo.pixel_size == pytest.approx((d * m_lon, d * m_lat))
    plane_feet = tmp_path / "plane_feet.dem"
    write_usgs_dem(plane_feet, elev, starts, counts, res=(10.0, 10.0, 1.0), plane_unit=1)
    state = read_dem(plane_feet)
    assert state.transform[1] == 10.0 and state.pixel_size == pytest.approx((3.048, 3.048))


@pytest.mark.parametrize("ncols", [120, 7])
def test_usgs_dem_truncated_and_garbage(tmp_path, ncols):
    elev, starts, counts, _ = ramp_dem(6, ncols)
    good = tmp_path / "good.dem"
    write_usgs_dem(good, elev, starts, counts)
    text = good.read_text()
    cut = tmp_path / "cut.dem"
    cut.write_text(text[: 1024 * (ncols // 2 + 1) + 150])  # inside profile ncols // 2 + 1
    with pytest.raises(InputError, match=rf"cut\.dem: USGS DEM profile {ncols // 2 + 1} \(col.*"):
        read_dem(cut)
    cut.write_text(text[: 1024 * (ncols // 2 + 1)])  # whole profiles missing: VTK says nothing
    with pytest.raises(InputError, match=rf"cut\.dem: .*{ncols} profiles.*ends after {ncols // 2}"):
        read_dem(cut)
    short = tmp_path / "short.dem"
    short.write_text(text[:500])
    with pytest.raises(InputError, match=r"short\.dem: 500 bytes is too short"):
        read_dem(short)
    garbage = tmp_path / "garbage.dem"
    garbage.write_text("hello world " * 200)
    with pytest.raises(InputError, match=r"garbage\.dem: not a USGS ASCII DEM"):
        read_dem(garbage)
    # two profiles at the same easting: no grid
    twin = tmp_path / "twin.dem"
    write_usgs_dem(twin, elev, starts, counts)
    text = twin.read_text()
    second = text[2048:3072].replace(_d24(500000.0 + 30.0), _d24(500000.0), 1)
    twin.write_text(text[:2048] + second + text[3072:])
    with pytest.raises(InputError, match=r"twin\.dem: USGS DEM profiles do not form a grid"):
        read_dem(twin)


def _quad(nrows: int = 40, ncols: int = 120):
    """A 7.5-minute-quad-like file's content: a known plane z = 1500 + 0.02 x' - 0.03 y' (m,
    x' / y' metres from the SW post), profiles starting and ending at northings that vary
    across the quad (its edges are not grid lines), a void post, and local datum elevations."""
    r, c = np.mgrid[0:nrows, 0:ncols]
    plane = 1500.0 + 0.02 * 30 * c - 0.03 * 30 * r  # row 0 south
    elev = np.round(plane / 0.5).astype(np.int64)  # 0.5 m units
    starts = [int(5 + 4 * np.sin(k / 17.0)) for k in range(ncols)]
    counts = [nrows - s - int(3 + 2 * np.cos(k / 11.0)) for k, s in enumerate(starts)]
    elev[starts[7] + 2, 7] = -32767  # a void post
    datums = [100.0 if k % 4 == 0 else 0.0 for k in range(ncols)]
    return elev, starts, counts, datums


def test_usgs_quad_profiles_placed_by_northing_with_datum_and_crs(tmp_path):
    """The profile-start defect: profiles of a real quad all say row 1; where they start is
    their first post's northing. Every post must land at its own (x, y) with its height."""
    elev, starts, counts, datums = _quad()
    path = tmp_path / "quad.dem"
    write_usgs_dem(
        path, elev, starts, counts, row_ids_one=True, datum_elevations=datums, datum_code=4,
        zone=13,
    )  # fmt: skip
    dem = read_dem(path)
    assert dem.crs == "EPSG:26913"  # NAD83 / UTM zone 13N, from the header
    s0 = min(starts)
    nrows = max(s + n for s, n in zip(starts, counts, strict=True)) - s0
    assert dem.shape == (nrows, 120)
    x0, dx, _, ytop, _, dy = dem.transform
    assert (x0, dx, dy) == (500000.0 - 15.0, 30.0, -30.0)
    assert ytop == 4000000.0 + s0 * 30.0 + (nrows - 0.5) * 30.0
    for c, (s, n) in enumerate(zip(starts, counts, strict=True)):
        rows = nrows - 1 - (np.arange(s, s + n) - s0)  # our rows, north first
        col = dem.heights[rows, c]
        want = 0.5 * elev[s : s + n, c]
        void = elev[s : s + n, c] == -32767
        np.testing.assert_array_equal(col[~void], want[~void].astype(np.float32))
        assert np.isnan(col[void]).all()
        outside = np.ones(nrows, bool)
        outside[rows] = False
        assert np.isnan(dem.heights[outside, c]).all()  # no fill value outside the profile
    assert int(np.isnan(dem.heights).sum()) == nrows * 120 - sum(counts) + 1


def test_usgs_quad_agrees_with_gdal(tmp_path):
    """GDAL's USGSDEM driver (through rasterio) as an independent reader of the same file:
    every post at the same map position, the same height, the same CRS."""
    rasterio = pytest.importorskip("rasterio")
    elev, starts, counts, datums = _quad()
    path = tmp_path / "quad.dem"
    write_usgs_dem(
        path, elev, starts, counts, row_ids_one=True, datum_elevations=datums, datum_code=4,
    )  # fmt: skip
    dem = read_dem(path)
    with rasterio.open(path) as src:
        ref = src.read(1, masked=True).astype(np.float64).filled(np.nan)
        gt = src.transform
        assert src.crs.to_epsg() == 26913
    rows, cols = np.nonzero(dem.mask)
    x0, dx, _, ytop, _, dy = dem.transform
    xs, ys = x0 + (cols + 0.5) * dx, ytop + (rows + 0.5) * dy
    gc = np.floor((xs - gt.c) / gt.a).astype(int)
    gr = np.floor((ys - gt.f) / gt.e).astype(int)
    np.testing.assert_allclose(ref[gr, gc], dem.heights[rows, cols], rtol=0, atol=1e-3)
    assert np.isnan(ref).sum() - np.isnan(dem.heights).sum() == ref.size - dem.heights.size


# --- xarray DataArray -----------------------------------------------------------------------


def test_dataarray_projected_round_trip_either_y_order():
    xr = pytest.importorskip("xarray")
    values = np.array([[1.0, 2.0, 3.0, 4.0], [5.0, -9999.0, 7.0, 8.0], [9.0, 10.0, 11.0, 12.0]])
    x = 100 + 10 * np.arange(4) + 5.0  # pixel centres
    y = 500 - 20 * np.arange(3) - 10.0  # north first
    da = xr.DataArray(values, dims=("y", "x"), coords={"x": x, "y": y}, name="z")
    da.attrs.update(crs="EPSG:32613", _FillValue=-9999.0)
    for variant in (da, da.isel(y=slice(None, None, -1)), da.transpose("x", "y")):
        dem = read_dem(variant)
        assert dem.transform == (100.0, 10.0, 0.0, 500.0, 0.0, -20.0)
        assert dem.pixel_size == (10.0, 20.0) and not dem.geographic and dem.crs == "EPSG:32613"
        np.testing.assert_array_equal(dem.mask, values != -9999)
        np.testing.assert_array_equal(dem.heights[dem.mask], values[values != -9999])
        assert dem.heights[2, 0] == 9.0  # south-west stays south-west
    east_to_west = da.isel(x=slice(None, None, -1))
    assert read_dem(east_to_west).heights[0, 0] == 1.0
    wkt = 'PROJCS["UTM 13N",GEOGCS["WGS 84"]]'
    bare = xr.DataArray(values, dims=("y", "x"), coords={"x": x, "y": y})
    bare = bare.assign_coords(spatial_ref=xr.DataArray(0, attrs={"crs_wkt": wkt}))
    assert read_dem(bare, nodata=-9999).crs == wkt
    with pytest.raises(InputError, match="transform=/crs="):
        read_dem(da, crs="EPSG:4326")


def test_dataarray_lonlat_is_geographic():
    xr = pytest.importorskip("xarray")
    lat = 45.0 + 0.01 * np.arange(5)  # south first: flipped to north up
    lon = 7.0 + 0.02 * np.arange(3)
    values = np.arange(15, dtype=np.float32).reshape(5, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # lon/lat dims answer the question: no guessing warning
        dem = read_dem(xr.DataArray(values, dims=("lat", "lon"), coords={"lat": lat, "lon": lon}))
    assert dem.geographic and dem.heights[0, 0] == 12 and dem.heights[4, 2] == 2
    assert dem.transform == pytest.approx((6.99, 0.02, 0, 45.045, 0, -0.01))
    m_lon, m_lat = metres_per_degree(45.02)
    assert dem.pixel_size == pytest.approx((0.02 * m_lon, 0.01 * m_lat))
    long = xr.DataArray(
        values, dims=("latitude", "longitude"), coords={"latitude": lat, "longitude": lon}
    )
    assert read_dem(long).pixel_size == dem.pixel_size


def test_dataarray_errors():
    xr = pytest.importorskip("xarray")
    values = np.zeros((3, 4))
    uneven = xr.DataArray(values, dims=("y", "x"), coords={"x": [0.0, 1, 2, 4], "y": [2.0, 1, 0]})
    with pytest.raises(InputError, match=r"coordinate 'x' is not evenly spaced"):
        read_dem(uneven)
    with pytest.raises(InputError, match="no coordinate values"):
        read_dem(xr.DataArray(values, dims=("y", "x")))
    with pytest.raises(InputError, match="expected one of x/lon"):
        read_dem(xr.DataArray(values, dims=("row", "col")))
    with pytest.raises(InputError, match="2-D DataArray"):
        read_dem(xr.DataArray(np.zeros((2, 3, 4)), dims=("t", "y", "x")))


# --- DEM.to_pyvista -------------------------------------------------------------------------


def test_to_pyvista_projected_points_at_pixel_centres():
    values = np.array([[1.0, 2.0, np.nan], [4.0, 5.0, 6.0]])
    dem = read_dem(values, transform=(1000.0, 10.0, 0.0, 2000.0, 0.0, -20.0), crs="EPSG:32613")
    grid = dem.to_pyvista(z_factor=2.0)
    assert grid.dimensions == (3, 2, 1)
    pts = grid.points.reshape(2, 3, 3)[::-1]  # i east fastest, j north: flip to north-up rows
    cc, rr = np.meshgrid(np.arange(3), np.arange(2))
    np.testing.assert_allclose(pts[..., 0], 1000 + (cc + 0.5) * 10)
    np.testing.assert_allclose(pts[..., 1], 2000 - (rr + 0.5) * 20)
    np.testing.assert_allclose(pts[..., 2], [[2, 4, 2], [8, 10, 12]])  # nodata z: min valid x 2
    elevation = grid.point_data["elevation"].reshape(2, 3)[::-1]
    assert elevation.dtype == np.float32
    np.testing.assert_array_equal(elevation, values.astype(np.float32))
    assert np.isfinite(grid.points).all()
    ghost = grid.point_data["vtkGhostType"].reshape(2, 3)[::-1]
    np.testing.assert_array_equal(ghost != 0, np.isnan(values))
    # only the western quad has 4 valid corners; vtkGeometryFilter honours the blanking
    assert grid.extract_surface(algorithm=None).n_cells == 1


def test_to_pyvista_hugo_site_hides_nodata_cells(shared_data):
    dem = read_dem(shared_data / "dem" / "hugo_site.asc")
    grid = dem.to_pyvista()
    assert np.isfinite(grid.points).all() and grid.n_points == 55 * 76
    m = dem.mask
    full_quads = int((m[:-1, :-1] & m[1:, :-1] & m[:-1, 1:] & m[1:, 1:]).sum())
    assert 0 < full_quads < grid.n_cells
    surface = grid.extract_surface(algorithm=None)  # vtkGeometryFilter
    assert surface.n_cells == full_quads
    # VTK quirk: vtkDataSetSurfaceFilter (PyVista 0.49's default algorithm) ignores blanking
    assert grid.extract_surface(algorithm="dataset_surface").n_cells == grid.n_cells
    valid_z = surface.points[:, 2]
    assert valid_z.min() >= np.nanmin(dem.heights) and valid_z.max() == np.nanmax(dem.heights)
    # quads face up (+z) so lighting is right: i runs east, j north
    normals = surface.compute_normals(cell_normals=True, point_normals=False)
    assert (normals.cell_data["Normals"][:, 2] > 0).all()


def test_to_pyvista_geographic_metres_and_step(shared_data):
    dem = read_dem(shared_data / "dem" / SRTM_ASC, geographic=True)
    h, w = dem.shape
    grid = dem.to_pyvista()
    xmin, xmax, ymin, ymax, zmin, zmax = grid.bounds
    # pixel centres: (w - 1) pixels between the outer ones, centred on the grid centre
    assert xmax - xmin == pytest.approx((w - 1) * dem.pixel_size[0], rel=1e-9)
    assert ymax - ymin == pytest.approx((h - 1) * dem.pixel_size[1], rel=1e-9)
    assert (xmin + xmax, ymin + ymax) == pytest.approx((0, 0), abs=1e-6)
    assert (zmin, zmax) == (np.nanmin(dem.heights), np.nanmax(dem.heights))
    coarse = dem.to_pyvista(step=7)
    assert coarse.dimensions == (math.ceil(w / 7), math.ceil(h / 7), 1)
    elevation = coarse.point_data["elevation"].reshape(math.ceil(h / 7), math.ceil(w / 7))[::-1]
    np.testing.assert_array_equal(elevation, dem.heights[::7, ::7])
    xs = coarse.points.reshape(math.ceil(h / 7), math.ceil(w / 7), 3)[0, :, 0]
    np.testing.assert_allclose(np.diff(xs), 7 * dem.pixel_size[0], rtol=1e-9)
    for bad in (0, 1.5, True):
        with pytest.raises(InputError, match="step must be an integer"):
            dem.to_pyvista(step=bad)


def test_cli_geotiff_of_a_usgs_quad_carries_its_crs(tmp_path):
    rasterio = pytest.importorskip("rasterio")
    from tests.helpers.cli import run_cli

    elev, starts, counts, _ = _quad()
    path = tmp_path / "quad.dem"
    write_usgs_dem(path, elev, starts, counts, row_ids_one=True, datum_code=3, zone=12)
    png, tif = tmp_path / "quad.png", tmp_path / "quad.tif"
    proc = run_cli(["topo", path, "-o", png, "--geotiff", tif])
    assert proc.returncode == 0, proc.stderr
    with rasterio.open(tif) as src:
        assert src.crs.to_epsg() == 32612  # WGS 84 / UTM zone 12N
