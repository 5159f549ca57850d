"""The topographic map written block by block (``write_topographic_png``) against the map made
whole (``topographic_map``): the same pixels for every option that streams, on the shared DEMs
and odd synthetic grids; the PNG's blocks, the thread rule, the fall-backs, and the CLI."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from sciviz_gbuf.cli import main
from sciviz_gbuf.core import bands
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes import terrain
from sciviz_gbuf.recipes.terrain import topographic_map, write_topographic_png
from sciviz_gbuf.writers.png import encode_png_rows, write_png_blocks
from tests.helpers.paths import SHARED_DATA, shared_dem

DATA = SHARED_DATA / "dem"


def _dem(name: str):
    return shared_dem(name)


def _png(path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGBA") if im.mode != "RGBA" else im)


@pytest.fixture
def streamed(monkeypatch):
    """Small maps stream too, in blocks of 8 rows (so many block borders and halos)."""
    monkeypatch.setattr(terrain, "LARGE_IMAGE", 1)
    monkeypatch.setattr(terrain, "STREAM_ROWS", 8)
    monkeypatch.setattr(terrain, "STREAM_HALOS", 0)
    calls = []
    real = terrain.window_map

    def spy(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(terrain, "window_map", spy)
    return calls


MAPS = [
    ("hugo_site.asc", {}),
    ("hugo_site.asc", {"generalize": False, "interval": 2.0}),
    ("hugo_site.asc", {"variant": "multidirectional", "bands": "continuous", "width": 2.5}),
    ("pre_runout_DEM.asc", {"sky_view": True}),
    ("pre_runout_DEM.asc", {"relief": "vat"}),
    ("hugo_site.asc", {"relief": "openness", "bands": False}),
    ("pre_runout_DEM.asc", {"interval": 5.0, "major_interval": 25.0, "sea_level": 300.0}),
    ("SRTMGL3_40.09_-105.55_40.21_-105.35.asc", {"contours": False}),
    ("SRTMGL3_40.09_-105.55_40.21_-105.35.asc", {"bands": [2000.0, 2500.0, 3000.0]}),
    ("SRTMGL3_40.09_-105.55_40.21_-105.35.asc", {"relief": False, "scale": 2}),
]


@pytest.mark.parametrize(("name", "kwargs"), MAPS)
def test_streamed_map_has_the_pixels_of_the_whole_map(name, kwargs, streamed, tmp_path):
    d = _dem(name)
    ref = topographic_map(d, **kwargs)
    h, w = write_topographic_png(tmp_path / "m.png", d, **kwargs)
    assert streamed, "the map did not stream"
    assert (h, w) == ref.shape[:2]
    got = _png(tmp_path / "m.png")
    assert got.shape == ref.shape and np.array_equal(got, ref)


@settings(max_examples=25, deadline=None)
@given(
    st.integers(3, 40), st.integers(3, 40), st.integers(0, 2**31), st.sampled_from([True, False]),
    st.integers(1, 9),
)  # fmt: skip
def test_streamed_map_of_odd_grids(rows, cols, seed, generalize, block):
    """Grids of any shape with nodata anywhere, blocks of 1-9 rows: the whole map's pixels."""
    import tempfile
    from pathlib import Path

    rng = np.random.default_rng(seed)
    z = np.cumsum(rng.standard_normal((rows, cols)), 0).astype(np.float32) * 7
    z[rng.random(z.shape) < 0.1] = np.nan
    z[0, 0] = 1.0  # at least one cell of data
    ref = topographic_map(z, generalize=generalize)
    with pytest.MonkeyPatch.context() as mp, tempfile.TemporaryDirectory() as tmp:
        mp.setattr(terrain, "LARGE_IMAGE", 1)
        mp.setattr(terrain, "STREAM_ROWS", block)
        mp.setattr(terrain, "STREAM_HALOS", 0)
        write_topographic_png(Path(tmp) / "m.png", z, generalize=generalize)
        assert np.array_equal(_png(Path(tmp) / "m.png"), ref)


def test_a_short_halo_would_show(monkeypatch, tmp_path):
    """The test above can fail: with a halo one row short the blocks' borders differ."""
    d = _dem("hugo_site.asc")
    ref = topographic_map(d, generalize=False)
    monkeypatch.setattr(terrain, "LARGE_IMAGE", 1)
    monkeypatch.setattr(terrain, "STREAM_ROWS", 8)
    monkeypatch.setattr(terrain, "STREAM_HALOS", 0)
    real = terrain.window_map
    monkeypatch.setattr(terrain, "window_map", lambda *a: (real(*a)[0], real(*a)[1] - 1))
    write_topographic_png(tmp_path / "m.png", d, generalize=False)
    assert not np.array_equal(_png(tmp_path / "m.png"), ref)


@pytest.mark.parametrize("kwargs", [{"shadows": True}, {"relief": "texture"}])
def test_whole_grid_layers_are_made_whole(kwargs, streamed, tmp_path):
    """Cast shadows and texture shading take the whole grid: made by topographic_map."""
    d = _dem("hugo_site.asc")
    write_topographic_png(tmp_path / "m.png", d, **kwargs)
    assert not streamed
    assert np.array_equal(_png(tmp_path / "m.png"), topographic_map(d, **kwargs))


def test_bad_options_and_paths(tmp_path):
    z = np.arange(100, dtype=np.float32).reshape(10, 10)
    with pytest.raises(InputError, match="width"):
        write_topographic_png(tmp_path / "m.png", z, width=-1.0)
    with pytest.raises(InputError, match="variant"):
        write_topographic_png(tmp_path / "m.png", z, variant="nope")
    with pytest.raises(InputError, match=r"\.png"):
        write_topographic_png(tmp_path / "m.jpg", z)
    with pytest.raises(InputError, match="every cell is nodata"):
        write_topographic_png(tmp_path / "m.png", np.full((5, 5), np.nan, np.float32))
    assert not list(tmp_path.iterdir())


def test_a_failing_block_leaves_no_file(monkeypatch, tmp_path):
    monkeypatch.setattr(terrain, "LARGE_IMAGE", 1)
    monkeypatch.setattr(terrain, "STREAM_ROWS", 4)
    monkeypatch.setattr(terrain, "STREAM_HALOS", 0)

    def broken(*a, **k):
        raise MemoryError("block 3")

    monkeypatch.setattr(terrain, "encode_png_rows", broken)
    z = np.cumsum(np.ones((40, 30), np.float32), 0)
    with pytest.raises(MemoryError):
        write_topographic_png(tmp_path / "m.png", z)
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------- a COG from the same blocks
SRTM = "SRTMGL3_40.09_-105.55_40.21_-105.35.asc"


@pytest.mark.parametrize("kwargs", [{"scale": 4}, {"scale": 4, "generalize": False}])
def test_streamed_geotiff_is_the_cog_of_the_whole_map(kwargs, streamed, monkeypatch, tmp_path):
    """The COG written from the streamed blocks (576 rows: two blocks of whole tile rows) has
    the bytes write_cog makes of the whole map, and the PNG its pixels."""
    from sciviz_gbuf.writers import cog

    encoded = []
    real = cog._Sink.encode
    monkeypatch.setattr(
        cog._Sink, "encode", lambda self, *a: encoded.append(a[1:]) or real(self, *a)
    )
    d = _dem(SRTM)
    ref = topographic_map(d, **kwargs)
    h, w = write_topographic_png(tmp_path / "m.png", d, **kwargs, geotiff=tmp_path / "m.tif")
    assert streamed and (h, w) == ref.shape[:2] == (576, 960)
    assert sorted(encoded) == [(0, 0), (512, 0)], "not two blocks of whole tile rows"
    assert np.array_equal(_png(tmp_path / "m.png"), ref)
    cog.write_cog(ref, tmp_path / "ref.tif", dem=d)
    assert (tmp_path / "m.tif").read_bytes() == (tmp_path / "ref.tif").read_bytes()
    cog.check_cog(tmp_path / "m.tif")


@pytest.mark.parametrize("kwargs", [{"scale": 4}, {"scale": 4, "relief": "vat", "bands": False}])
def test_streamed_cog_is_write_cog_of_the_whole_map(kwargs, streamed, tmp_path):
    """write_topographic_cog: the bytes of write_cog(topographic_map(...)), preview too."""
    from sciviz_gbuf.recipes.terrain import write_topographic_cog
    from sciviz_gbuf.writers import cog

    d = _dem(SRTM)
    out = write_topographic_cog(tmp_path / "m.tif", d, **kwargs, overview_png=tmp_path / "m.png",
                                overview_size=300)  # fmt: skip
    assert streamed and out == (576, 960)
    ref = topographic_map(d, **kwargs)
    cog.write_cog(ref, tmp_path / "r.tif", dem=d, overview_png=tmp_path / "r.png",
                  overview_size=300)  # fmt: skip
    for a, b in (("m.tif", "r.tif"), ("m.png", "r.png")):
        assert (tmp_path / a).read_bytes() == (tmp_path / b).read_bytes()


def test_write_topographic_cog_refuses_before_mapping(streamed, tmp_path):
    from sciviz_gbuf.recipes.terrain import write_topographic_cog

    d = _dem("hugo_site.asc")
    for kwargs, message in (
        ({"geotiff": tmp_path / "g.tif"}, "geotiff: not an option"),
        ({"colour": "red"}, "colour: not an option"),
        ({"overview_png": tmp_path / "o.jpg"}, r"overview_png.*\.png"),
        ({"overview_size": 0}, "overview_size"),
        ({"width": -1.0}, "width"),
    ):
        with pytest.raises(InputError, match=message):
            write_topographic_cog(tmp_path / "m.tif", d, **kwargs)
    with pytest.raises(InputError, match=r"\.tif"):
        write_topographic_cog(tmp_path / "m.png", d)
    assert not streamed and not list(tmp_path.iterdir())


def test_geotiff_of_a_map_made_whole(tmp_path):
    """Small maps are made whole: their COG is write_cog's too."""
    from sciviz_gbuf.writers import cog

    d = _dem("hugo_site.asc")
    write_topographic_png(tmp_path / "m.png", d, geotiff=tmp_path / "m.tif")
    cog.write_cog(topographic_map(d), tmp_path / "ref.tif", dem=d)
    assert (tmp_path / "m.tif").read_bytes() == (tmp_path / "ref.tif").read_bytes()


def test_a_bad_geotiff_is_refused_before_mapping(streamed, tmp_path):
    d = _dem("hugo_site.asc")
    for bad, message in ((tmp_path / "g.png", r"\.tif"), (tmp_path / "no" / "g.tif", "directory")):
        with pytest.raises(InputError, match=message):
            write_topographic_png(tmp_path / "m.png", d, geotiff=bad)
    assert not streamed and not list(tmp_path.iterdir())


def test_a_failing_block_leaves_neither_file(streamed, monkeypatch, tmp_path):
    real = terrain.encode_png_rows
    seen = []

    def broken(rgba, last):
        seen.append(1)
        if last:
            raise MemoryError("the last block")
        return real(rgba, last=last)

    monkeypatch.setattr(terrain, "encode_png_rows", broken)
    with pytest.raises(MemoryError):
        write_topographic_png(tmp_path / "m.png", _dem(SRTM), scale=4, geotiff=tmp_path / "m.tif")
    assert len(seen) == 2 and not list(tmp_path.iterdir())


# ------------------------------------------------------------------------- the PNG's blocks
@settings(max_examples=40, deadline=None)
@given(
    st.integers(1, 40), st.integers(1, 33), st.sampled_from([None, 3, 4]), st.integers(1, 12),
    st.integers(0, 2**31),
)  # fmt: skip
def test_png_blocks_round_trip(rows, cols, channels, block, seed):
    """Blocks of any height, encoded on their own, decode (Pillow) to the image."""
    import io

    rng = np.random.default_rng(seed)
    shape = (rows, cols) if channels is None else (rows, cols, channels)
    a = rng.integers(0, 256, shape, dtype=np.uint8)
    a[: rows // 2] //= 16  # runs and repeats as well as noise
    starts = list(range(0, rows, block))
    parts = [encode_png_rows(a[r : r + block], last=r == starts[-1]) for r in starts]
    buf = io.BytesIO()
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        p = write_png_blocks(Path(tmp) / "a.png", a.shape, parts, dpi=300.0)
        buf.write(p.read_bytes())
    with Image.open(buf) as im:
        assert np.array_equal(np.asarray(im), a)
        assert round(im.info["dpi"][0]) == 300


def test_png_blocks_refuse_bad_shapes(tmp_path):
    part = encode_png_rows(np.zeros((2, 2, 4), np.uint8), last=True)
    with pytest.raises(InputError, match="shape"):
        write_png_blocks(tmp_path / "a.png", (2, 2, 5), [part])
    with pytest.raises(InputError, match=r"\.png"):
        write_png_blocks(tmp_path / "a.tif", (2, 2, 4), [part])
    assert not list(tmp_path.iterdir())


def test_run_bands_on_this_thread():
    """Inside ``on_this_thread`` a kernel's loop runs whole on the calling thread (a map's
    blocks on pool threads do not wait for the shared pool)."""
    import threading

    seen = []

    def kernel(i0, i1):
        seen.append((i0, i1, threading.get_ident()))

    with bands.on_this_thread():
        bands.run_bands(kernel, 1000, min_items=1)
    assert seen == [(0, 1000, threading.get_ident())]
    seen.clear()
    bands.run_bands(kernel, 1000, min_items=1)  # outside: one band per core again
    assert len(seen) == bands.threads()
    assert sorted(s[:2] for s in seen)[0][0] == 0 and max(s[1] for s in seen) == 1000


# --------------------------------------------------------------------------------- the CLI
def test_cli_png_streams_the_pixels_of_the_whole_map(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(terrain, "LARGE_IMAGE", 1)
    monkeypatch.setattr(terrain, "STREAM_ROWS", 16)
    monkeypatch.setattr(terrain, "STREAM_HALOS", 0)
    path = DATA / "pre_runout_DEM.asc"
    if not path.is_file():
        pytest.skip(f"{path} not available")
    assert main(["topo", str(path), "-o", str(tmp_path / "m.png"), "--no-progress",
                 "--dpi", "150"]) == 0  # fmt: skip
    d = read_dem(path)
    got = _png(tmp_path / "m.png")
    assert np.array_equal(got, topographic_map(d))
    with Image.open(tmp_path / "m.png") as im:
        assert round(im.info["dpi"][0]) == 150
    assert f"({got.shape[1]}x{got.shape[0]})" in capsys.readouterr().out


def test_cli_geotiff_streams_with_the_png(monkeypatch, tmp_path):
    """``-o map.png --geotiff map.tif`` streams both: the COG's pixels are the PNG's."""
    import rasterio

    monkeypatch.setattr(terrain, "LARGE_IMAGE", 1)
    calls = []
    real = terrain.window_map
    monkeypatch.setattr(terrain, "window_map", lambda *a, **k: calls.append(1) or real(*a, **k))
    src = DATA / SRTM
    png, tif = tmp_path / "m.png", tmp_path / "m.tif"
    assert main(["topo", str(src), "-o", str(png), "--geotiff", str(tif), "--scale", "4",
                 "--no-progress"]) == 0  # fmt: skip
    assert calls, "the map did not stream"
    with rasterio.open(tif) as f:
        rgba = np.moveaxis(f.read(), 0, 2)
        assert f.overviews(1) == [2] and f.block_shapes[0] == (512, 512)
        gt = f.transform.to_gdal()
    with pytest.warns(UserWarning, match="degrees"):
        x0, dx, _, y0, _, dy = read_dem(src).transform
    assert gt == pytest.approx((x0, dx / 4, 0.0, y0, 0.0, dy / 4), rel=1e-12)  # --scale 4
    assert np.array_equal(rgba, _png(png))


def test_cli_cog_streams(monkeypatch, tmp_path):
    """``-o map.tif`` streams: the bytes of write_cog of the map made whole."""
    from sciviz_gbuf.writers import cog

    monkeypatch.setattr(terrain, "LARGE_IMAGE", 1)
    calls = []
    real = terrain.window_map
    monkeypatch.setattr(terrain, "window_map", lambda *a, **k: calls.append(1) or real(*a, **k))
    src = DATA / "pre_runout_DEM.asc"
    tif = tmp_path / "m.tif"
    assert main(["topo", str(src), "-o", str(tif), "--overview", str(tmp_path / "o.png"),
                 "--no-progress"]) == 0  # fmt: skip
    assert calls, "the map did not stream"
    d = read_dem(src)
    cog.write_cog(topographic_map(d), tmp_path / "r.tif", dem=d, overview_png=tmp_path / "r.png")
    assert tif.read_bytes() == (tmp_path / "r.tif").read_bytes()
    assert (tmp_path / "o.png").read_bytes() == (tmp_path / "r.png").read_bytes()
