"""Vector contours and label text in print layouts (``vector=True``, the PDF default): the
lines are the map's (within the generalisation's tolerance of the exact contours), cut under
every label and where minors crowd, drawn where the raster map draws its ink, and the PDF
holds the labels as text over one raster image."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from PIL import Image
from scipy.spatial import cKDTree

import sciviz_gbuf.datasets
from sciviz_gbuf.filters import contour_polylines
from sciviz_gbuf.readers import DEM
from sciviz_gbuf.recipes._resample import map_grid
from sciviz_gbuf.recipes.labels import PAD_FONTS, labels_of_grid
from sciviz_gbuf.recipes.layout import map_lines, map_page, write_map_page

pypdf = pytest.importorskip("pypdf")
pdfium = pytest.importorskip("pypdfium2")


@pytest.fixture(scope="module")
def dem():
    return sciviz_gbuf.datasets.load_jacksboro_dem()


@pytest.fixture(scope="module")
def grid(dem):
    return map_grid(dem, scale="1:50000", dpi=100)


def _densified(points: np.ndarray, step: float = 0.1) -> np.ndarray:
    """Points along the polyline every ``step`` of its arc length (and its vertices)."""
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])
    s = np.union1d(np.arange(0.0, arc[-1], step), arc)
    return np.column_stack([np.interp(s, arc, points[:, k]) for k in (0, 1)])


@settings(max_examples=80, deadline=None)
@given(
    hnp.arrays(
        np.float64, st.tuples(st.integers(2, 40), st.just(2)), elements=st.floats(-100, 100)
    ),
    st.floats(0.05, 20.0),
)
def test_densify_keeps_the_vertices_and_the_step(points, step):
    """The page's resampling of a line: its vertices in order, no gap over ``step``, every
    new point on its segment."""
    from sciviz_gbuf.recipes.layout import _densify

    out = _densify(points, step)
    seg = np.hypot(*np.diff(points, axis=0).T)
    n = np.maximum(np.ceil(seg / step).astype(int), 1)
    at = np.concatenate([[0], np.cumsum(n)])  # where each vertex lands
    np.testing.assert_allclose(out[at], points, rtol=0, atol=1e-9)
    gaps = np.hypot(*np.diff(out, axis=0).T)
    assert np.all(gaps <= step * (1 + 1e-9) + 1e-9)
    for k in range(len(seg)):  # between its two vertices, on the straight segment
        a, b, part = points[k], points[k + 1], out[at[k] : at[k + 1] + 1]
        cross = (b - a)[0] * (part - a)[:, 1] - (b - a)[1] * (part - a)[:, 0]
        assert np.all(np.abs(cross) <= 1e-6 * (1 + seg[k]) * (1 + np.abs(part - a).max()))


def test_vector_lines_follow_the_exact_contours(grid):
    """Generalised lines move at most 0.6 px from the exact ones (their tolerance band)."""
    heights = np.where(grid.mask, grid.heights, np.nan)
    lines = map_lines(grid, interval=20.0, major_interval=100.0)
    exact = contour_polylines(heights, interval=20.0)
    tree = cKDTree(np.concatenate([_densified(p.points) for p in exact]))
    pts = np.concatenate([p for p, _ in lines])
    dist, _ = tree.query(pts)
    # the smoothed heights stay in a 0.6 px tolerance band; traced, the lines stay within 1 px
    assert len(lines) > 20 and np.percentile(dist, 99) < 0.75 and np.percentile(dist, 99.9) < 1.0
    exact_lines = map_lines(grid, interval=20.0, major_interval=100.0, generalize=False)
    d2, _ = tree.query(np.concatenate([p for p, _ in exact_lines]))
    assert d2.max() < 0.06  # the same tracer: on the exact lines


def test_majors_and_crowded_minors_on_ramps():
    """A ramp whose minors would be 2 px apart draws only its majors; one with minors 10 px
    apart draws every minor whole."""
    j = np.mgrid[0:60, 0:200][1].astype(np.float32)
    # metres per pixel, the majors and minors of a 10 m / 50 m map on heights 5 + rise * j
    for rise, n_major, n_minor in ((5.0, 19, 0), (1.0, 4, 16)):
        z = j * rise + 5.0  # no level on the grid's edge
        d = DEM(heights=z, mask=np.ones(z.shape, bool), crs=None,
                transform=(0.0, 1.0, 0.0, 60.0, 0.0, -1.0), pixel_size=(1.0, 1.0),
                geographic=False)  # fmt: skip
        lines = map_lines(d, interval=10.0, major_interval=50.0)
        majors = [p for p, m in lines if m]
        minors = [p for p, m in lines if not m]
        assert (len(majors), len(minors)) == (n_major, n_minor)
        assert all(np.ptp(p[:, 1]) > 58 for p in majors + minors)  # whole, top to bottom


def test_no_line_under_a_label(grid):
    labels = labels_of_grid(grid, None, None, 12.0, 300.0)
    assert len(labels) >= 3
    lines = map_lines(grid, labels=labels)
    pts = np.concatenate([p for p, _ in lines])
    for lab in labels:
        a = math.radians(lab.angle)
        d = np.array([math.cos(a), -math.sin(a)])  # baseline, image coordinates
        n = np.array([-d[1], d[0]])
        rel = pts - (lab.x, lab.y)
        u, v = rel @ d, rel @ n
        inside = (np.abs(u) < lab.width / 2 - 0.5) & (np.abs(v) < lab.height / 2 - 0.5)
        assert not inside.any(), lab


def _ink(rgb: np.ndarray) -> np.ndarray:
    """Dark brown contour ink (and label text): darker than any band colour."""
    return rgb.astype(float).sum(axis=-1) < 250


def test_vector_ink_lies_where_the_raster_map_draws_it(tmp_path, dem):
    """The page rendered with vector lines and with the map's own ink: the ink overlaps best
    at zero shift (the vectors are placed to the pixel), and mostly coincides."""
    kw = {"dpi": 100, "title": "T", "labels": False}
    raster = tmp_path / "raster.png"
    vector = tmp_path / "vector.png"
    write_map_page(raster, dem, **kw)
    write_map_page(vector, dem, vector=True, **kw)
    a = _ink(np.asarray(Image.open(raster).convert("RGB")))
    b = _ink(np.asarray(Image.open(vector).convert("RGB")))
    fig = map_page(dem, **kw)
    img, (x0, y0), _ = fig.sciviz_map
    ih, iw = img.shape[:2]
    top = a.shape[0] - y0 - ih
    win = (slice(top + 3, top + ih - 3), slice(x0 + 3, x0 + iw - 3))
    scores = {}
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            shifted = np.roll(b, (dy, dx), axis=(0, 1))
            scores[dy, dx] = (a[win] & shifted[win]).sum() / max(a[win].sum(), 1)
    assert max(scores, key=scores.get) == (0, 0), scores
    assert scores[0, 0] > 0.6


def test_pdf_holds_labels_as_text_over_one_image(tmp_path, dem):
    path = tmp_path / "map.pdf"
    write_map_page(path, dem, dpi=100, title="Jacksboro", credit="USGS 3DEP")
    data = path.read_bytes()
    assert data.startswith(b"%PDF") and data.count(b"/Subtype /Image") == 1
    assert b"/FontFile2" in data  # TrueType embedded: text, not outlines or pixels
    text = pypdf.PdfReader(path).pages[0].extract_text()
    fig = map_page(dem, dpi=100, title="Jacksboro", credit="USGS 3DEP", vector=True)
    texts = [t.get_text() for t in fig.texts]
    labels = [t for t in texts if t.replace("\u2212", "").isdigit()]
    assert len(labels) >= 3
    for word in ["Jacksboro", "USGS 3DEP", "Contour interval", *labels]:
        assert word in text, word
    # the rasterised PDF shows the map: not blank, the labels' ink near their places
    page = pdfium.PdfDocument(str(path))[0].render(scale=100 / 72).to_pil().convert("RGB")
    rgb = np.asarray(page)
    assert (rgb.std(axis=(0, 1)) > 10).all()


@pytest.mark.parametrize("angle", [0.0, 33.0, -53.3, 90.0, 126.0, -170.0])
@pytest.mark.parametrize("text", ["500", "\u22121250", "20"])
def test_label_text_is_centred_on_its_placement_as_in_the_raster_map(text, angle):
    """The vector text (matplotlib) and the raster text (PIL) of one label on a blank page:
    their ink has one centroid (within 0.6 px: two rasterisers), and its box in the text's
    frame is centred on the label's (x, y) within a pixel."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from sciviz_gbuf.recipes.labels import ContourLabel, label_ink, label_options
    from sciviz_gbuf.recipes.layout import _draw_vectors

    dpi, size = 150, 120
    font_px, _ = label_options(None, None, dpi)
    width, height = _label_box(text, font_px)
    lab = ContourLabel(text, 0.0, 60.3, 58.6, angle, width, height, 0.0, 0.0, angle)
    raster = label_ink([lab], (size, size), font_px)
    fig = Figure(figsize=(size / dpi, size / dpi), dpi=dpi)
    _draw_vectors(fig, [], [lab], origin=(0, size), dpi=dpi, map_options={}, font_px=font_px)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    vector = 1.0 - np.asarray(canvas.buffer_rgba())[..., :3].mean(axis=-1) / 255.0
    centroids = []
    for ink in (raster, vector):
        rows, cols = np.nonzero(ink > 0.02)
        w = ink[rows, cols]
        centroids.append((np.average(cols, weights=w), np.average(rows, weights=w)))
        # the label's (x, y) is the centre of its ink's box, in the text's own frame
        r, c = np.nonzero(ink > 0.25)
        a = math.radians(angle)
        u = (c - lab.x) * math.cos(a) - (r - lab.y) * math.sin(a)  # along the baseline
        v = (c - lab.x) * math.sin(a) + (r - lab.y) * math.cos(a)  # across it
        centre = ((u.min() + u.max()) / 2, (v.min() + v.max()) / 2)
        assert np.hypot(*centre) < 1.0, (centre, lab)
    assert np.hypot(*np.subtract(*centroids)) < 0.6, centroids


def _label_box(text, font_px):
    """The box of a label as the placement sizes it: the text's ink (PIL, DejaVu Sans at 4x)
    plus a margin of PAD_FONTS font sizes all round."""
    from pathlib import Path

    import matplotlib
    from PIL import ImageFont

    path = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
    left, top, right, bottom = ImageFont.truetype(str(path), round(font_px * 4)).getbbox(text)
    pad = 2 * PAD_FONTS * font_px
    return (right - left) / 4 + pad, (bottom - top) / 4 + pad
