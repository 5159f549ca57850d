"""Hidden lines (issue 24 item 3): the edges of the surfaces behind, from multi-layer
G-buffers, drawn dashed or thin, raster and vector. A cube seen through its own front faces
has exactly its 3 hidden edges (those between two back faces), computed here from the cube's
corners and the camera alone; the dashes run on along each stroke."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import pyvista as pv
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import Stroke, dash_pieces, draw_strokes, hidden_edges
from sciviz_gbuf.recipes import technical_drawing, technical_drawing_image, write_vector
from tests.helpers.edge_truth import precision_recall

VIEWS = {
    "front-right-up": [(3.0, 2.2, 1.8), (0, 0, 0), (0, 0, 1)],
    "left-low": [(-2.6, 3.1, -1.7), (0, 0, 0), (0, 0, 1)],
    "behind-above": [(-1.9, -3.3, 2.4), (0, 0, 0), (0, 0, 1)],
}
SIZE = (400, 320)


def _cube_hidden_segments(eye: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """World segments of the unit-half cube's edges between two faces facing away from
    ``eye`` (perspective): its hidden edges."""
    corners = np.array(list(itertools.product((-0.5, 0.5), repeat=3)))
    faces = [(axis, sign) for axis in range(3) for sign in (-0.5, 0.5)]
    away = {(a, s): (eye[a] - s) * np.sign(s) < 0 for a, s in faces}  # eye behind the face
    out = []
    for i, j in itertools.combinations(range(8), 2):
        diff = np.flatnonzero(corners[i] != corners[j])
        if len(diff) != 1:
            continue
        shared = [(a, corners[i][a]) for a in range(3) if a != diff[0]]
        if all(away[f] for f in shared):
            out.append((corners[i], corners[j]))
    return out


def _project(cam, p: np.ndarray, k: int) -> np.ndarray:
    """World point -> output pixel (x col, y row) of a capture supersampled ``k`` times."""
    w, h = cam.window_size
    c = cam.world_to_clip() @ np.r_[p, 1.0]
    ndc = c[:3] / c[3]
    buf = np.array([(ndc[0] + 1) * 0.5 * w - 0.5, (1 - ndc[1]) * 0.5 * h - 0.5])
    return (buf + 0.5) / k - 0.5


def _truth(gb) -> tuple[np.ndarray, list]:
    cam, k = gb.camera, gb.supersample
    segs = [(_project(cam, a, k), _project(cam, b, k)) for a, b in
            _cube_hidden_segments(np.asarray(cam.position))]  # fmt: skip
    img = np.zeros(gb.output_shape, bool)
    for a, b in segs:
        t = np.linspace(0, 1, 4000)[:, None]
        xy = np.rint(a + t * (b - a)).astype(int)
        img[xy[:, 1], xy[:, 0]] = True
    return img, segs


def _seg_distance(p: np.ndarray, segs) -> np.ndarray:
    best = np.full(len(p), np.inf)
    for a, b in segs:
        d = b - a
        t = np.clip((p - a) @ d / (d @ d), 0, 1)
        best = np.minimum(best, np.hypot(*(p - a - t[:, None] * d).T))
    return best


@pytest.mark.parametrize("supersample", [1, 2])
@pytest.mark.parametrize("view", list(VIEWS))
def test_a_cube_has_exactly_its_three_hidden_edges(view, supersample):
    cube = pv.Cube().triangulate()
    gb = sg.capture(cube, window_size=SIZE, camera=VIEWS[view], layers=2, supersample=supersample)
    truth, segs = _truth(gb)
    assert len(segs) == 3
    ink = hidden_edges(gb) >= 0.5
    precision, recall = precision_recall(ink, truth, tol_px=1.5)
    # raster: cut where a visible line crosses (1.5 px each side) and at the silhouette
    assert precision >= 0.98 and recall >= 0.9, (precision, recall)
    pic = technical_drawing(gb, hidden="dashed")
    hidden = [s for s in pic.strokes if s.kind == "hidden"]
    assert len(hidden) == 3, [np.round(s.points).tolist() for s in hidden]
    pts = np.concatenate([s.points for s in hidden])
    assert _seg_distance(pts, segs).max() <= 1.5
    assert all(s.dash is not None for s in hidden)
    # the strokes cover the hidden edges end to end, but for the clearance at the outline
    drawn = np.zeros_like(truth)
    for s in hidden:
        for a, b in itertools.pairwise(s.points):
            t = np.linspace(0, 1, 2000)[:, None]
            xy = np.rint(a + t * (b - a)).astype(int)
            drawn[xy[:, 1], xy[:, 0]] = True
    precision, recall = precision_recall(drawn, truth, tol_px=1.5)
    assert precision >= 0.98 and recall >= 0.95, (precision, recall)
    # none of the visible edges is hidden
    visible = [s for s in pic.strokes if s.kind != "hidden"]
    assert visible and all(s.dash is None for s in visible)


def test_dashes_run_on_through_vertices():
    """An L of 10 + 10 px dashed (6, 3): pieces every 9 px along the whole arc length, one
    across the corner; drawn, the ink follows the pieces."""
    s = Stroke(np.array([[10.0, 10.0], [20.0, 10.0], [20.0, 20.0]]), 1.0, "x", dash=(6.0, 3.0))
    pieces = dash_pieces(s)
    lengths = [float(np.hypot(*np.diff(p, axis=0).T).sum()) for p in pieces]
    np.testing.assert_allclose(lengths, [6.0, 6.0, 2.0])
    np.testing.assert_allclose(pieces[1][0], [19.0, 10.0])
    np.testing.assert_allclose(pieces[1][-1], [20.0, 15.0])  # through the corner
    assert len(pieces[1]) == 3
    ink = draw_strokes([s], (30, 30))
    assert ink[10, 10:16].min() > 0.45 and ink[10, 17] < 0.05  # a dash, then the gap
    assert ink[12:15, 20].min() > 0.9  # the dash around the corner
    solid = draw_strokes([s._replace(dash=None)], (30, 30))
    # a 1 px line: one pixel of ink per pixel of length, whatever its position
    assert abs(solid.sum() - 20.0) < 1.5, solid.sum()
    assert abs(ink.sum() - 14.0) < 1.5, ink.sum()


def test_svg_and_raster_draw_the_same_dashes(tmp_path):
    cube = pv.Cube().triangulate()
    gb = sg.capture(cube, window_size=SIZE, camera=VIEWS["front-right-up"], layers=2)
    pic = technical_drawing(gb, hidden="dashed")
    svg = write_vector(tmp_path / "cube.svg", pic)
    root = ET.parse(svg).getroot()
    ns = {"s": "http://www.w3.org/2000/svg"}
    (group,) = [g for g in root.findall("s:g", ns) if g.get("class") == "hidden"]
    assert len(group) == 3 and all(e.get("stroke-dasharray") == "6 3" for e in group)
    img = technical_drawing_image(gb, hidden="dashed")
    assert img.shape == (*gb.output_shape, 3)
    ink = 1.0 - img.mean(axis=2)
    hidden_ink = draw_strokes([s for s in pic.strokes if s.kind == "hidden"], gb.output_shape)
    # along the hidden strokes, away from visible lines, the picture's ink is the dashes'
    visible = draw_strokes([s for s in pic.strokes if s.kind != "hidden"], gb.output_shape)
    away = ndimage.distance_transform_edt(visible < 0.05) > 2
    assert np.abs(ink - hidden_ink)[away].max() < 1e-5
    thin = technical_drawing(gb, hidden="thin")
    grey = [s for s in thin.strokes if s.kind == "hidden"]
    assert len(grey) == 3 and all(s.dash is None and s.width == 0.5 for s in grey)
    assert all(s.color == (0.45, 0.45, 0.45) for s in grey)
    assert not [s for s in technical_drawing(gb, hidden=None).strokes if s.kind == "hidden"]


def test_hidden_lines_need_layers():
    cube = pv.Cube().triangulate()
    gb = sg.capture(cube, window_size=(64, 48), camera=VIEWS["left-low"])
    with pytest.raises(InputError, match="layers"):
        hidden_edges(gb)
    with pytest.raises(InputError, match="layers"):
        technical_drawing(gb)
    with pytest.raises(InputError, match="hidden"):
        technical_drawing(gb, hidden="dotted")
