"""Graticules and furniture placement of print layouts: round spacings, values printed as a
map reader expects, ticks exactly where their coordinates are, the furniture panel inside
the frame, refusals, and the command line."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import sciviz_gbuf.datasets
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import DEM
from sciviz_gbuf.recipes._resample import map_grid
from sciviz_gbuf.recipes.layout import map_page, page_scale, tick_text
from tests.helpers.cli import assert_clean_failure, run_cli


def _projected(h=300, w=240, cell=5.0):
    i, j = np.mgrid[0:h, 0:w].astype(np.float32)
    z = 200 + 0.3 * j + 40 * np.sin(i / 25.0)
    return DEM(heights=z, mask=np.ones(z.shape, bool), crs="EPSG:32613",
               transform=(485_010.0, cell, 0.0, 4_450_020.0, 0.0, -cell),
               pixel_size=(cell, cell), geographic=False)  # fmt: skip


@pytest.mark.parametrize(
    ("value", "step", "geo", "axis", "text"),
    [
        (485000.0, 500.0, False, "x", "485\u2009000"),
        (-1500.0, 500.0, False, "y", "\u22121\u2009500"),
        (-105.5333333333, 2 / 60, True, "x", "105\u00b032\u2032W"),
        (40.0, 1.0, True, "y", "40\u00b0N"),
        (40.1, 1 / 60, True, "y", "40\u00b006\u2032N"),
        (-33.8625, 15 / 3600, True, "y", "33\u00b051\u203245\u2033S"),
        (0.0, 30 / 60, True, "x", "0\u00b000\u2032E"),
    ],
)
def test_tick_text(value, step, geo, axis, text):
    assert tick_text(value, step, geo, axis) == text


def _ticks(fig, rotation=0.0):
    return [t for t in fig.texts if t.get_rotation() == rotation and t.get_gid() == "graticule"]


def test_ticks_stand_at_their_coordinates():
    d = _projected()
    fig = map_page(d, dpi=100, graticule="ticks", legend=False)
    img, (x0, y0), n = fig.sciviz_map
    grid = map_grid(d, scale=f"1:{n}", dpi=100)
    gx0, gdx, _, gy0, _, gdy = grid.transform
    xs = _ticks(fig, 0.0)
    ys = _ticks(fig, 90.0)
    assert len(xs) >= 6 and len(ys) >= 6  # top and bottom, left and right
    values = sorted({float(t.get_text().replace("\u2009", "")) for t in xs})
    steps = np.diff(values)
    assert np.allclose(steps, steps[0]) and steps[0] in (100.0, 200.0, 500.0, 1000.0)
    assert all(v % steps[0] == 0 for v in values)
    for t in xs:
        v = float(t.get_text().replace("\u2009", ""))
        x_px = t.get_position()[0] * 100  # inches to page pixels
        assert x_px == pytest.approx(x0 + (v - gx0) / gdx, abs=1e-6)
    for t in ys:
        v = float(t.get_text().replace("\u2009", ""))
        y_px = t.get_position()[1] * 100
        assert y_px == pytest.approx(y0 + img.shape[0] - (v - gy0) / gdy, abs=1e-6)


def test_grid_lines_and_geographic_ticks():
    d = sciviz_gbuf.datasets.load_jacksboro_dem()
    fig = map_page(d, dpi=80, graticule="grid")
    texts = [t.get_text() for t in _ticks(fig, 0.0)]
    assert texts and all(t.endswith("W") and "\u00b0" in t for t in texts)
    from matplotlib.collections import LineCollection

    grids = [a for a in fig.artists if isinstance(a, LineCollection)
             and a.get_gid() == "graticule-grid"]  # fmt: skip
    assert (
        len(grids) == 1
        and len(grids[0].get_segments()) == len(texts) // 2 + len(_ticks(fig, 90.0)) // 2
    )


def test_furniture_inside_the_frame():
    d = _projected(600, 900)
    out = map_page(d, dpi=100, title="T")
    inside = map_page(d, dpi=100, title="T", furniture="inside")
    assert page_scale(d, furniture="inside") <= page_scale(d)
    img, (x0, y0), _ = inside.sciviz_map
    h = img.shape[0]
    words = {t.get_text(): t for t in inside.texts}
    for key in ("Height (m)", "N"):
        x, y = words[key].get_position()  # figure fractions
        page_w, page_h = inside.get_size_inches() * 100
        assert x0 <= x * page_w <= x0 + img.shape[1] and y0 <= y * page_h <= y0 + h, key
    # outside, the same words lie below the map
    _, (_, y2), _ = out.sciviz_map
    y = {t.get_text(): t for t in out.texts}["Height (m)"].get_position()[1]
    assert y * out.get_size_inches()[1] * 100 < y2


def test_refusals():
    d = _projected()
    with pytest.raises(InputError, match="graticule"):
        map_page(d, dpi=50, graticule="lines")
    with pytest.raises(InputError, match="furniture"):
        map_page(d, dpi=50, furniture="left")
    rotated = dataclasses.replace(d, transform=(485_010.0, 5.0, 0.5, 4_450_020.0, 0.5, -5.0))
    with pytest.raises(InputError, match="rotated"):
        map_page(rotated, dpi=50, graticule="ticks")


def test_cli_graticule_and_furniture(tmp_path):
    dem = tmp_path / "dem.asc"
    z = np.add.outer(np.arange(60.0), np.arange(80.0)) * 2.0
    head = "ncols 80\nnrows 60\nxllcorner 485000\nyllcorner 4450000\ncellsize 10\n"
    dem.write_text(head + "\n".join(" ".join(f"{v:g}" for v in r) for r in z))
    out = tmp_path / "page.pdf"
    proc = run_cli(["topo", str(dem), "-o", str(out), "--page", "A4", "--dpi", "72",
                    "--graticule", "grid", "--furniture", "inside"])  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes().startswith(b"%PDF")
    bad = run_cli(["topo", str(dem), "-o", str(tmp_path / "x.png"), "--graticule", "ticks"])
    assert_clean_failure(bad, names="--graticule", outputs=[tmp_path / "x.png"])
