"""The object-space edge ground truth (tests/helpers/edge_truth.py) against analytic results."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import pyvista as pv
from vtkmodules.vtkFiltersCore import vtkFeatureEdges
from vtkmodules.vtkRenderingCore import vtkCamera

import sciviz_gbuf as sg
from sciviz_gbuf.core.camera import CameraInfo
from tests.helpers.edge_truth import (
    classify_edges,
    mesh_triangles,
    precision_recall,
    scene_triangles,
    visible_edge_truth,
)

SIZE = (200, 200)


def make_camera(
    position,
    focal=(0.0, 0.0, 0.0),
    up=(0.0, 0.0, 1.0),
    *,
    parallel=False,
    scale=1.1,
    view_angle=30.0,
    size=SIZE,
    clip=(0.1, 100.0),
) -> CameraInfo:
    cam = vtkCamera()
    cam.SetPosition(*position)
    cam.SetFocalPoint(*focal)
    cam.SetViewUp(*up)
    cam.SetViewAngle(view_angle)
    cam.SetParallelProjection(parallel)
    cam.SetParallelScale(scale)
    cam.SetClippingRange(*clip)
    return CameraInfo.from_vtk(cam, size)


def project(cam: CameraInfo, pts) -> np.ndarray:
    """World points -> continuous pixel coordinates (col, row), row 0 on top."""
    w, h = cam.window_size
    pts = np.atleast_2d(np.asarray(pts, dtype=np.float64))
    c = np.c_[pts, np.ones(len(pts))] @ cam.world_to_clip().T
    ndc = c[:, :2] / c[:, 3:4]
    return np.stack([(ndc[:, 0] + 1) / 2 * w, (1 - ndc[:, 1]) / 2 * h], axis=1)


def pixel_centres(img: np.ndarray) -> np.ndarray:
    r, c = np.nonzero(img)
    return np.stack([c + 0.5, r + 0.5], axis=1)


def dist_to_segments(p: np.ndarray, segs) -> np.ndarray:
    """Distance of 2-D points (n, 2) to the nearest of the 2-D segments [(a, b), ...]."""
    best = np.full(len(p), np.inf)
    for a, b in segs:
        ab = b - a
        t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(p - (a + t[:, None] * ab), axis=1))
    return best


def along(segs, step=0.5) -> np.ndarray:
    """Points every ``step`` pixels along 2-D segments."""
    out = []
    for a, b in segs:
        n = max(int(np.ceil(np.linalg.norm(b - a) / step)), 1)
        t = np.linspace(0.0, 1.0, n + 1)[:, None]
        out.append(a + t * (b - a))
    return np.concatenate(out)


def near_truth(points: np.ndarray, img: np.ndarray) -> np.ndarray:
    """Distance of each 2-D point to the nearest truth pixel centre."""
    centres = pixel_centres(img)
    if len(centres) == 0:
        return np.full(len(points), np.inf)
    d = np.linalg.norm(points[:, None, :] - centres[None, :, :], axis=2)
    return d.min(axis=1)


CAMERAS = {
    "perspective": make_camera((3.0, 2.2, 1.7)),
    "parallel": make_camera((3.0, 2.2, 1.7), parallel=True),
}


def cube_edges(cam: CameraInfo):
    """The 12 edges of the unit cube with how many of their two faces face the eye."""
    eye = np.asarray(cam.position)
    d = cam.direction
    out = []
    for a, b in itertools.combinations(itertools.product((-0.5, 0.5), repeat=3), 2):
        a, b = np.asarray(a), np.asarray(b)
        diff = np.flatnonzero(a != b)
        if len(diff) != 1:
            continue
        front = 0
        for axis in set(range(3)) - {int(diff[0])}:
            n = np.zeros(3)
            n[axis] = np.sign(a[axis])
            centre = n * 0.5
            facing = n @ (-d) if cam.parallel_projection else n @ (eye - centre)
            front += facing > 0
        out.append((a, b, front))
    return out


# --------------------------------------------------------------------------- cube
@pytest.mark.parametrize("kind", sorted(CAMERAS))
def test_cube_has_nine_visible_edges(kind):
    cam = CAMERAS[kind]
    truth = visible_edge_truth(pv.Cube(), cam)
    edges = cube_edges(cam)
    visible = [project(cam, [a, b]) for a, b, f in edges if f > 0]
    outline = [project(cam, [a, b]) for a, b, f in edges if f == 1]
    hidden = [project(cam, [a, b]) for a, b, f in edges if f == 0]
    assert (len(visible), len(outline), len(hidden)) == (9, 6, 3)

    assert not truth["border"].any()
    np.testing.assert_array_equal(truth["all"], truth["crease"] | truth["silhouette"])
    # every truth pixel lies on one of the 9 visible segments ...
    assert dist_to_segments(pixel_centres(truth["all"]), visible).max() <= 0.75
    assert dist_to_segments(pixel_centres(truth["silhouette"]), outline).max() <= 0.75
    # ... and each of them is drawn end to end (all cube edges are 90-degree creases)
    for key, segs in (("all", visible), ("crease", visible), ("silhouette", outline)):
        assert near_truth(along(segs), truth[key]).max() <= 1.0, key
    # the 3 hidden edges are not drawn where they are clear of the visible ones
    pts = along(hidden)
    clear = dist_to_segments(pts, visible) > 3.0
    assert clear.sum() > 50
    assert near_truth(pts[clear], truth["all"]).min() > 1.5


def test_cube_kinds_can_be_switched_off():
    cam = CAMERAS["perspective"]
    t = visible_edge_truth(pv.Cube(), cam, creases=False)
    assert t["silhouette"].any() and not t["crease"].any()
    np.testing.assert_array_equal(t["all"], t["silhouette"])
    t = visible_edge_truth(pv.Cube(), cam, feature_angle=95.0, silhouettes=False)
    assert not t["all"].any()


def test_unstructured_input_gives_the_cube():
    cam = CAMERAS["perspective"]
    grid = pv.ImageData(dimensions=(2, 2, 2), origin=(-0.5, -0.5, -0.5)).cast_to_unstructured_grid()
    a = visible_edge_truth(grid, cam)
    b = visible_edge_truth(pv.Cube(), cam)
    for key in ("silhouette", "crease", "all"):
        assert a[key].sum() > 100
        assert precision_recall(a[key], b[key], tol_px=1.0) == (1.0, 1.0)


def test_unmerged_cube_has_only_borders():
    """Six quads that share no points (an unmerged CAD export): every cube edge is a border."""
    cam = CAMERAS["perspective"]
    cube = pv.Cube()
    quads = cube.faces.reshape(-1, 5)[:, 1:]
    faces = np.c_[np.full(len(quads), 4), np.arange(quads.size).reshape(-1, 4)].ravel()
    soup = pv.PolyData(cube.points[quads.reshape(-1)], faces)
    assert soup.n_points == 24
    t = visible_edge_truth(soup, cam)
    assert not t["crease"].any() and not t["silhouette"].any()
    ref = visible_edge_truth(cube, cam)["all"]
    assert precision_recall(t["border"], ref, tol_px=1.0) == (1.0, 1.0)


# --------------------------------------------------------------------------- plane
@pytest.mark.parametrize("z", [2.0, -2.0], ids=["front", "back"])
@pytest.mark.parametrize("parallel", [False, True], ids=["persp", "ortho"])
def test_plane_has_only_border_edges(z, parallel):
    cam = make_camera((0.8, -1.5, z), parallel=parallel, scale=0.8, view_angle=40.0)
    truth = visible_edge_truth(pv.Plane(i_resolution=4, j_resolution=4), cam)
    assert not truth["crease"].any() and not truth["silhouette"].any()
    corners = np.array([(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)])
    px = project(cam, corners)
    square = [(px[i], px[(i + 1) % 4]) for i in range(4)]
    assert dist_to_segments(pixel_centres(truth["border"]), square).max() <= 0.75
    assert near_truth(along(square), truth["border"]).max() <= 1.0


# --------------------------------------------------------------------------- sphere
@pytest.mark.parametrize("parallel", [False, True], ids=["persp", "ortho"])
def test_sphere_silhouette_is_the_analytic_circle(parallel):
    radius, dist = 0.5, 3.0
    eye = dist * np.array([0.6, -0.48, 0.64])
    cam = make_camera(eye, parallel=parallel, scale=0.8)
    sphere = pv.Sphere(radius=radius, theta_resolution=60, phi_resolution=60)
    truth = visible_edge_truth(sphere, cam, feature_angle=30.0)
    assert not truth["crease"].any() and not truth["border"].any()
    w, h = SIZE
    if parallel:
        r_px = radius / cam.parallel_scale * h / 2
    else:
        alpha = np.arcsin(radius / dist)
        r_px = np.tan(alpha) / np.tan(np.radians(cam.view_angle / 2)) * h / 2
    p = pixel_centres(truth["silhouette"]) - [w / 2, h / 2]
    r = np.linalg.norm(p, axis=1)
    assert np.abs(r - r_px).max() <= 1.0
    angle = np.degrees(np.arctan2(p[:, 1], p[:, 0]))
    assert len(np.unique(np.floor(angle / 5.0))) == 72  # closed all round


# --------------------------------------------------------------------------- occlusion
@pytest.mark.parametrize("parallel", [False, True], ids=["persp", "ortho"])
def test_edge_behind_a_box_is_hidden(parallel):
    cam = make_camera((0, 0, 5), up=(0, 1, 0), parallel=parallel, scale=1.2)
    plane = pv.Plane(i_size=2, j_size=2)
    box = pv.Box(bounds=(0.6, 1.4, -0.2, 0.2, 0.3, 0.5))
    truth = visible_edge_truth([plane, box], cam)
    ys = np.linspace(-0.9, 0.9, 181)
    edge_px = project(cam, np.c_[np.ones_like(ys), ys, np.zeros_like(ys)])
    d = near_truth(edge_px, truth["border"])
    assert d[np.abs(ys) <= 0.15].min() > 2.0  # under the box
    assert d[np.abs(ys) >= 0.35].max() <= 1.0  # in the open
    left = project(cam, [(-1, -1, 0), (-1, 1, 0)])
    assert near_truth(along([left]), truth["border"]).max() <= 1.0
    # the box's own top outline is drawn, and the plane's border alone without the box is whole
    top = project(cam, [(0.6, -0.2, 0.5), (0.6, 0.2, 0.5)])
    assert near_truth(along([top]), truth["all"]).max() <= 1.0
    alone = visible_edge_truth(plane, cam)
    assert near_truth(edge_px, alone["border"]).max() <= 1.0


# --------------------------------------------------------------------------- edge classes
def test_non_manifold_edge_is_a_border():
    pts = np.array([(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -1, 0), (0.5, 0, 1)], float)
    tris = np.array([(0, 1, 2), (1, 0, 3), (0, 1, 4)])
    k = classify_edges(pts, tris, feature_angle=30.0)
    shared = np.flatnonzero((k["edges"] == [0, 1]).all(axis=1))
    assert len(shared) == 1 and k["border"][shared[0]]
    assert k["border"].sum() == 7 and not k["crease"].any()


@pytest.mark.parametrize("fold", [20.0, 60.0, 160.0])
def test_winding_does_not_matter(fold):
    """Two triangles hinged on the x axis; the second one wound either way."""
    a = np.radians(fold)
    pts = np.array([(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -np.cos(a), np.sin(a))])
    good = np.array([(0, 1, 2), (1, 0, 3)])
    bad = np.array([(0, 1, 2), (0, 1, 3)])
    eye = np.array([0.5, -3.0, 0.5])
    res = [classify_edges(pts, t, feature_angle=30.0, eye=eye) for t in (good, bad)]
    for r in res:
        hinge = (r["edges"] == [0, 1]).all(axis=1)
        assert r["crease"][hinge][0] == (fold >= 30.0)  # normals differ by `fold`
        assert not r["border"][hinge][0]
    for key in ("crease", "silhouette"):
        np.testing.assert_array_equal(res[0][key], res[1][key])


def test_fold_silhouette():
    pts = np.array([(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -1, 0.2)], float)
    tris = np.array([(0, 1, 2), (1, 0, 3)])
    hinge = 0  # the edge (0, 1) sorts first
    above = classify_edges(pts, tris, eye=(0.5, 0, 5))
    assert not above["silhouette"][hinge]
    from_side = classify_edges(pts, tris, eye=(0.5, 5, 0.1))
    assert not from_side["silhouette"][hinge]
    # from under the far flap: the near one faces the eye, the far one faces away
    grazing = classify_edges(pts, tris, eye=(0.5, -5, 0.5))
    assert grazing["silhouette"][hinge]
    par = classify_edges(pts, tris, view_direction=(0, 1, -0.1))
    assert par["silhouette"][hinge]


def test_stl_feature_edges_match_vtk(shared_data):
    mesh = pv.read(shared_data / "meshes" / "vtkdata_42400-IDGH.stl")
    pts, tris = mesh_triangles(mesh)
    k = classify_edges(pts, tris, feature_angle=30.0)
    ours = k["edges"][k["crease"] | k["border"]]
    fe = vtkFeatureEdges()
    fe.SetInputData(mesh)
    fe.SetFeatureAngle(30.0)
    fe.FeatureEdgesOn()
    fe.BoundaryEdgesOn()
    fe.NonManifoldEdgesOn()
    fe.ManifoldEdgesOff()
    fe.Update()
    ref = pv.wrap(fe.GetOutput())
    assert ref.n_cells == len(ours) == 2099
    mid_ref = ref.points[ref.lines.reshape(-1, 3)[:, 1:]].mean(axis=1)
    mid_ours = pts[ours].mean(axis=1)
    key = lambda m: m[np.lexsort(m.T[::-1])]  # noqa: E731
    np.testing.assert_allclose(key(mid_ours), key(mid_ref), atol=1e-5)


def test_stl_truth_lies_on_the_capture(shared_data):
    mesh = pv.read(shared_data / "meshes" / "vtkdata_42400-IDGH.stl")
    gb = sg.capture(mesh, window_size=(256, 256))
    truth = visible_edge_truth(mesh, gb)
    assert truth["crease"].sum() > 300 and truth["silhouette"].sum() > 300
    assert not truth["border"].any()
    # every truth pixel is on the rendered part or right next to it, diagonals included
    # (a silhouette sliver thinner than a pixel may cover no pixel centre)
    _, recall = precision_recall(gb.mask, truth["all"], tol_px=1.5)
    assert recall == 1.0


def test_scene_triangles_flattens_lists_and_multiblocks():
    mb = pv.MultiBlock([pv.Cube(), pv.Plane()])
    pts, tris, owner = scene_triangles([mb, pv.Sphere()])
    assert set(np.unique(owner)) == {0, 1, 2}
    assert tris.max() < len(pts)
    assert (owner[tris[:, 0]] == owner[tris[:, 1]]).all()


def test_empty_scene_and_bad_arguments():
    cam = CAMERAS["parallel"]
    t = visible_edge_truth(pv.PolyData(), cam)
    assert set(t) == {"silhouette", "border", "crease", "all"}
    assert all(v.shape == (SIZE[1], SIZE[0]) and not v.any() for v in t.values())
    with pytest.raises(ValueError):
        visible_edge_truth(pv.Cube(), cam, feature_angle=200.0)
    with pytest.raises(ValueError):
        visible_edge_truth(pv.Cube(), cam, step_px=0.0)


# --------------------------------------------------------------------------- scoring
def test_precision_recall():
    truth = np.zeros((40, 40), bool)
    truth[20, 5:35] = True
    assert precision_recall(truth, truth) == (1.0, 1.0)
    assert precision_recall(np.roll(truth, 1, axis=0), truth) == (1.0, 1.0)
    assert precision_recall(np.roll(truth, 3, axis=0), truth) == (0.0, 0.0)
    half = truth.copy()
    half[20, 20:] = False
    p, r = precision_recall(half, truth)
    assert p == 1.0 and r == pytest.approx(16 / 30)  # col 20 is 1 px from col 19
    extra = truth.copy()
    extra[5, 5:15] = True
    p, r = precision_recall(extra, truth)
    assert p == pytest.approx(30 / 40) and r == 1.0


def test_precision_recall_empty_and_shapes():
    empty = np.zeros((10, 10), bool)
    some = empty.copy()
    some[5, 5] = True
    assert precision_recall(empty, empty) == (1.0, 1.0)
    assert precision_recall(empty, some) == (1.0, 0.0)
    assert precision_recall(some, empty) == (0.0, 1.0)
    with pytest.raises(ValueError):
        precision_recall(empty, np.zeros((10, 11), bool))
