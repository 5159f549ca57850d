"""PMTiles archives against Protomaps' own Python reader (``pmtiles``, an independent
implementation of the specification): tile ids, every tile of a pyramid read back from the
archive equal to the XYZ folder's, leaf directories, shared tiles, the header, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import DEM
from sciviz_gbuf.recipes import write_map_tiles
from sciviz_gbuf.writers import pmtiles as P
from tests.helpers.cli import assert_clean_failure, run_cli

reader = pytest.importorskip("pmtiles.reader")
tile = pytest.importorskip("pmtiles.tile")
rasterio = pytest.importorskip("rasterio")


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 26), st.data())
def test_tile_ids_are_the_specification_s(z, data):
    x = data.draw(st.integers(0, 2**z - 1))
    y = data.draw(st.integers(0, 2**z - 1))
    tid = P.pmtiles_tile_id(z, x, y)
    assert tid == tile.zxy_to_tileid(z, x, y)
    assert tile.tileid_to_zxy(tid) == (z, x, y)


def test_tile_ids_refuse_tiles_outside_their_level():
    for z, x, y in ((27, 0, 0), (-1, 0, 0), (3, 8, 0), (3, 0, -1)):
        with pytest.raises(InputError):
            P.pmtiles_tile_id(z, x, y)


def _read(path: Path):
    f = open(path, "rb")  # the mapping needs the file open while it is read
    src = reader.MmapSource(f)
    return f, src, reader.Reader(src)


@pytest.fixture(scope="module")
def dem_utm(tmp_path_factory):
    """A 300 x 400 UTM DEM of rolling hills with a nodata corner (tiles without data)."""
    from rasterio.transform import from_origin

    yy, xx = np.mgrid[0:300, 0:400].astype(np.float32)
    z = 900 + 120 * np.sin(xx / 37.0) * np.cos(yy / 29.0) + 0.4 * xx
    z[:60, :80] = np.nan
    path = tmp_path_factory.mktemp("pm") / "dem.tif"
    with rasterio.open(path, "w", driver="GTiff", width=400, height=300, count=1,
                       dtype="float32", crs="EPSG:32613", nodata=np.nan,
                       transform=from_origin(440000.0, 4440000.0, 30.0, 30.0)) as f:  # fmt: skip
        f.write(z, 1)
    return path


@pytest.mark.parametrize("fmt", ["png", "webp"])
def test_archive_holds_the_pyramid_s_tiles(dem_utm, tmp_path, fmt):
    from sciviz_gbuf.readers import read_dem

    d = read_dem(dem_utm)
    folder = write_map_tiles(d, tmp_path / "xyz", zoom=(9, 12), format=fmt)
    arch = write_map_tiles(d, tmp_path / "m.pmtiles", zoom=(9, 12), format=fmt)
    assert arch.path == tmp_path / "m.pmtiles" and arch.tiles == folder.tiles
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.pmtiles", "xyz"]  # no scratch
    files = {
        (int(p.parent.parent.name), int(p.parent.name), int(p.stem)): p.read_bytes()
        for p in (tmp_path / "xyz").rglob(f"*.{fmt}")
    }
    assert len(files) == folder.count > 4
    f, src, r = _read(arch.path)
    with f:
        got = {zxy: bytes(b) for zxy, b in reader.all_tiles(src)}
        assert got == files  # every tile, and no other
        for (z, x, y), data in list(files.items())[:20]:
            assert r.get(z, x, y) == data
        assert r.get(12, 0, 0) is None  # outside the data
        h = r.header()
        meta = r.metadata()
    assert h["tile_type"] == (tile.TileType.PNG if fmt == "png" else tile.TileType.WEBP)
    assert h["tile_compression"] == tile.Compression.NONE and h["clustered"]
    assert (h["min_zoom"], h["max_zoom"]) == (9, 12)
    assert h["addressed_tiles_count"] == folder.count
    west, south, east, north = folder.bounds
    got = (h["min_lon_e7"], h["min_lat_e7"], h["max_lon_e7"], h["max_lat_e7"])
    assert got == tuple(round(v * 1e7) for v in (west, south, east, north))
    assert meta["format"] == fmt and meta["minzoom"] == 9 and meta["maxzoom"] == 12


def test_leaf_directories_and_shared_tiles(tmp_path, monkeypatch):
    """A root too small for the entries moves them into leaves (the reader follows them);
    tiles with the same bytes are stored once, runs of them as one entry."""
    monkeypatch.setattr(P, "_ROOT_MAX", 40)
    tiles = []
    rng = np.random.default_rng(4)
    for k, (x, y) in enumerate((x, y) for x in range(16) for y in range(16)):
        p = tmp_path / f"t{k}.png"
        same = (x + y) % 3 == 0
        p.write_bytes(b"same tile" if same else rng.bytes(int(rng.integers(1, 60))))
        tiles.append((4, x, y, p))
    out = P.write_pmtiles(tiles, tmp_path / "a.pmtiles", fmt="png", bounds=(-1, -1, 1, 1),
                          name="t")  # fmt: skip
    f, _, r = _read(out)
    with f:
        h = r.header()
        assert h["leaf_directory_length"] > 0
        for _, x, y, p in tiles:
            assert r.get(4, x, y) == p.read_bytes()
        shared = sum((x + y) % 3 == 0 for x in range(16) for y in range(16))
        assert h["addressed_tiles_count"] == 256
        assert h["tile_contents_count"] == 256 - shared + 1
        assert h["tile_data_length"] < sum(len(p.read_bytes()) for *_, p in tiles)


def test_bad_archives_are_refused(tmp_path, dem_utm):
    from sciviz_gbuf.readers import read_dem

    with pytest.raises(InputError, match=r"\.pmtiles"):
        P.write_pmtiles([], tmp_path / "a.mbtiles", fmt="png", bounds=(0, 0, 1, 1), name="x")
    with pytest.raises(InputError, match="no tiles"):
        P.write_pmtiles([], tmp_path / "a.pmtiles", fmt="png", bounds=(0, 0, 1, 1), name="x")
    with pytest.raises(InputError, match="fmt"):
        P.write_pmtiles([], tmp_path / "a.pmtiles", fmt="jpeg", bounds=(0, 0, 1, 1), name="x")
    (tmp_path / "dir.pmtiles").mkdir()
    with pytest.raises(InputError, match="folder"):
        write_map_tiles(read_dem(dem_utm), tmp_path / "dir.pmtiles", zoom=9)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.pmtiles"]


def test_a_failed_map_leaves_no_archive(dem_utm, tmp_path, monkeypatch):
    from sciviz_gbuf.readers import read_dem
    from sciviz_gbuf.recipes import tiles as T

    def broken(*a, **k):
        raise MemoryError("a level")

    monkeypatch.setattr(T, "topographic_map", broken)
    with pytest.raises(MemoryError):
        T.write_map_tiles(read_dem(dem_utm), tmp_path / "m.pmtiles", zoom=(9, 10))
    assert not list(tmp_path.iterdir())


def test_cli_pmtiles(dem_utm, tmp_path):
    out = tmp_path / "web.pmtiles"
    r = run_cli(["topo", dem_utm, "--tiles", out, "--zoom", "10-11"])
    assert r.returncode == 0, r.stderr
    assert f"wrote {out} (" in r.stdout and "viewer" not in r.stdout
    f, src, rd = _read(out)
    with f:
        assert (rd.header()["min_zoom"], rd.header()["max_zoom"]) == (10, 11)
        assert sum(1 for _ in reader.all_tiles(src)) >= 2
    (tmp_path / "d.pmtiles").mkdir()
    r = run_cli(["topo", dem_utm, "--tiles", tmp_path / "d.pmtiles", "--zoom", "10"])
    assert_clean_failure(r, names="--tiles", outputs=[])


def test_geographic_bounds_in_the_header(tmp_path):
    """A grid in degrees: the header's bounds are its extent (to 1e-7 degrees)."""
    z = np.add.outer(np.arange(60.0), np.arange(80.0)).astype(np.float32)
    d = DEM(heights=z, mask=np.ones(z.shape, bool), crs="EPSG:4326",
            transform=(10.0, 0.01, 0.0, 46.6, 0.0, -0.01), pixel_size=(760.0, 1110.0),
            geographic=True)  # fmt: skip
    arch = write_map_tiles(d, tmp_path / "g.pmtiles", zoom=(8, 9))
    f, _, r = _read(arch.path)
    with f:
        h = r.header()
    for key, v in zip(("min_lon_e7", "min_lat_e7", "max_lon_e7", "max_lat_e7"),
                      (10.0, 46.0, 10.8, 46.6), strict=True):  # fmt: skip
        assert math.isclose(h[key] / 1e7, v, abs_tol=1e-6), key
