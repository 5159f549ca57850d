"""compose (channel images, PNG, montage), datasets (nut, Jacksboro DEM in metres) and run_demo."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from PIL import Image

from sciviz_gbuf import GBuffer, InputError
from sciviz_gbuf.apps.demo import run_demo, terrain_birdseye_camera
from sciviz_gbuf.compose import colorize, ids_to_rgb, montage, normals_to_rgb, to_uint8, write_png
from sciviz_gbuf.core.framing import framing
from sciviz_gbuf.datasets import load_jacksboro_terrain, load_nut

WHITE = np.ones(3, dtype=np.float32)


# ---------------------------------------------------------------------------- colorize
def test_colorize_background_and_limits():
    v = np.array([[0.0, 1.0, 2.0], [np.nan, 0.5, 3.0]])
    mask = np.array([[True, True, True], [True, True, False]])
    before = v.copy()
    rgb = colorize(v, mask=mask, cmap="viridis", background=(1.0, 0.0, 0.0))
    np.testing.assert_array_equal(v, before)  # input untouched
    assert rgb.shape == (2, 3, 3)
    assert rgb.dtype == np.float32
    np.testing.assert_array_equal(rgb[1, 0], [1, 0, 0])  # NaN
    np.testing.assert_array_equal(rgb[1, 2], [1, 0, 0])  # masked out
    cmap = matplotlib.colormaps["viridis"]
    # the default range is that of the finite, masked values: 0 .. 2 (3.0 is masked out)
    np.testing.assert_allclose(rgb[0, 0], cmap(0.0)[:3], atol=1e-6)
    np.testing.assert_allclose(rgb[0, 2], cmap(1.0)[:3], atol=1e-6)


def test_colorize_explicit_range_clips():
    v = np.array([[-5.0, 10.0, 20.0, 100.0]])
    rgb = colorize(v, vmin=10.0, vmax=20.0, cmap="magma")
    cmap = matplotlib.colormaps["magma"]
    for j, t in enumerate([0.0, 0.0, 1.0, 1.0]):
        np.testing.assert_allclose(rgb[0, j], cmap(t)[:3], atol=1e-6)


def test_colorize_all_background_and_constant():
    assert (colorize(np.full((4, 5), np.nan)) == WHITE).all()
    const = colorize(np.full((2, 2), 7.0))
    np.testing.assert_allclose(const[0, 0], matplotlib.colormaps["viridis"](0.5)[:3], atol=1e-6)


@settings(max_examples=40, deadline=None)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(1, 8), st.integers(1, 8)),
        elements=st.floats(-1e6, 1e6) | st.just(np.nan),
    )
)
def test_colorize_property(v):
    rgb = colorize(v)
    assert rgb.shape == (*v.shape, 3)
    assert np.isfinite(rgb).all()
    assert ((rgb >= 0) & (rgb <= 1)).all()
    assert (rgb[np.isnan(v)] == WHITE).all()


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"values": np.zeros((2, 2, 2))}, "values"),
        ({"values": np.zeros((2, 2)), "mask": np.ones((3, 2), bool)}, "mask"),
        ({"values": np.zeros((2, 2)), "mask": np.ones((2, 2))}, "mask"),
        ({"values": np.zeros((2, 2)), "cmap": "no_such_map"}, "cmap"),
        ({"values": np.zeros((2, 2)), "vmin": 2.0, "vmax": 1.0}, "vmin"),
        ({"values": np.zeros((2, 2)), "vmin": np.nan}, "vmin"),
        ({"values": np.zeros((2, 2)), "background": (1, 1)}, "background"),
        ({"values": np.zeros((2, 2)), "background": (2, 0, 0)}, "background"),
        ({"values": np.array([["a", "b"]])}, "values"),
    ],
)
def test_colorize_rejects(kwargs, word):
    values = kwargs.pop("values")
    with pytest.raises(InputError, match=word):
        colorize(values, **kwargs)


# ---------------------------------------------------------------------------- normals, ids
def test_normals_to_rgb():
    n = np.array([[[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [np.nan, np.nan, np.nan]]], np.float32)
    before = n.copy()
    rgb = normals_to_rgb(n, background=(0.0, 0.0, 0.0))
    np.testing.assert_array_equal(n, before)
    np.testing.assert_allclose(rgb[0, 0], [0.5, 0.5, 1.0])
    np.testing.assert_allclose(rgb[0, 1], [0.0, 0.5, 0.5])
    np.testing.assert_array_equal(rgb[0, 2], [0, 0, 0])
    with pytest.raises(InputError, match="normal"):
        normals_to_rgb(np.zeros((2, 2, 2)))
    with pytest.raises(InputError, match="normal"):
        normals_to_rgb(np.zeros((2, 2, 3), dtype=np.int32))


def test_ids_to_rgb_distinct_and_stable():
    ids = np.arange(1000, dtype=np.int64).reshape(20, 50)
    rgb = ids_to_rgb(ids)
    triples = to_uint8(rgb).reshape(-1, 3)
    assert len(np.unique(triples, axis=0)) == 1000
    # equal ids give equal colours, whatever the array they are in
    again = ids_to_rgb(np.array([[999, 0], [999, -1]], dtype=np.int32))
    np.testing.assert_array_equal(again[0, 0], rgb[-1, -1])
    np.testing.assert_array_equal(again[1, 0], rgb[-1, -1])
    np.testing.assert_array_equal(again[0, 1], rgb[0, 0])
    np.testing.assert_array_equal(again[1, 1], WHITE)
    assert not (rgb[0, 0] == WHITE).all()  # id 0 (one-object scenes) is not background


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**24 - 1), st.integers(0, 2**24 - 1))
def test_ids_to_rgb_injective_below_2_24(a, b):
    ca, cb = (to_uint8(ids_to_rgb(np.array([[x]]))) for x in (a, b))
    assert (a == b) == bool((ca == cb).all())


def test_ids_to_rgb_rejects_floats():
    with pytest.raises(InputError, match="ids"):
        ids_to_rgb(np.zeros((2, 2)))


# ---------------------------------------------------------------------------- PNG, montage
@pytest.mark.parametrize(
    "image",
    [
        np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4),
        np.random.default_rng(0).random((5, 7, 3)),
        np.random.default_rng(1).integers(0, 256, (6, 4, 4), dtype=np.uint8),
        np.eye(4, dtype=bool),
    ],
)
def test_write_png_round_trip(tmp_path, image):
    before = image.copy()
    path = write_png(tmp_path / "x.png", image)
    np.testing.assert_array_equal(image, before)
    with Image.open(path) as im:
        assert im.format == "PNG"
        back = np.asarray(im)
    np.testing.assert_array_equal(back, to_uint8(image))


@pytest.mark.parametrize(
    ("image", "name"),
    [
        (np.zeros((2, 2, 2)), "x.png"),
        (np.zeros((2, 2), dtype=np.int16), "x.png"),
        (np.zeros((2, 2)), "x.jpg"),
        (np.full((2, 2), np.nan), "x.png"),
    ],
)
def test_write_png_rejects(tmp_path, image, name):
    with pytest.raises(InputError):
        write_png(tmp_path / name, image)


def test_montage_layout_and_titles():
    a = np.zeros((30, 40, 3), np.float32)
    b = np.ones((20, 20), np.float32)
    out = montage([("black", a), ("white", b), ("mask", np.eye(10, dtype=bool))], columns=2)
    assert out.dtype == np.float32
    assert out.shape[2] == 3
    assert out.shape[0] > 2 * 30 and out.shape[1] > 2 * 40
    assert ((out >= 0) & (out <= 1)).all()
    # the black tile and some dark title text are in there
    assert (out.min(axis=2) == 0).sum() >= 30 * 40
    with pytest.raises(InputError, match="images"):
        montage([])
    with pytest.raises(InputError, match="images"):
        montage([("t", np.zeros((2, 2, 2)))])
    with pytest.raises(InputError, match="columns"):
        montage([("t", a)], columns=0)


# ---------------------------------------------------------------------------- datasets
@pytest.fixture(scope="module")
def dem():
    from matplotlib import cbook

    data = cbook.get_sample_data("jacksboro_fault_dem.npz")
    if not hasattr(data, "files"):
        data = np.load(data)
    with data:
        return {k: np.asarray(data[k]) for k in data.files}


def test_load_nut():
    nut = load_nut()
    assert nut.n_points > 0 and nut.n_cells > 0


def test_jacksboro_terrain_north_up_and_metres(dem):
    raw = dem["elevation"]
    rows, cols = raw.shape
    grid = load_jacksboro_terrain()
    assert grid.dimensions == (cols, rows, 1)
    elev = np.asarray(grid.point_data["elevation"])
    assert elev.dtype == np.float32
    pts = np.asarray(grid.points)
    # the northernmost row (row 0 of the file, whose ymin is the north edge) is at max y
    assert dem["ymin"] > dem["ymax"]
    north = np.isclose(pts[:, 1], pts[:, 1].max())
    np.testing.assert_array_equal(elev[north][np.argsort(pts[north, 0])], raw[0])
    south = np.isclose(pts[:, 1], pts[:, 1].min())
    np.testing.assert_array_equal(elev[south][np.argsort(pts[south, 0])], raw[-1])
    # and the west edge is at min x
    west = np.isclose(pts[:, 0], pts[:, 0].min())
    np.testing.assert_array_equal(elev[west][np.argsort(-pts[west, 1])], raw[:, 0])
    # the whole array, and z, are the raw elevations
    np.testing.assert_array_equal(np.sort(elev), np.sort(raw.ravel().astype(np.float32)))
    np.testing.assert_array_equal(pts[:, 2], elev)
    # metres, not degrees
    lat = np.radians((dem["ymin"] + dem["ymax"]) / 2)
    width = (dem["xmax"] - dem["xmin"]) * 111320 * np.cos(lat)
    height = (dem["ymin"] - dem["ymax"]) * 110574
    xmin, xmax, ymin, ymax, zmin, zmax = grid.bounds
    assert xmax - xmin == pytest.approx(width, rel=0.01)
    assert ymax - ymin == pytest.approx(height, rel=0.01)
    assert (zmin, zmax) == (raw.min(), raw.max())


def test_jacksboro_vert_exag():
    g = load_jacksboro_terrain(vert_exag=2.5)
    np.testing.assert_allclose(g.points[:, 2], 2.5 * g.point_data["elevation"].astype(float))
    for bad in (0.0, -1.0, np.nan):
        with pytest.raises(InputError, match="vert_exag"):
            load_jacksboro_terrain(vert_exag=bad)


def test_birdseye_camera_is_south_east_and_above():
    bounds = (0.0, 1000.0, 0.0, 2000.0, 0.0, 100.0)
    pos, foc, up = terrain_birdseye_camera(bounds)
    # framed by the one rule: the box's projected corners centred, filling 85 %
    corners = np.array(np.meshgrid(*np.reshape(bounds, (3, 2)))).reshape(3, -1).T
    fill, dx, dy = framing(corners, pos, foc, up)
    assert fill == pytest.approx(0.85, abs=2e-3) and abs(dx) < 2e-3 and abs(dy) < 2e-3
    d = np.subtract(pos, foc)
    assert d[0] > 0 and d[1] < 0 and d[2] > 0
    assert d[0] == pytest.approx(-d[1])
    assert np.degrees(np.arctan2(d[2], np.hypot(d[0], d[1]))) == pytest.approx(35.0)
    assert up == (0.0, 0.0, 1.0)


# ---------------------------------------------------------------------------- run_demo
WINDOW = (160, 120)
# Scalar panels (scene channels and curvature maps) carry a colour bar in their units.
COLOUR_BAR = re.compile(
    r"^(nut|terrain)_(depth|sz|shade|world_[xyz]|scalars_\w+)\.png$|^fig15_curv"
)


REPORTED: list[str] = []


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    outdir = tmp_path_factory.mktemp("demo")
    return outdir, run_demo(outdir, window_size=WINDOW, report=REPORTED.append)


def test_run_demo_reports_every_step_as_it_starts_and_ends(demo):
    steps = [line for line in REPORTED if line.startswith("[")]
    n = int(steps[0].split("/")[1].split("]")[0])
    assert n >= 10 and len(steps) == 2 * n
    for k in range(1, n + 1):
        start, end = steps[2 * k - 2], steps[2 * k - 1]
        assert start.startswith(f"[{k}/{n}] ") and start.endswith(" ...")
        assert end.startswith(start[:-4] + ": ") and end.endswith(" s in all)")


def test_run_demo_files(demo):
    outdir, files = demo
    assert files[-1] == outdir / "index.html"
    assert sorted(files) == sorted(outdir.iterdir())  # nothing written beside them
    pngs = [p for p in files if p.suffix == ".png"]
    # per scene 9 channels + shade + montage, + terrain elevation; then the edge figures:
    # Fig. 3 (7 panels + montage) and Fig. 7 (8 panels + montage); then the contour figures:
    # Fig. 5 (5 panels + montage), Fig. 6 (3 + montage) and Fig. 11 (7 + montage); then the
    # terrain figure: topographic map, Fig. 12 cn, pr, sh, mx2, mx4, Fig. 13 sumi-e + montage;
    # the line-art figure: hidden lines dashed, thin, edges over the shade + montage; the
    # medical figure: Fig. 14 (a), (b), pr, cn, sh, bands, translucent skin + montage; the
    # surface analysis figure: Fig. 15 contours, reflection lines C1/C2, zebra C1/C2,
    # curvature C1/C2, isophotes and the NPR figure: 8 styles + montage
    assert len(pngs) == 2 * 11 + 1 + 8 + 9 + 6 + 4 + 8 + 9 + 4 + 8 + 9 + 9
    for p in files:
        assert p.is_file() and p.stat().st_size > 0
    contour_figures = ("fig5_", "fig6_", "fig11_")
    for p in pngs:
        with Image.open(p) as im:
            assert im.format == "PNG"
            if p.stem.endswith("montage"):
                assert im.size[0] > WINDOW[0] and im.size[1] > WINDOW[1]
            elif p.name.startswith(contour_figures):  # square, as large as the window allows
                assert im.size == (min(WINDOW), min(WINDOW))
            elif p.name == "fig12_topo.png":  # the plan-view map: one pixel per DEM cell
                assert im.size == (403, 344)
            elif p.name == "fig12_topo_labels.png":  # 1200 px wide: labels to read
                assert im.size == (1200, 1024)
            elif COLOUR_BAR.search(p.name):  # a scalar panel: its colour bar below
                assert im.size[0] == WINDOW[0] and im.size[1] > WINDOW[1], p.name
            else:
                assert im.size == WINDOW
    page = (outdir / "index.html").read_text(encoding="utf-8")
    referenced = set(re.findall(r'src="([^"]+)"', page))
    assert referenced == {p.name for p in pngs}
    for npz in (p for p in files if p.suffix == ".npz"):
        assert f'href="{npz.name}"' in page


def test_run_demo_medical_figure(demo):
    outdir, _ = demo
    page = (outdir / "index.html").read_text(encoding="utf-8")
    assert "Fig. 14" in page
    shaded = np.asarray(Image.open(outdir / "fig14_shaded.png"))
    enhanced = np.asarray(Image.open(outdir / "fig14_enhanced.png"))
    bone = shaded[..., :3].min(axis=2) < 250  # not white paper
    # the skeleton fills a good part of the picture, the same pixels in (a) and (b)
    assert 0.1 < bone.mean() < 0.7
    assert np.mean(bone == (enhanced[..., :3].min(axis=2) < 250)) > 0.97


def test_run_demo_translucent_and_hidden_line_figures(demo):
    """The translucent frog shows the skin's tint over the bone (the envelope covers it all)
    and the skin alone over paper; the nut's technical drawing
    has dashed ink (runs of ink and paper along its hidden lines) besides solid lines."""
    from sciviz_gbuf.recipes.medical import BONE, SKIN

    outdir, _ = demo
    rgb = np.asarray(Image.open(outdir / "fig14_translucent.png"))[..., :3] / 255.0
    drawn = rgb.min(axis=2) < 0.98
    assert 0.1 < drawn.mean() < 0.8
    hue = rgb[drawn] / np.maximum(rgb[drawn].max(axis=1, keepdims=True), 1e-6)
    skin = np.asarray(SKIN) / max(SKIN)
    bone = np.asarray(BONE) / max(BONE)
    # the skin's tint over the bone lies between the two hues; over paper it is a pale skin
    tinted = np.linalg.norm(hue - (0.35 * skin + 0.65 * bone), axis=1) < 0.06
    pale = 0.35 * skin * max(SKIN) * 0.8 + 0.65  # lit skin film over white
    film = np.linalg.norm(rgb[drawn] - pale, axis=1) < 0.08
    assert tinted.mean() > 0.02 and film.mean() > 0.02, (tinted.mean(), film.mean())
    dashed = np.asarray(Image.open(outdir / "lineart_dashed.png").convert("L")) / 255.0
    thin = np.asarray(Image.open(outdir / "lineart_thin.png").convert("L")) / 255.0
    ink = dashed < 0.5
    assert 0.005 < ink.mean() < 0.2
    # thin grey hidden lines: mid-grey pixels the dashed drawing lacks
    grey = (thin > 0.35) & (thin < 0.8)
    assert grey.sum() > 200


def test_run_demo_terrain_view(demo):
    outdir, _ = demo
    g = GBuffer.load(outdir / "terrain_gbuffer.npz")
    assert g.shape == (WINDOW[1], WINDOW[0])
    assert "elevation" in g.scalars
    # framed: the terrain fills the view but does not touch the image border
    border = np.concatenate([g.mask[0], g.mask[-1], g.mask[:, 0], g.mask[:, -1]])
    assert not border.any() and g.mask.mean() > 0.2
    # north away from the viewer: northing grows towards the top rows, and so does depth
    rows = np.nonzero(g.mask)[0]
    assert np.corrcoef(rows, g.world[..., 1][g.mask])[0, 1] < -0.5
    assert np.corrcoef(rows, g.depth[g.mask])[0, 1] < -0.5
    elev = g.scalars["elevation"][g.mask]
    np.testing.assert_allclose(g.world[..., 2][g.mask], 2.0 * elev, rtol=1e-4)


def test_run_demo_rejects_bad_window(tmp_path):
    with pytest.raises(InputError, match="window_size"):
        run_demo(tmp_path / "out", window_size=(0, 10))
    assert not (tmp_path / "out").exists()


def test_run_demo_edge_figures(demo):
    outdir, files = demo
    names = {p.name for p in files}
    for key in ("depth", "gradient", "second_order", "profile", "internal"):
        assert f"fig3_{key}.png" in names
    for key in ("a_shaded", "c_edges", "d_enhanced", "c2_edges", "d2_enhanced", "edgemap_c1"):
        assert f"fig7_{key}.png" in names
    page = (outdir / "index.html").read_text(encoding="utf-8")
    assert "Fig. 3" in page and "Fig. 7" in page
    # scenes; edge, line-art, contour, terrain, medical, surface and NPR figures
    assert page.count("Timings:") == 2 + 2 + 1 + 3 + 1 + 1 + 1 + 1

    def grey(name):
        with Image.open(outdir / name) as im:
            return np.asarray(im.convert("L")).astype(int)

    # Fig. 7 (c): mid-grey paper with white (convex) and black (concave, profile) lines
    c = grey("fig7_c_edges.png")
    assert np.median(c) in (127, 128) and c.max() == 255 and c.min() == 0
    # (c'): black lines only
    assert grey("fig7_c2_edges.png").max() <= 128
    # the literal profile image (Eq. 3) draws the outline of the nut: black ink on white
    prof = grey("fig3_profile.png")
    assert prof.min() == 0 and np.median(prof) == 255


def test_run_demo_contour_figures(demo):
    outdir, files = demo
    names = {p.name for p in files}
    for key in ("a_black", "b_grey", "f1_bilevel", "f1_linear", "f1_smooth"):
        assert f"fig5_{key}.png" in names
    for key in ("contours", "hatching", "hatching_exact"):
        assert f"fig6_{key}.png" in names
    for key in ("wz", "cn", "cn_unthinned", "majors", "sh", "bands", "mx3"):
        assert f"fig11_{key}.png" in names
    page = (outdir / "index.html").read_text(encoding="utf-8")
    for fig in ("Fig. 5", "Fig. 6", "Fig. 11"):
        assert f"Saito &amp; Takahashi 1990 {fig}" in page
    # captions from the recipe, and timings without a capture
    assert "(mx3) combination of the contours" in page
    assert "Timings: contour filters" in page and "Timings: hatching filters" in page

    def grey(name):
        with Image.open(outdir / name) as im:
            return np.asarray(im.convert("L")).astype(int)

    # Fig. 5 (a): black corners and white centre; (b): grey corners
    a, b = grey("fig5_a_black.png"), grey("fig5_b_grey.png")
    n = a.shape[0]
    c = n // 2
    assert a[:4, :4].max() < 30 and abs(b[:4, :4].mean() - 128) < 12
    assert a[c - 1 : c + 1, c - 1 : c + 1].min() > 200
    # Fig. 11: the map is in colour, the contour image black on white
    with Image.open(outdir / "fig11_mx3.png") as im:
        assert im.mode == "RGB"
    cn = grey("fig11_cn.png")
    assert cn.min() == 0 and np.median(cn) == 255


def test_run_demo_terrain_figure(demo):
    """The terrain figure: the plan-view map on the DEM grid, the bird's-eye panels with ink on
    coloured ground, the sumi-e mostly paper."""
    outdir, _ = demo

    def rgb(name):
        with Image.open(outdir / name) as im:
            return np.asarray(im.convert("RGB")).astype(int)

    topo = rgb("fig12_topo.png")
    assert len(np.unique(topo.reshape(-1, 3), axis=0)) > 50  # bands x relief x lines
    labelled = rgb("fig12_topo_labels.png")
    assert len(np.unique(labelled.reshape(-1, 3), axis=0)) > 50
    mx4, pr = rgb("fig12_mx4.png"), rgb("fig12_pr.png")
    ground = (pr < 250).any(axis=-1) | (mx4 != 255).any(axis=-1)
    assert 0.1 < ground.mean() < 0.95  # the terrain, framed, on white
    assert (pr.min(axis=-1) < 60).any()  # black profile lines
    sumi = rgb("fig12_sumi_e.png")
    assert np.median(sumi.mean(axis=-1)) > 200  # paper
    assert sumi.min() < 120  # and ink
    page = (outdir / "index.html").read_text(encoding="utf-8")
    assert "Fig. 12" in page and "sumi-e" in page


def test_with_colorbar_keeps_the_image_and_draws_the_map_and_ticks():
    from sciviz_gbuf.compose import with_colorbar

    v = np.linspace(0.0, 3.0, 200 * 150, dtype=np.float32).reshape(150, 200)
    rgb = colorize(v, cmap="viridis", vmin=0.0, vmax=3.0)
    out = with_colorbar(rgb, cmap="viridis", vmin=0.0, vmax=3.0, label="depth (m)")
    assert out.shape[1] == 200 and out.shape[0] > 150
    np.testing.assert_allclose(out[:150], np.round(rgb * 255) / 255, atol=1e-6)
    strip = out[150:]
    # the bar: a row whose colours run from viridis(0) on the left to viridis(1) on the right
    from matplotlib import colormaps

    lo, hi = np.asarray(colormaps["viridis"]([0.0, 1.0]))[:, :3]
    rows = [
        k
        for k, r in enumerate(strip)
        if np.abs(r[7] - lo).max() < 0.05 and np.abs(r[-8] - hi).max() < 0.05
    ]
    assert len(rows) >= 4, "no colour-map bar in the strip"
    bar = strip[rows[len(rows) // 2], 7:-7]
    t = np.linspace(0.0, 1.0, len(bar))
    np.testing.assert_allclose(bar, np.asarray(colormaps["viridis"](t))[:, :3], atol=0.05)
    # black text (ticks and label) below the bar
    below = strip[rows[-1] + 2 :]
    assert (below.max(axis=2) < 0.3).sum() > 30
    with pytest.raises(InputError, match="vmin"):
        with_colorbar(rgb, vmin=2.0, vmax=1.0, label="x")
    with pytest.raises(InputError, match="label"):
        with_colorbar(rgb, vmin=0.0, vmax=1.0, label=3)


_CHROMIUM = shutil.which("chromium")
_CHROMEDRIVER = shutil.which("chromedriver") or (
    "/usr/bin/chromedriver" if Path("/usr/bin/chromedriver").exists() else None
)


@pytest.mark.skipif(
    _CHROMIUM is None or _CHROMEDRIVER is None,
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver)",
)
def test_gallery_is_a_navigable_grid_in_a_real_browser(demo):
    """The gallery in Chromium at 1400x900: no horizontal overflow, a page a few screens tall
    (it was one 60,000 px column), every thumbnail a link to its full-size PNG, every nav link
    to a section of the page."""
    pytest.importorskip("selenium")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    outdir, _ = demo
    opts = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,900"):
        opts.add_argument(a)
    opts.binary_location = _CHROMIUM
    driver = webdriver.Chrome(options=opts, service=Service(_CHROMEDRIVER))
    try:
        driver.get((outdir / "index.html").as_uri())
        width = driver.execute_script("return document.documentElement.clientWidth")
        assert driver.execute_script("return document.documentElement.scrollWidth") <= width
        images = driver.execute_script(
            "return [...document.images].map(i => [i.getAttribute('src'), "
            "i.closest('a') && i.closest('a').getAttribute('href'), "
            "i.getBoundingClientRect().width, i.closest('figure').innerText]);"
        )
        assert len(images) > 60
        for src, href, shown, caption in images:
            assert href == src and (outdir / src).is_file()
            assert 150 <= shown <= 700, (src, shown)  # thumbnails, several per row
            assert caption.strip()
        height = driver.execute_script("return document.documentElement.scrollHeight")
        rows = driver.execute_script(
            "return new Set([...document.images].map(i => Math.round(i.getBoundingClientRect()"
            ".top + window.scrollY))).size"
        )
        assert rows < len(images) / 3  # a grid: at least three thumbnails a row on average
        assert height < 60 * 900 / 4, height
        targets = driver.execute_script(
            "return [...document.querySelectorAll('nav a')].map(a => a.getAttribute('href'));"
        )
        assert len(targets) >= 10
        for t in targets:
            assert driver.execute_script(f"return !!document.querySelector('{t}');"), t
    finally:
        driver.quit()


def test_numba_cache_is_cold_looks_where_numba_keeps_its_cache(tmp_path, monkeypatch):
    from sciviz_gbuf.apps.demo import numba_cache_is_cold

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert numba_cache_is_cold()
    deep = tmp_path / "work" / "sciviz_gbuf" / "filters"
    deep.mkdir(parents=True)
    (deep / "_edge_kernels._edge_pass_tasks-988.py311.nbi").write_bytes(b"")
    assert not numba_cache_is_cold()


@pytest.mark.parametrize("job", ["demo", "all", "topo"])
def test_cold_markers_name_cached_kernels_the_job_compiles(job):
    """A marker that names no cached numba kernel (a kernel renamed or turned into a Python
    wrapper) would make every run look like a first one."""
    import importlib

    from numba.core.caching import NullCache
    from numba.core.dispatcher import Dispatcher

    from sciviz_gbuf.apps.warmup import COLD_MARKERS

    module, name = COLD_MARKERS[job].split(".")
    kernel = getattr(importlib.import_module(f"sciviz_gbuf.filters.{module}"), name)
    assert isinstance(kernel, Dispatcher), f"{COLD_MARKERS[job]} is not a numba kernel"
    assert not isinstance(kernel._cache, NullCache), f"{COLD_MARKERS[job]} is not cache=True"
