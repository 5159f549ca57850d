"""The contour figures of Saito & Takahashi 1990 (recipes.contour_figures): Fig. 5, 6 and 11."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from sciviz_gbuf import InputError
from sciviz_gbuf.datasets import load_jacksboro_terrain
from sciviz_gbuf.recipes import (
    CONTOUR_CAPTIONS,
    fig5_panels,
    fig6_panels,
    fig11_panels,
    write_panels,
)
from sciviz_gbuf.recipes.contour_figures import jacksboro_plan, relief, xy_field

SIZE = 128


def _radius(size: int) -> np.ndarray:
    y, x = np.mgrid[1 : -1 : size * 1j, -1 : 1 : size * 1j]
    return np.hypot(x, y)


def _check_panels(panels, keys, shape):
    assert [k for k, _, _ in panels] == keys
    for key, title, image in panels:
        assert key in CONTOUR_CAPTIONS and title
        assert image.shape[:2] == shape and image.ndim in (2, 3), key
        assert image.dtype == np.float32, key
        assert np.isfinite(image).all() and image.min() >= 0 and image.max() <= 1, key


@pytest.fixture(scope="module")
def fig5():
    return {k: im for k, _, im in fig5_panels(SIZE)}


@pytest.fixture(scope="module")
def fig11():
    return {k: im for k, _, im in fig11_panels(SIZE)}


# ---------------------------------------------------------------------------- Fig. 5
def test_xy_field():
    s, px = xy_field(17)
    assert s.dtype == np.float32 and s.shape == (17, 17)
    assert px == pytest.approx(0.125)
    assert s[0, -1] == 1 and s[0, 0] == -1 and s[8, 8] == 0  # row 0 is y = 1
    assert s[4, 12] == pytest.approx(0.25)  # x = 0.5, y = 0.5
    with pytest.raises(InputError, match="size"):
        xy_field(8)


def test_fig5_panels_keys_and_shapes():
    keys = ["a_black", "b_grey", "f1_bilevel", "f1_linear", "f1_smooth"]
    _check_panels(fig5_panels(SIZE), keys, (SIZE, SIZE))
    _check_panels(fig5_panels(64, profiles=False), keys[:2], (64, 64))


def test_fig5_dense_corners_black_or_grey_and_white_centre(fig5):
    r = _radius(SIZE)
    corners = r > 1.15
    a, b = fig5["a_black"], fig5["b_grey"]
    # (a) c_dense = 1: the corners are solid ink
    assert (a[corners] < 0.1).mean() > 0.95
    # (b) c_dense = 0.5: an even grey there, not lines
    assert np.mean(b[corners]) == pytest.approx(0.5, abs=0.03)
    assert (np.abs(b[corners] - 0.5) < 0.1).mean() > 0.9
    # the flat centre (g -> 0) fades to white (c_sparse = 0) in both
    centre = r < 0.05
    for img in (a, b):
        assert img[centre].min() > 0.85 and img[centre].mean() > 0.9
    # in between, separate lines: both full ink and white paper
    ring = (r > 0.3) & (r < 0.5)
    for img in (a, b):
        assert img[ring].min() < 0.1 and img[ring].max() > 0.95
        assert 0.2 < img[ring].mean() < 0.9


def test_fig5_line_profiles(fig5):
    bilevel, linear, smooth = (fig5[f"f1_{p}"] for p in ("bilevel", "linear", "smooth"))
    # Eq. 8: a step, no antialiasing; the others have intermediate greys at the line edges
    assert set(np.unique(bilevel)) <= {0.0, 1.0}
    for img in (linear, smooth):
        assert ((img > 0.05) & (img < 0.95)).mean() > 0.05
    # every profile puts about the same ink across a line (width d)
    inks = [1 - img.mean() for img in (bilevel, linear, smooth)]
    assert max(inks) < 1.25 * min(inks) and min(inks) > 0.02


# ---------------------------------------------------------------------------- Fig. 6
def test_fig6_hatching_keeps_its_density_where_contours_crowd():
    size = 192
    panels = fig6_panels(size)
    _check_panels(panels, ["contours", "hatching", "hatching_exact"], (size, size))
    ink = {k: 1 - im for k, _, im in panels}
    r = _radius(size)
    flat, steep = (r > 0.1) & (r < 0.3), r > 1.05  # gradients 0.1-0.3 vs > 1.05
    ratio = {k: v[steep].mean() / v[flat].mean() for k, v in ink.items()}
    assert ratio["contours"] > 3  # crowded corners, sparse centre
    assert 0.7 < ratio["hatching"] < 1.4
    assert 0.85 < ratio["hatching_exact"] < 1.15  # Eq. 18: constant mean ink
    # the hatching is lines, not a grey tone
    h = ink["hatching"][steep]
    assert h.max() > 0.95 and (h < 0.05).mean() > 0.5


def test_fig6_without_exact():
    assert [k for k, _, _ in fig6_panels(64, exact=False)] == ["contours", "hatching"]


# ---------------------------------------------------------------------------- Fig. 11
def test_jacksboro_plan_is_the_dem_north_up():
    grid = load_jacksboro_terrain()
    nx, ny, _ = grid.dimensions
    elev = np.asarray(grid.point_data["elevation"]).reshape(ny, nx)  # row 0 south
    pts = np.asarray(grid.points)
    dx, dy = pts[1, 0] - pts[0, 0], pts[nx, 1] - pts[0, 1]
    # centre on sample (150, 200) with pixels one DEM row high: the centre column of the plan
    # hits the DEM's samples; row 0 of the plan is north, i.e. higher DEM rows
    z = jacksboro_plan(17, pixel_size=dy, centre=(200 * dx, 150 * dy), smooth=0.0)
    assert z.shape == (17, 17) and z.dtype == np.float32
    np.testing.assert_allclose(z[:, 8], elev[158:141:-1, 200], atol=0.01)


def test_jacksboro_plan_rejects():
    with pytest.raises(InputError, match="fit"):
        jacksboro_plan(512, pixel_size=100.0)
    with pytest.raises(InputError, match="pixel_size"):
        jacksboro_plan(64, pixel_size=0.0)
    with pytest.raises(InputError, match="size"):
        jacksboro_plan(4)


def test_relief_sun_in_the_north_west():
    j = np.arange(32, dtype=np.float32)
    east = np.tile(j, (32, 1)) * 10  # rises to the east: faces west
    south = east.T  # rises with the row index, to the south: faces north
    flat = relief(np.zeros((32, 32), np.float32), 20.0)
    assert flat[5, 5] == pytest.approx(np.sin(np.radians(45)), abs=1e-5)
    for facing_nw in (east, south):
        assert relief(facing_nw, 20.0)[5, 5] > flat[5, 5] + 0.1
        assert relief(-facing_nw, 20.0)[5, 5] < flat[5, 5] - 0.1


def test_fig11_panels_keys_and_shapes(fig11):
    keys = ["wz", "cn", "cn_unthinned", "majors", "sh", "bands", "mx3"]
    _check_panels(list(fig11_panels(32)), keys, (32, 32))
    assert list(fig11) == keys
    assert fig11["bands"].ndim == 3 and fig11["mx3"].ndim == 3 and fig11["cn"].ndim == 2


def test_fig11_minor_contours_thin_out_on_steep_slopes(fig11):
    z = jacksboro_plan(SIZE)
    grad_r, grad_c = np.gradient(z.astype(np.float64))
    minor_spacing = 20.0 / np.maximum(np.hypot(grad_r, grad_c), 1e-9)  # px between 20 m lines
    steep, gentle = minor_spacing < 2.5, minor_spacing > 8.0
    assert steep.mean() > 0.05 and gentle.mean() > 0.05
    cn, majors = 1 - fig11["cn"], 1 - fig11["majors"]
    unthinned = 1 - fig11["cn_unthinned"]
    # steep: only the majors remain (the minors faded to white, c_dense = 0) ...
    assert np.abs(cn - majors)[steep].mean() < 0.02
    assert unthinned[steep].mean() > 1.5 * cn[steep].mean()
    # ... gentle: the minors are there, and add much ink to the majors
    assert cn[gentle].sum() > 3 * majors[gentle].sum()
    assert np.abs(cn - unthinned)[gentle].mean() < 0.02
    # majors never thin out: wherever the majors alone have ink, (cn) has it too
    assert (cn >= majors - 0.02).all()


def test_fig11_combination(fig11):
    cn, bands, mx3 = 1 - fig11["cn"], fig11["bands"], fig11["mx3"]
    # contour ink is black in the combination
    assert (mx3[cn > 0.99] < 0.02).all()
    # colour bands: few discrete tints, one per 100 m of height, ordered by height
    z = jacksboro_plan(SIZE)
    band = np.floor(z / 100).astype(int)
    tints = {b: np.unique(bands[band == b], axis=0) for b in np.unique(band)}
    assert len(tints) >= 3 and all(len(t) == 1 for t in tints.values())
    assert len({tuple(t[0]) for t in tints.values()}) == len(tints)
    # relief shades the bands away from the contours: not a flat copy of them
    clear = cn < 0.01
    assert np.std(mx3[clear] / np.maximum(bands[clear], 1e-3)) > 0.05


# ---------------------------------------------------------------------------- files
def test_write_panels(tmp_path):
    img = np.linspace(0, 1, 16 * 16, dtype=np.float32).reshape(16, 16)
    rgb = np.dstack([img, img, 1 - img])
    paths = write_panels(tmp_path, "figX", [("a", "A", img), ("b", "B", rgb)], columns=2)
    assert [p.name for p in paths] == ["figX_a.png", "figX_b.png", "figX_montage.png"]
    with Image.open(paths[0]) as im:
        assert im.size == (16, 16) and im.mode == "L"
    with Image.open(paths[2]) as im:
        assert im.size[0] > 32
