"""``topo``/``birdseye`` ``--size``, ``--scale``, ``--dpi``: the output's size, the GeoTIFF's
transform and the PNG's DPI follow; bad or conflicting values exit 2 with one line."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from sciviz_gbuf.cli import main
from tests.helpers.cli import run_cli

rasterio = pytest.importorskip("rasterio")


@pytest.fixture
def dem_asc(tmp_path):
    """A 30 x 20 ESRI ASCII grid of 10 m cells (a smooth hill)."""
    r, c = np.mgrid[0:20, 0:30].astype(np.float64)
    z = 100.0 + 40.0 * np.exp(-((c - 14.3) ** 2 + (r - 9.6) ** 2) / 60.0)
    path = tmp_path / "hill.asc"
    header = "ncols 30\nnrows 20\nxllcorner 500000\nyllcorner 4000000\ncellsize 10\n"
    rows = "\n".join(" ".join(f"{v:.3f}" for v in row) for row in z)
    path.write_text(header + "NODATA_value -9999\n" + rows + "\n")
    return path


def test_topo_scale_writes_a_larger_map_and_georeference(dem_asc, tmp_path):
    out, tif = tmp_path / "m.png", tmp_path / "m.tif"
    argv = ["topo", str(dem_asc), "-o", str(out), "--scale", "2", "--geotiff", str(tif)]
    assert main([*argv, "--no-progress"]) == 0
    with Image.open(out) as im:
        assert im.size == (60, 40) and "dpi" not in im.info
    with rasterio.open(tif) as src:
        assert (src.width, src.height) == (60, 40)
        assert (src.transform.a, src.transform.e) == pytest.approx((5.0, -5.0))
        assert tuple(src.bounds) == pytest.approx((500000, 4000000, 500300, 4000200))


def test_topo_map_scale_and_dpi(dem_asc, tmp_path):
    """1:10000 at 254 dpi: 1 m per pixel, 300 x 200 pixels; the PNG records 254 dpi; a COG
    output follows the output pixel too."""
    out = tmp_path / "m.png"
    argv = ["topo", str(dem_asc), "-o", str(out), "--scale", "1:10000", "--dpi", "254"]
    assert main([*argv, "--no-progress"]) == 0
    with Image.open(out) as im:
        assert im.size == (300, 200)
        assert im.info["dpi"] == pytest.approx((254, 254), abs=0.01)
    cog = tmp_path / "m.tif"
    assert main(["topo", str(dem_asc), "-o", str(cog), "--size", "45", "--no-progress"]) == 0
    with rasterio.open(cog) as src:
        assert (src.width, src.height) == (45, 30)
        assert src.transform.a == pytest.approx(300 / 45)


def test_birdseye_size_and_dpi(dem_asc, tmp_path):
    out = tmp_path / "b.png"
    argv = ["birdseye", str(dem_asc), "-o", str(out), "--size", "160", "--supersample", "1"]
    assert main([*argv, "--dpi", "150", "--no-progress"]) == 0
    with Image.open(out) as im:
        assert im.size == (160, 120)
        assert im.info["dpi"] == pytest.approx((150, 150), abs=0.02)  # whole px per m


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--size", "100", "--scale", "2"], "scale: expected size= or scale=, not both"),
        (["--scale", "1:25000"], "dpi: a map scale '1:25000' needs dpi="),
        (["--size", "20000"], "size: expected an integer in [1, 16384]"),
        (["--scale", "1000"], "scale: 1000.0 gives a map side of"),
        (["--scale", "1:25000", "--dpi", "100000"], "dpi: expected a number in (0, 9600]"),
        (["--chunks", "16", "--size", "64"], "--size: out of core (--chunks/--dask)"),
    ],
)
def test_topo_refuses_bad_sizes_in_one_line(dem_asc, tmp_path, capsys, extra, message):
    out = tmp_path / ("m.tif" if "--chunks" in extra else "m.png")
    assert main(["topo", str(dem_asc), "-o", str(out), *extra, "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err
    assert not list(tmp_path.glob("m.*")) and not list(tmp_path.glob(".m.*"))


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["topo", "--size", "0"], "argument --size: expected a long side N or WIDTHxHEIGHT"),
        (["topo", "--size", "12by4"], "argument --size: expected a long side N"),
        (["topo", "--scale", "2:3"], "argument --scale: expected pixels per DEM cell"),
        (["topo", "--dpi", "-5"], "argument --dpi: expected dots per inch > 0, got '-5'"),
        (["birdseye", "--scale", "1:25000"], "scale: a map scale '1:25000' applies to plan-view"),
    ],
)
def test_bad_values_exit_2_in_a_fresh_process(tmp_path, argv, message):
    r = run_cli([*argv, "-o", tmp_path / "x.png", "--no-progress"])
    assert r.returncode == 2
    last = r.stderr.strip().splitlines()[-1]
    assert message in last, r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("cmd", ["topo", "birdseye"])
def test_exact_contours_flag_draws_the_exact_lines(cmd, tmp_path, shared_data):
    """``--exact-contours``: the map of ``generalize=False``; the default is the generalised
    map (on whole-metre SRTM heights the two differ)."""
    import warnings

    import sciviz_gbuf as sg
    from sciviz_gbuf.readers import read_dem
    from sciviz_gbuf.recipes import birdseye_gbuffer, birdseye_panels

    src = shared_data / "dem" / "SRTMGL3_40.09_-105.55_40.21_-105.35.asc"
    if not src.is_file():
        pytest.skip(f"{src} not available")
    extra = ["--size", "240x160", "--supersample", "1"] if cmd == "birdseye" else []
    images = {}
    for flag in ([], ["--exact-contours"]):
        out = tmp_path / f"{cmd}{len(flag)}.png"
        assert main([cmd, str(src), "-o", str(out), "--no-progress", *extra, *flag]) == 0
        with Image.open(out) as im:
            images[bool(flag)] = np.asarray(im.convert("RGBA"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        dem = read_dem(src)
    if cmd == "topo":
        want = {g: sg.topographic_map(dem, generalize=not g) for g in (False, True)}
    else:
        gb = birdseye_gbuffer(dem, size=(240, 160), supersample=1)
        want = {g: birdseye_panels(gb, generalize=not g)["mx4"] for g in (False, True)}
    for exact in (False, True):
        np.testing.assert_array_equal(images[exact], want[exact])
    assert not np.array_equal(images[True], images[False])
