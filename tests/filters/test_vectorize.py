"""Line vectorisation (issue 24, item 1): strokes from line images, against analytic lines and
against the object-space truth of tests/helpers/edge_truth.py.

The strokes are rasterised back by an independent helper (tests/helpers/stroke_raster.py: the
pixels their centre lines pass through) and scored like the raster edges of
test_edges_acceptance.py, at the issue's bar: precision and recall >= 0.95 at 1.5 px.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import sciviz_gbuf as sg
from sciviz_gbuf.datasets import load_nut
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import crease_edges, edge_strokes, profile_edges, simplify, vectorize
from tests.filters.test_edges_acceptance import view
from tests.filters.test_edges_organic import _organic
from tests.helpers.edge_truth import precision_recall, visible_edge_truth
from tests.helpers.stroke_raster import rasterize


def _segment_ink(shape, a, b, width, samples=8) -> np.ndarray:
    """Antialiased ink of a straight band ``width`` px wide from ``a`` to ``b`` (x, y): the
    fraction of each pixel's ``samples``^2 sub-samples within width/2 of the segment."""
    h, w = shape
    s = (np.arange(samples) + 0.5) / samples - 0.5
    yy, xx = np.mgrid[:h, :w].astype(np.float64)
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    ink = np.zeros(shape)
    for oy in s:
        for ox in s:
            px, py = xx + ox - a[0], yy + oy - a[1]
            t = np.clip((px * d[0] + py * d[1]) / (d @ d), 0, 1)
            dist = np.hypot(px - t * d[0], py - t * d[1])
            ink += dist <= width / 2
    return (ink / samples**2).astype(np.float32)


def _ring_ink(shape, centre, radius, width, samples=8) -> np.ndarray:
    h, w = shape
    s = (np.arange(samples) + 0.5) / samples - 0.5
    yy, xx = np.mgrid[:h, :w].astype(np.float64)
    ink = np.zeros(shape)
    for oy in s:
        for ox in s:
            r = np.hypot(xx + ox - centre[0], yy + oy - centre[1])
            ink += np.abs(r - radius) <= width / 2
    return (ink / samples**2).astype(np.float32)


def _distance_to_line(pts, a, b) -> np.ndarray:
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = (b - a) / np.linalg.norm(b - a)
    rel = pts - a
    return np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0])


@pytest.mark.parametrize("width", [1.0, 1.6, 3.0])
def test_an_antialiased_line_is_one_straight_stroke_on_its_centre(width):
    a, b = (10.3, 12.7), (110.6, 47.2)
    ink = _segment_ink((64, 128), a, b, width)
    strokes = vectorize(ink, kind="test")
    assert len(strokes) == 1
    s = strokes[0]
    assert s.kind == "test" and not s.closed
    assert len(s.points) <= 4  # a straight line needs two vertices (simplified within 0.25)
    assert _distance_to_line(s.points, a, b).max() < 0.15
    length = np.hypot(*(s.points[-1] - s.points[0]))
    assert length > np.hypot(100.3, 34.5) - width - 2
    assert abs(s.width - width) < 0.15 * width, s.width  # the ink integrated across


def test_an_aliased_staircase_is_straightened_within_half_a_pixel():
    """A 0/1 line (no sub-pixel information): its vertices lie within half a pixel of the true
    line (the staircase's bound) and few remain; the staircase itself would need one vertex
    per step."""
    a, b = (5.0, 20.2), (150.0, 31.4)  # slope 0.077: steps every 13 px
    ink = (_segment_ink((50, 160), a, b, 1.0, samples=1) > 0).astype(np.float32)
    (s,) = vectorize(ink)
    assert _distance_to_line(s.points, a, b).max() <= 0.5
    assert len(s.points) <= 6, len(s.points)


def test_a_ring_is_one_closed_stroke_on_its_radius():
    ink = _ring_ink((100, 100), (50.3, 49.6), 30.2, 1.5)
    (s,) = vectorize(ink)
    assert s.closed
    r = np.hypot(s.points[:, 0] - 50.3, s.points[:, 1] - 49.6)
    assert np.abs(r - 30.2).max() < 0.25
    assert 12 <= len(s.points) <= 60


def test_junctions_join_straight_continuations_only():
    """A cross is two strokes (each bar straight through the crossing), a T two (the bar and
    the stem ending on it), a Y of three 120-degree arms three."""
    shape = (120, 120)
    cross = np.maximum(_segment_ink(shape, (10, 60), (110, 60), 1.5),
                       _segment_ink(shape, (60, 10), (60, 110), 1.5))  # fmt: skip
    strokes = vectorize(cross)
    assert len(strokes) == 2
    for s in strokes:  # each bar spans the picture
        assert np.ptp(s.points, axis=0).max() > 95
    tee = np.maximum(_segment_ink(shape, (10, 30), (110, 30), 1.5),
                     _segment_ink(shape, (60, 30), (60, 110), 1.5))  # fmt: skip
    bar, stem = vectorize(tee)
    assert np.ptp(bar.points[:, 0]) > 95 and np.ptp(stem.points[:, 1]) > 75
    assert np.abs(stem.points[:, 1].min() - 30) < 1.0  # the stem reaches the bar
    c = np.array([60.0, 60.0])
    arms = [c + 50 * np.array([np.cos(t), np.sin(t)]) for t in np.radians([90, 210, 330])]
    y = np.max([_segment_ink(shape, c, e, 1.5) for e in arms], axis=0)
    strokes = vectorize(y)
    assert len(strokes) == 3
    for s in strokes:  # each arm ends at the centre
        assert min(np.hypot(*(s.points[0] - c)), np.hypot(*(s.points[-1] - c))) < 1.5


def test_signed_ink_nan_and_thresholds():
    ink = _segment_ink((40, 80), (5, 20), (75, 20), 1.0)
    (pos,) = vectorize(ink)
    (neg,) = vectorize(-ink)  # a concave crease image: by magnitude
    np.testing.assert_allclose(pos.points, neg.points)
    ink[0, 0] = np.nan
    assert len(vectorize(ink)) == 1
    assert vectorize(ink * 0.2) == []  # below the threshold
    assert vectorize(np.zeros((5, 5))) == []
    assert len(vectorize(ink, width=2.5)) == 1 and vectorize(ink, width=2.5)[0].width == 2.5
    with pytest.raises(InputError, match="lines"):
        vectorize(np.zeros(5))
    with pytest.raises(InputError, match="lines"):
        vectorize(np.array([["a"]]))
    with pytest.raises(InputError, match="threshold"):
        vectorize(ink, threshold=0)
    with pytest.raises(InputError, match="tolerance"):
        vectorize(ink, tolerance=-1)
    with pytest.raises(InputError, match="width"):
        vectorize(ink, width=1000)


@settings(max_examples=60, deadline=None)
@given(pts=arrays(np.float64, st.tuples(st.integers(2, 40), st.just(2)),
                  elements=st.floats(-100, 100)),
       tol=st.floats(0, 5))  # fmt: skip
def test_simplify_keeps_every_vertex_within_the_tolerance(pts, tol):
    kept = simplify(pts, tol)
    assert np.array_equal(kept[0], pts[0]) and np.array_equal(kept[-1], pts[-1])
    # every original vertex lies within tol of the simplified polyline
    for p in pts:
        best = np.inf
        for a, b in itertools.pairwise(kept):
            d = b - a
            t = 0.0 if d @ d == 0 else np.clip((p - a) @ d / (d @ d), 0, 1)
            best = min(best, float(np.hypot(*(p - a - t * d))))
        assert best <= tol + 1e-9


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    img=arrays(
        np.float32,
        st.tuples(st.integers(1, 24), st.integers(1, 24)),
        elements=st.sampled_from([0.0, 0.0, 1.0, 0.5, np.nan, np.inf, -1.0]),
    )
)
def test_odd_images_give_strokes_inside_the_picture(img):
    for s in vectorize(img, min_length=0):
        assert np.isfinite(s.points).all() and len(s.points) >= 2
        assert (s.points >= -1).all() and (s.points[:, 0] <= img.shape[1]).all()
        assert (s.points[:, 1] <= img.shape[0]).all()
        assert 0 < s.width <= 64


# ----------------------------------------------------------------- against object-space truth
VIEWS = [(35.0, 30.0), (-120.0, 55.0), (200.0, -25.0)]


def _stl(shared):
    return pv.read(shared / "meshes" / "vtkdata_42400-IDGH.stl")


@pytest.fixture(scope="module")
def cad(shared_data):
    return {"cube": pv.Cube().triangulate(), "nut": load_nut(), "cad_stl": _stl(shared_data)}


def _score(mesh, truth_mesh, azel, size, supersample):
    camera = view(truth_mesh, *azel)
    gb = sg.capture(mesh, window_size=size, camera=camera, supersample=supersample)
    plain = gb if supersample == 1 else sg.capture(mesh, window_size=size, camera=camera)
    truth = visible_edge_truth(truth_mesh, plain, feature_angle=30.0)["all"]
    strokes = edge_strokes(gb)
    drawn = rasterize(strokes, truth.shape)
    return strokes, precision_recall(drawn, truth, tol_px=1.5)


@pytest.mark.parametrize("supersample", [1, 2])
@pytest.mark.parametrize("azel", VIEWS, ids=[f"az{a:g}_el{e:g}" for a, e in VIEWS])
@pytest.mark.parametrize("name", ["cube", "nut", "cad_stl"])
def test_vector_edges_match_object_space_truth(cad, name, azel, supersample):
    mesh = cad[name]
    strokes, (precision, recall) = _score(mesh, mesh, azel, (512, 512), supersample)
    assert precision >= 0.95 and recall >= 0.95, (precision, recall, len(strokes))
    kinds = {s.kind for s in strokes}
    assert kinds <= {"profile", "crease"} and "profile" in kinds
    if name == "cube":
        # 9 (or 7 seen edge-on) visible edges: the outline is one closed stroke, the inner
        # edges meeting at the front corner three more
        assert len(strokes) <= 9 + 3, len(strokes)
        assert sum(s.closed for s in strokes) == 1


@pytest.mark.parametrize("azel", VIEWS, ids=[f"az{a:g}_el{e:g}" for a, e in VIEWS])
@pytest.mark.parametrize("name", ["noisy_sphere", "noisy_torus", "decimated_torus"])
def test_vector_edges_of_organic_meshes_match_their_smooth_shape(name, azel):
    """As test_edges_organic.py's raster check (320 x 240, no supersampling: supersampled,
    the noisy sphere's raster creases themselves fall to precision ~0.84)."""
    mesh, smooth = _organic()[name]
    strokes, (precision, recall) = _score(mesh, smooth, azel, (320, 240), 1)
    assert precision >= 0.95 and recall >= 0.95, (precision, recall, len(strokes))


def test_a_wrong_stroke_fails_the_same_check(cad):
    """The check can fail: strokes shifted by 3 px lose both numbers."""
    mesh = cad["cad_stl"]
    gb = sg.capture(mesh, window_size=(512, 512), camera=view(mesh, *VIEWS[0]))
    truth = visible_edge_truth(mesh, gb, feature_angle=30.0)["all"]
    shifted = [s._replace(points=s.points + 3.0) for s in edge_strokes(gb)]
    precision, recall = precision_recall(rasterize(shifted, truth.shape), truth, tol_px=1.5)
    assert precision < 0.5 and recall < 0.5


def test_vector_edges_agree_with_the_raster_edges(cad):
    mesh = cad["nut"]
    gb = sg.capture(mesh, window_size=(400, 300), camera=view(mesh, *VIEWS[1]), supersample=2)
    raster = (profile_edges(gb) >= 0.5) | (crease_edges(gb) >= 0.5)
    drawn = rasterize(edge_strokes(gb), raster.shape)
    precision, recall = precision_recall(drawn, raster, tol_px=1.5)
    assert precision >= 0.97 and recall >= 0.97


def test_a_one_pixel_hole_in_a_patch_is_no_stroke_of_one_point():
    """Found by hypothesis in CI: the skeleton of a patch of ink around a one-pixel hole is a
    ring within the tolerance of a point; it was a closed stroke of one vertex."""
    img = np.ones((4, 15), np.float32)
    img[2, 11] = 0.0
    for s in vectorize(img, min_length=0):
        assert len(s.points) >= 2
