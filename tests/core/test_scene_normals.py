"""Point normals smoothed across sharp edges are split there (issue item 6: flat CAD faces
shade flat)."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.core.scene import collect_surfaces
from tests.filters.test_edges_acceptance import view
from tests.helpers.geometry import camera_basis


def _smoothed(mesh: pv.PolyData, path) -> pv.PolyData:
    """``mesh`` saved and read back with normals averaged across every edge."""
    smooth = mesh.clean().compute_normals(
        feature_angle=179.9, split_vertices=False, cell_normals=False, consistent_normals=True
    )
    smooth.save(path)
    back = pv.read(path)
    assert back.point_data.active_normals_name == "Normals"
    return back


def _eye_face_normals(gb, mesh):
    """Per pixel: the world normal of the triangle of the user's cell, in eye space."""
    d, right, up = camera_basis(gb.camera)
    face = np.asarray(mesh.compute_normals(cell_normals=True, point_normals=False)["Normals"])
    n = face[gb.cell_id[gb.mask]]
    eye = np.stack([n @ right, n @ up, -(n @ d)], axis=1)
    return eye * np.sign(np.einsum("ij,ij->i", eye, gb.normal[gb.mask]))[:, None]


@pytest.mark.parametrize("suffix", [".vtp", ".ply"])
def test_cube_with_smoothed_normals_shades_flat(tmp_path, suffix):
    cube = pv.Cube().triangulate()
    data = _smoothed(cube, tmp_path / f"cube{suffix}")
    gb = sg.capture(data, window_size=(160, 120), camera=((3.0, -2.2, 1.7), (0, 0, 0), (0, 0, 1)))
    got = gb.normal[gb.mask]
    want = _eye_face_normals(gb, data)
    angle = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", got, want), -1, 1)))
    assert angle.max() < 0.05  # float32 normals
    # each visible face: one normal (std ~ 0), three different faces
    faces = np.round(want, 3)
    groups = np.unique(faces, axis=0)
    assert len(groups) == 3
    for g in groups:
        sel = np.all(faces == g, axis=1)
        assert sel.sum() > 200 and got[sel].std(axis=0).max() < 1e-4


def _flat_face_cells(mesh: pv.PolyData, feature_angle: float = 30.0) -> np.ndarray:
    """Cells of planar CAD faces: at each corner, every triangle within the feature angle of
    the cell is coplanar with it (so its split normal is the face's own)."""
    face = np.asarray(mesh.compute_normals(cell_normals=True, point_normals=False)["Normals"])
    tris = mesh.faces.reshape(-1, 4)[:, 1:]
    lo = np.cos(np.radians(feature_angle))
    flat = np.ones(len(tris), dtype=bool)
    around: dict[int, list[int]] = {}
    for t, corners in enumerate(tris):
        for p in corners:
            around.setdefault(int(p), []).append(t)
    for t, corners in enumerate(tris):
        for p in corners:
            dots = face[around[int(p)]] @ face[t]
            if ((dots >= lo) & (dots < np.cos(np.radians(0.5)))).any():
                flat[t] = False
                break
    return flat


def test_cad_part_flat_faces_shade_flat(shared_data, tmp_path):
    stl = pv.read(shared_data / "meshes" / "vtkdata_42400-IDGH.stl")
    data = _smoothed(stl, tmp_path / "part.vtp")
    cam = view(stl, 35.0, 30.0)
    flat = _flat_face_cells(data)[None]
    for feature_angle, streaky in ((30.0, False), (180.0, True)):
        gb = sg.capture(data, window_size=(320, 240), camera=cam, feature_angle=feature_angle)
        want_all = _eye_face_normals(gb, data)
        on_flat = flat[0][gb.cell_id[gb.mask]]
        assert on_flat.sum() > 1000
        got, want = gb.normal[gb.mask][on_flat], want_all[on_flat]
        angle = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", got, want), -1, 1)))
        if streaky:  # 180 degrees keeps the file's normals: tilted by the sharp neighbours
            assert np.percentile(angle, 90) > 10.0
        else:  # the face's own normal (float32 STL faces beside them turn by < 0.5 degree)
            assert angle.max() < 2.0 and np.percentile(angle, 95) < 0.5


def test_agreeing_normals_are_kept_as_given():
    sphere = pv.Sphere(theta_resolution=24, phi_resolution=24)
    (surface,) = collect_surfaces(sphere)
    assert surface.points.shape[0] == sphere.n_points
    np.testing.assert_allclose(surface.normals, sphere.point_data["Normals"], atol=1e-6)
