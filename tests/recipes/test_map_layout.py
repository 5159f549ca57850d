"""Print layouts: the page's size, the map placed unresampled at its stated scale, PDF
output, refusals."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import sciviz_gbuf.datasets
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.readers import read_dem
from sciviz_gbuf.recipes.layout import PAGES, map_page, page_scale, write_map_page
from tests.helpers.cli import assert_clean_failure, run_cli


@pytest.fixture(scope="module")
def dem():
    return sciviz_gbuf.datasets.load_jacksboro_dem()


def test_page_png_holds_the_map_pixel_for_pixel(tmp_path, dem):
    path = tmp_path / "page.png"
    w, h = write_map_page(path, dem, dpi=100, title="T", credit="C")
    page = np.asarray(Image.open(path).convert("RGBA"))
    assert page.shape[:2] == (h, w)
    assert (w, h) == (int(210 / 25.4 * 100), int(297 / 25.4 * 100))
    fig = map_page(dem, dpi=100, title="T", credit="C")
    img, (x0, y0), n = fig.sciviz_map
    ih, iw = img.shape[:2]
    top = h - y0 - ih  # figimage's offset counts from the bottom
    crop = page[top : top + ih, x0 : x0 + iw, :3]
    opaque = img[..., 3] == 255
    inner = np.zeros_like(opaque)
    inner[2:-2, 2:-2] = True  # the frame line is drawn over the map's edge
    assert (crop[opaque & inner] == img[..., :3][opaque & inner]).all()
    # the stated scale: the map's width on paper is the ground width / N
    ground_w = dem.shape[1] * dem.pixel_size[0]
    assert iw / 100 * 0.0254 == pytest.approx(ground_w / n, rel=0.01)


@pytest.mark.parametrize("page", sorted(PAGES))
@pytest.mark.parametrize("landscape", [False, True])
def test_round_scale_is_the_smallest_that_fits(dem, page, landscape):
    n = page_scale(dem, page, landscape=landscape)
    mant = n / 10 ** np.floor(np.log10(n))
    assert round(float(mant), 6) in (1.0, 2.0, 2.5, 5.0)
    fig = map_page(dem, page=page, landscape=landscape, dpi=50, legend=False, labels=False)
    img, _, used = fig.sciviz_map
    assert used == n
    pw, _ph = PAGES[page][::-1] if landscape else PAGES[page]
    assert img.shape[1] / 50 * 25.4 <= pw - 24 + 0.5


def test_pdf_page(tmp_path, dem):
    path = tmp_path / "page.pdf"
    write_map_page(path, dem, dpi=72, title="Jacksboro")
    data = path.read_bytes()
    assert data.startswith(b"%PDF-") and data.rstrip().endswith(b"%%EOF")
    assert b"/Subtype /Image" in data  # the map raster
    assert b"DejaVu" in data  # vector text of the furniture


def test_stated_scale_that_does_not_fit_is_refused(dem):
    with pytest.raises(InputError, match="scale: at 1:10000"):
        map_page(dem, scale="1:10000")
    with pytest.raises(InputError, match="scale"):
        map_page(dem, scale="2:5")


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"page": "A9"}, "page"),
        ({"dpi": 0}, "dpi"),
        ({"dpi": 2000}, "dpi"),
        ({"size": 100}, "size"),
        ({"title": 5}, "title"),
        ({"landscape": "yes"}, "landscape"),
    ],
)
def test_bad_page_options(dem, kw, match):
    with pytest.raises(InputError, match=match):
        map_page(dem, **kw)


def test_geographic_grid_page(tmp_path, shared_data):
    with pytest.warns(UserWarning):
        d = read_dem(shared_data / "dem" / "SRTMGL3_40.09_-105.55_40.21_-105.35.asc")
    fig = map_page(d, dpi=60)
    assert fig.sciviz_map[2] >= 10000
    texts = [t.get_text() for t in fig.texts]
    assert "True north" in texts


def test_cli_page(tmp_path):
    out = tmp_path / "map.pdf"
    proc = run_cli(["topo", "--page", "A4", "--labels", "--dpi", "100", "-o", out,
                    "--title", "Jacksboro"], cwd=tmp_path)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes().startswith(b"%PDF-")
    bad = tmp_path / "bad.pdf"
    for argv, name in (
        (["--page", "A4", "--size", "100"], "--size"),
        (["--page", "A4", "--scale", "3"], "--scale"),
        (["--title", "x"], "--page"),
        (["--page", "A4", "--chunks", "64"], "--page"),
    ):
        assert_clean_failure(run_cli(["topo", "-o", bad, *argv], cwd=tmp_path), names=name,
                             outputs=[bad])  # fmt: skip
