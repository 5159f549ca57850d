"""``-o out.svg`` / ``out.pdf`` of the edges, mesh, patches and topo commands (issue 24): the
files a user gets parse, hold the right kinds of strokes, and the contour strokes of a map lie
on the traced contours of their own level; bad requests fail in one line, leaving nothing."""

from __future__ import annotations

import itertools
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from scipy.spatial import cKDTree

import sciviz_gbuf.datasets
from sciviz_gbuf.filters import contour_polylines
from sciviz_gbuf.filters.contours import generalized_field
from sciviz_gbuf.recipes import topographic_picture
from sciviz_gbuf.recipes._intervals import contour_intervals
from tests.helpers.cli import assert_clean_failure, checksums, run_cli

NS = {"s": "http://www.w3.org/2000/svg"}


def _groups(path) -> dict[str, list]:
    root = ET.parse(path).getroot()
    return {g.get("class"): list(g) for g in root.findall("s:g", NS)}


def _points(el) -> np.ndarray:
    return np.array([[float(v) for v in p.split(",")] for p in el.get("points").split()]) - 0.5


def _densified(points: np.ndarray, step: float = 0.05) -> np.ndarray:
    out = [points[:1]]
    for a, b in itertools.pairwise(points):
        n = max(1, math.ceil(np.hypot(*(b - a)) / step))
        out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(out)


@pytest.fixture(scope="module")
def stl(shared_data):
    return shared_data / "meshes" / "vtkdata_42400-IDGH.stl"


def test_edges_svg_and_pdf(tmp_path, stl):
    svg = tmp_path / "part.svg"
    r = run_cli(["edges", stl, "-o", svg, "--size", "480x360"])
    assert r.returncode == 0, r.stderr
    groups = _groups(svg)
    assert set(groups) == {"profile", "crease"}
    assert 10 < sum(map(len, groups.values())) < 200
    pdf = tmp_path / "part.pdf"
    r = run_cli(["edges", stl, "-o", pdf, "--size", "480x360", "--background", "shade"])
    assert r.returncode == 0, r.stderr
    pypdf = pytest.importorskip("pypdf")
    (page,) = pypdf.PdfReader(pdf).pages
    assert [float(v) for v in page.mediabox] == [0, 0, 480, 360]
    (image,) = page.images  # the shade, embedded once
    assert image.image.size == (480, 360)


def test_mesh_lines_svg_and_a_raster_style_refused(tmp_path, stl):
    svg = tmp_path / "drawing.svg"
    r = run_cli(["mesh", stl, "--style", "lines", "-o", svg, "--size", "480x360"])
    assert r.returncode == 0, r.stderr
    drawn = _groups(svg)["drawing"]
    assert len(drawn) > 50
    widths = {float(e.get("stroke-width")) for e in drawn}
    assert len(widths) > 3  # profiles and tone-modulated hatching: many widths
    out = tmp_path / "gooch.svg"
    r = run_cli(["mesh", stl, "--style", "gooch", "-o", out])
    assert "edges" in assert_clean_failure(r, names="--output", outputs=[out])


def test_patches_svg_has_its_lines_as_strokes(tmp_path, shared_data):
    svg = tmp_path / "teapot.svg"
    bpt = shared_data / "patches" / "teapot.bpt"
    r = run_cli(["patches", bpt, "-o", svg, "--size", "400x300", "--mode", "isophote"])
    assert r.returncode == 0, r.stderr
    groups = _groups(svg)
    assert len(groups["isophote"]) > 5 and len(groups["profile"]) >= 1
    root = ET.parse(svg).getroot()
    assert len(root.findall("s:image", NS)) == 1  # the shaded surface under the lines


def test_topo_svg_contours_lie_on_the_traced_contours_of_their_level(tmp_path):
    """--exact-contours: every vertex within 0.25 px of contour_polylines' line of the same
    level (the issue's acceptance); the labels are text."""
    svg = tmp_path / "map.svg"
    r = run_cli(["topo", "-o", svg, "--exact-contours", "--labels", "--contours", "20,100"])
    assert r.returncode == 0, r.stderr
    dem = sciviz_gbuf.datasets.load_jacksboro_dem()
    heights = np.where(dem.mask, dem.heights, np.nan)
    groups = _groups(svg)
    assert len(groups["contour"]) > 20 and len(groups["contour-major"]) > 5
    assert len(groups["labels"]) >= 3
    assert all(t.text.strip().lstrip("-").isdigit() for t in groups["labels"])
    _assert_on_levels(groups["contour"] + groups["contour-major"], heights, 20.0)


def _assert_on_levels(elements, field, interval) -> None:
    lines = contour_polylines(field, interval=interval)
    trees = {}
    for ln in lines:
        trees.setdefault(round(ln.level, 6), []).append(_densified(ln.points))
    trees = {k: cKDTree(np.concatenate(v)) for k, v in trees.items()}
    worst = 0.0
    for el in elements:
        level = round(float(el.get("data-level")), 6)
        dist, _ = trees[level].query(_points(el))
        worst = max(worst, float(dist.max()))
    assert worst <= 0.25, worst


def test_generalised_map_strokes_lie_on_the_generalised_contours():
    """The default (generalised) lines: on the contours of the smoothed field they are traced
    on, level by level."""
    dem = sciviz_gbuf.datasets.load_jacksboro_dem()
    pic = topographic_picture(dem, interval=20.0, major_interval=100.0)
    heights = np.where(dem.mask, dem.heights, np.nan).astype(np.float32)
    _lo, _hi, minor, _major = contour_intervals(heights, 20.0, 100.0)
    field, _ = generalized_field(heights, interval=minor)

    class _El:
        def __init__(self, s):
            self.s = s

        def get(self, key):
            if key == "data-level":
                return self.s.level
            return " ".join(f"{x + 0.5},{y + 0.5}" for x, y in self.s.points)

    assert {s.kind for s in pic.strokes} == {"contour", "contour-major"}
    _assert_on_levels([_El(s) for s in pic.strokes], field, 20.0)
    assert pic.background.shape[:2] == heights.shape


def test_topo_pdf_has_labels_as_text(tmp_path):
    pypdf = pytest.importorskip("pypdf")
    pdf = tmp_path / "map.pdf"
    r = run_cli(["topo", "-o", pdf, "--labels", "--size", "800"])
    assert r.returncode == 0, r.stderr
    (page,) = pypdf.PdfReader(pdf).pages
    words = page.extract_text().split()
    assert len(words) >= 10 and all(w.lstrip("-").isdigit() for w in words)


@pytest.mark.parametrize(
    ("args", "names"),
    [
        (["topo", "--chunks", "256", "-o", "{out}"], "--output"),
        (["topo", "--geotiff", "{tmp}/g.tif", "-o", "{out}"], "--geotiff"),
        (["topo", "--overview", "{tmp}/o.png", "-o", "{out}"], "--overview"),
        (["edges", "{stl}", "-o", "{tmp}/e.png", "--background", "shade"], "--background"),
        (["edges", "{stl}", "-o", "{tmp}/e.eps"], "--output"),
        (["edges", "{stl}", "-o", "{tmp}/missing/e.svg"], "--output"),
        (["patches", "{tmp}/none.bpt", "-o", "{out}"], "none.bpt"),
    ],
)
def test_bad_vector_requests_fail_in_one_line(tmp_path, stl, args, names):
    out = tmp_path / "m.svg"
    fill = {"out": out, "tmp": tmp_path, "stl": stl}
    before = checksums([stl])
    r = run_cli([a.format(**fill) for a in args])
    assert_clean_failure(r, names=names, outputs=[out, tmp_path / "e.png", tmp_path / "e.svg"],
                         inputs=before)  # fmt: skip


def test_edges_hidden_lines_png_and_svg(tmp_path, stl):
    png = tmp_path / "part.png"
    r = run_cli(["edges", stl, "-o", png, "--size", "320x240", "--hidden", "dashed"])
    assert r.returncode == 0, r.stderr
    svg = tmp_path / "part.svg"
    r = run_cli(["edges", stl, "-o", svg, "--size", "320x240", "--hidden", "dashed",
                 "--layers", "3"])  # fmt: skip
    assert r.returncode == 0, r.stderr
    hidden = _groups(svg)["hidden"]
    assert len(hidden) > 5 and all(e.get("stroke-dasharray") == "6 3" for e in hidden)
    out = tmp_path / "x.png"
    for args, name in ((["--layers", "3"], "--layers"), (["--hidden", "dotted"], "--hidden"),
                       (["--hidden", "thin", "--layers", "9"], "--layers")):  # fmt: skip
        r = run_cli(["edges", stl, "-o", out, *args])
        assert_clean_failure(r, names=name, outputs=[out])


def test_ct_translucent_skin(tmp_path, shared_data):
    out = tmp_path / "ct.png"
    src = shared_data / "ct" / "dcm_qa_ct_Philips_phantom_5mm"
    before = checksums([src])
    r = run_cli(["ct", src, "-o", out, "--translucent", "skin", "--iso", "bone",
                 "--size", "200x200", "--background", "white"])  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "translucent skin" in r.stdout and out.is_file()
    assert checksums([src]) == before
    bad = tmp_path / "bad.png"
    r = run_cli(["ct", src, "-o", bad, "--translucent", "skin", "--opacity", "1.5"])
    assert_clean_failure(r, names="--opacity", outputs=[bad])
    r = run_cli(["ct", src, "-o", bad, "--translucent", "skin", "--save-gbuffer",
                 tmp_path / "g.npz"])  # fmt: skip
    assert_clean_failure(r, names="--save-gbuffer", outputs=[bad, tmp_path / "g.npz"])
