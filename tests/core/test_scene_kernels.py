"""The compiled normal splitting (``core._scene_kernels``) against its numpy statement, stale
normals repaired, and the per-dataset preparation cache (issue 44: capture at render speed)."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sciviz_gbuf as sg
from sciviz_gbuf.core import scene
from sciviz_gbuf.core.scene import collect_surfaces, split_normals
from tests.helpers.paths import SHARED_DATA
from tests.helpers.split_reference import face_normals, split_reference

STL = SHARED_DATA / "meshes" / "vtkdata_42400-IDGH.stl"


def _split_parts(poly, normals, triangles, feature_angle):
    """What :func:`split_normals` decided, in the reference's terms."""
    _, all_normals, new_tris = split_normals(poly, normals, triangles, feature_angle)
    n0 = poly.n_points
    bad = np.flatnonzero((new_tris != triangles).ravel())
    return np.asarray(all_normals[:n0], np.float64), bad, np.asarray(all_normals[n0:], np.float64)


def _agrees(points, normals, triangles, feature_angle=30.0):
    poly = pv.PolyData(points, np.hstack([np.full((len(triangles), 1), 3), triangles]).ravel())
    poly.point_data["Normals"] = normals
    fitted, bad, new = _split_parts(poly, normals, triangles, feature_angle)
    out, _, _ = split_normals(poly, normals, triangles, feature_angle)
    if bad.size:  # the split surface carries its new normals under the file's name
        np.testing.assert_allclose(out.point_data["Normals"][poly.n_points :], new)
    want_fitted, want_bad, want_new = split_reference(points, normals, triangles, feature_angle)
    np.testing.assert_array_equal(bad, want_bad)
    # float32 in, float32 out: both routes round the same float64 normal
    np.testing.assert_allclose(new, want_new, atol=1e-6)
    nrm = np.asarray(normals, np.float64)
    unit = nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    changed = ~np.all(np.isclose(want_fitted, unit, atol=1e-12), axis=1)
    if changed.any():  # stale normals replaced: the kernel wrote the same ones
        np.testing.assert_allclose(fitted[changed], want_fitted[changed], atol=1e-6)
    return bad.size, int(changed.sum())


def _smoothed(mesh: pv.PolyData) -> pv.PolyData:
    """``mesh`` with its point normals averaged across every edge (a CAD export's)."""
    return mesh.clean().compute_normals(
        feature_angle=179.9, split_vertices=False, cell_normals=False, consistent_normals=True
    )


def _parts(mesh: pv.PolyData):
    tris = mesh.faces.reshape(-1, 4)[:, 1:].astype(np.int64)
    return np.asarray(mesh.points, np.float64), np.asarray(mesh.point_data["Normals"]), tris


def _stale_wave(n: int = 60) -> pv.PolyData:
    """A plane whose normals were computed before its points were lifted into a wave (the
    user's ``mesh.points = ...``, then plot): every normal still points straight up."""
    plane = pv.Plane(i_resolution=n, j_resolution=n).triangulate().compute_normals()
    pts = np.asarray(plane.points).copy()
    pts[:, 2] = 0.25 * np.sin(6 * pts[:, 0]) * np.cos(5 * pts[:, 1])
    plane.points = pts
    return plane


def _fresh(mesh: pv.PolyData) -> pv.PolyData:
    """The same surface with normals computed for its points as they are now (from bare
    geometry: ``vtkPolyDataNormals`` on the edited mesh itself keeps the stale ones)."""
    bare = pv.PolyData(np.asarray(mesh.points), mesh.faces)
    return bare.compute_normals(split_vertices=False, cell_normals=False)


def test_cube_split_as_the_reference():
    n_bad, n_stale = _agrees(*_parts(_smoothed(pv.Cube().triangulate())))
    assert n_bad == 36 and n_stale == 0  # every corner of a cube lies on a 90-degree edge


@pytest.mark.skipif(not STL.is_file(), reason="shared data not present")
def test_cad_part_split_as_the_reference():
    n_bad, _ = _agrees(*_parts(_smoothed(pv.read(STL).triangulate())))
    assert n_bad > 1000


def test_stale_wave_normals_replaced_as_the_reference():
    wave = _stale_wave()
    n_bad, n_stale = _agrees(*_parts(wave))
    assert n_stale > 1000 and n_bad < n_stale


def test_stale_normals_fit_their_faces():
    """Normals more than half the feature angle off their faces are replaced by the faces'
    area-weighted mean: near the normals VTK computes for the moved surface (the stale,
    up-pointing ones were up to 50 degrees off); the others are the file's, kept."""
    wave = _stale_wave()
    _, normals, tris = _parts(wave)
    fitted, _, _ = _split_parts(wave, normals, tris, 30.0)
    truth = np.asarray(_fresh(wave).point_data["Normals"], np.float64)
    before = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", normals, truth), -1, 1)))
    after = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", fitted, truth), -1, 1)))
    replaced = np.any(fitted != normals, axis=1)
    assert before.max() > 30 and replaced.sum() > 1000
    assert np.all(replaced[before > 17.0])  # (VTK's mean weighs faces alike, ours by area)
    assert np.percentile(after[replaced], 99) < 1.0 and after[replaced].max() < 2.0
    assert after.max() < 17.0


def test_stale_wave_shades_like_fresh_normals():
    """The captured normals of the stale wave are those of the same wave with fresh normals,
    but where a file normal is within half the feature angle of its faces (kept)."""
    wave = _stale_wave(80)
    fresh = _fresh(wave)
    cam = ((0.8, -1.0, 0.9), (0, 0, 0), (0, 0, 1))
    a = sg.capture(wave, window_size=(128, 96), camera=cam)
    b = sg.capture(fresh, window_size=(128, 96), camera=cam)
    both = a.mask & b.mask
    assert both.sum() > 4000
    dots = np.einsum("ij,ij->i", a.normal[both], b.normal[both])
    angle = np.degrees(np.arccos(np.clip(dots, -1, 1)))
    assert np.percentile(angle, 95) < 0.5 and angle.max() < 17.0


@st.composite
def _meshes(draw):
    """Small odd meshes: points on a coarse integer grid (coincident points, zero-area and
    repeated triangles), random and zero normals, any winding."""
    n = draw(st.integers(3, 12))
    coords = draw(st.lists(st.integers(-2, 2), min_size=3 * n, max_size=3 * n))
    points = np.asarray(coords, np.float64).reshape(n, 3)
    m = draw(st.integers(1, 20))
    idx = draw(st.lists(st.integers(0, n - 1), min_size=3 * m, max_size=3 * m))
    tris = np.asarray(idx, np.int64).reshape(m, 3)
    nrm = draw(st.lists(st.integers(-3, 3), min_size=3 * n, max_size=3 * n))
    normals = np.asarray(nrm, np.float32).reshape(n, 3)
    angle = draw(st.sampled_from([10.0, 30.0, 44.0, 75.0, 120.0]))
    return points, normals, tris, angle


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_meshes())
def test_odd_meshes_split_as_the_reference(case):
    points, normals, tris, angle = case
    _agrees(points, normals, tris, angle)


def test_face_normals_kernel():
    rng = np.random.default_rng(4)
    points = rng.normal(size=(50, 3))
    tris = rng.integers(0, 50, size=(200, 3))
    tris[:5, 1] = tris[:5, 0]  # zero-area triangles
    face = np.empty((200, 3))
    area2 = np.empty(200)
    scene._scene_kernels.face_normals_into(points, tris, face, area2)
    want_face, want_area2 = face_normals(points, tris)
    np.testing.assert_allclose(face, want_face, atol=1e-12)
    np.testing.assert_allclose(area2, want_area2, rtol=1e-12)
    assert np.all(face[:5] == 0) and np.all(area2[:5] == 0)


# -- the per-dataset preparation cache ------------------------------------------------------


def _prepared_points(data, **kw):
    (surface,) = collect_surfaces(data, **kw)
    return surface.points


def test_unchanged_dataset_is_prepared_once():
    mesh = _stale_wave(20)
    first = _prepared_points(mesh)
    assert _prepared_points(mesh) is first  # the remembered preparation, no mesh work
    assert _prepared_points(mesh, feature_angle=50.0) is not first  # an option changes it


@pytest.mark.parametrize(
    "edit",
    [
        "assign_points",
        "setitem_points",
        "new_point_data",
        "modified",
    ],
)
def test_edited_dataset_is_prepared_afresh(edit):
    mesh = pv.Sphere(theta_resolution=12, phi_resolution=12)
    first = _prepared_points(mesh)
    if edit == "assign_points":
        mesh.points = np.asarray(mesh.points) * 2.0
    elif edit == "setitem_points":
        mesh.points[0] = (0.0, 0.0, 5.0)
    elif edit == "new_point_data":
        mesh.point_data["Normals"] = -np.asarray(mesh.point_normals)
    else:
        mesh.Modified()
    second = _prepared_points(mesh)
    assert second is not first
    if edit == "setitem_points":
        np.testing.assert_allclose(second[0], (0.0, 0.0, 5.0))
    if edit == "assign_points":
        np.testing.assert_allclose(second, 2.0 * first, rtol=1e-6)


def test_actor_transform_is_part_of_the_key():
    mesh = pv.Sphere(theta_resolution=12, phi_resolution=12)
    pl = pv.Plotter(off_screen=True)
    actor = pl.add_mesh(mesh)
    first = _prepared_points(pl)
    assert _prepared_points(pl) is first
    actor.SetPosition(1.0, 0.0, 0.0)
    moved = _prepared_points(pl)
    np.testing.assert_allclose(moved, first + np.array([1.0, 0.0, 0.0]), atol=1e-6)
    pl.close()


def test_recapture_of_unchanged_scene_is_the_same_and_follows_edits():
    mesh = _stale_wave(40)
    cam = ((2.0, -2.5, 2.0), (0, 0, 0), (0, 0, 1))
    a = sg.capture(mesh, window_size=(96, 80), camera=cam)
    b = sg.capture(mesh, window_size=(96, 80), camera=cam)
    np.testing.assert_array_equal(a.depth, b.depth)
    np.testing.assert_array_equal(a.normal, b.normal)
    np.testing.assert_array_equal(a.cell_id, b.cell_id)
    # an edit after the kept window: the picture follows it
    mesh.points = np.asarray(mesh.points) + np.array([0.0, 0.0, 0.3])
    c = sg.capture(mesh, window_size=(96, 80), camera=cam)
    assert not np.array_equal(a.depth, c.depth)
    sg.clear_capture_cache()
    e = sg.capture(mesh, window_size=(96, 80), camera=cam)
    np.testing.assert_array_equal(c.depth, e.depth)
    np.testing.assert_array_equal(c.normal, e.normal)
    assert not scene._PREPARED or len(scene._PREPARED) <= scene.PREPARED_ENTRIES


def test_cache_holds_at_most_its_entries():
    sg.clear_capture_cache()
    meshes = [pv.Sphere(radius=1.0 + k, theta_resolution=8, phi_resolution=8) for k in range(12)]
    for m in meshes:
        collect_surfaces(m)
    assert len(scene._PREPARED) == scene.PREPARED_ENTRIES
    sg.clear_capture_cache()
    assert len(scene._PREPARED) == 0
