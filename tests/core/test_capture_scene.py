"""Object/cell ids, scalars, scenes from a Plotter, supersampling and multi-pass id renders."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from vtkmodules.vtkCommonCore import mutable
from vtkmodules.vtkCommonDataModel import vtkCellLocator

import sciviz_gbuf as sg
from sciviz_gbuf.core import _render
from tests.helpers.geometry import interior, rays_by_hand


def _two_objects():
    sphere = pv.Sphere(radius=1.0, center=(0, 0, 0), theta_resolution=60, phi_resolution=60)
    box = pv.Box(bounds=(-3, 3, -3, 3, -2.0, -1.5)).triangulate()
    return sphere, box


def _locator_picks(mesh, g, rows, cols):
    """Cell id and hit point of the first intersection along each pixel's ray (VTK locator)."""
    loc = vtkCellLocator()
    loc.SetDataSet(mesh)
    loc.BuildLocator()
    o, d = rays_by_hand(g.camera)
    far = g.camera.clipping_range[1] * 2
    ids, hits = [], []
    for r, c in zip(rows, cols, strict=True):
        p0 = o[r, c]
        p1 = p0 + far * d[r, c]
        t, x, pc = mutable(0.0), [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        sub, cell = mutable(0), mutable(0)
        found = loc.IntersectWithLine(p0, p1, 1e-12, t, x, pc, sub, cell)
        ids.append(int(cell) if found else -1)
        hits.append(x)
    return np.array(ids), np.array(hits)


def test_object_ids_distinguish_datasets():
    sphere, box = _two_objects()
    g = sg.capture(
        [sphere, box], window_size=(240, 200), camera=[(4, -6, 5), (0, 0, -0.5), (0, 0, 1)]
    )
    assert g.object_names and len(g.object_names) == 2
    assert set(np.unique(g.object_id)) == {-1, 0, 1}
    # each object's pixels lie on that object: sphere points at radius 1, box points in the box
    r = np.linalg.norm(g.world[g.object_id == 0], axis=-1)
    assert np.allclose(r, 1.0, atol=2e-3)
    zb = g.world[g.object_id == 1][:, 2]
    # (edge pixels may sit a sub-pixel snap outside a face: 1e-5 of the box size)
    assert zb.max() <= -1.5 + 6e-5 and zb.min() >= -2.0 - 6e-5
    # each dataset's own cell ids (not a global index)
    assert g.cell_id[g.object_id == 0].max() < sphere.n_cells
    assert g.cell_id[g.object_id == 1].max() < box.n_cells


def test_cell_ids_match_vtk_cell_locator():
    nut = pv.examples.load_nut()
    g = sg.capture(nut, window_size=(300, 240))
    # sample pixels away from cell borders so the answer is unambiguous
    same = np.ones_like(g.mask)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            same &= np.roll(np.roll(g.cell_id, dr, 0), dc, 1) == g.cell_id
    ok = interior(g.mask) & same
    rows, cols = np.nonzero(ok)
    rng = np.random.default_rng(0)
    pick = rng.choice(rows.size, size=min(400, rows.size), replace=False)
    ids, hits = _locator_picks(nut, g, rows[pick], cols[pick])
    assert (ids == g.cell_id[rows[pick], cols[pick]]).all()
    size = np.linalg.norm(np.ptp(nut.points, axis=0))
    assert np.abs(hits - g.world[rows[pick], cols[pick]]).max() < 1e-5 * size


def test_polygons_and_strips_keep_original_cell_ids():
    # quads and a triangle strip: triangles trace back to the user's cells
    grid = pv.Plane(center=(2, 1.5, 0), i_size=4, j_size=3, i_resolution=4, j_resolution=3)
    grid.clear_data()
    grid.cell_data["label"] = np.arange(grid.n_cells, dtype=np.float64) * 10
    strip = pv.PolyData(
        np.array([[0, 0, 1], [1, 0, 1], [0, 1, 1.2], [1, 1, 1.2], [0, 2, 1.4], [1, 2, 1.4]], float),
        strips=[6, 0, 1, 2, 3, 4, 5],
    ).translate((6, 0, 0), inplace=False)
    g = sg.capture([grid, strip], window_size=(200, 120), camera="xy", scalars=["label"])
    on_grid = g.object_id == 0
    assert g.cell_id[on_grid].max() == grid.n_cells - 1
    assert np.array_equal(g.scalars["label"][on_grid], g.cell_id[on_grid] * 10.0)
    # each pixel's world x/y lies in the quad its cell id names
    centers = np.asarray(grid.cell_centers().points)
    cx = centers[g.cell_id[on_grid], 0] - 0.5
    cy = centers[g.cell_id[on_grid], 1] - 0.5
    x, y = g.world[on_grid][:, 0], g.world[on_grid][:, 1]
    assert ((x >= cx - 1e-5) & (x <= cx + 1 + 1e-5) & (y >= cy - 1e-5) & (y <= cy + 1 + 1e-5)).all()
    on_strip = g.object_id == 1
    assert set(np.unique(g.cell_id[on_strip])) == {0}
    assert np.isnan(g.scalars["label"][on_strip]).all()  # the strip lacks the array


def test_volume_dataset_uses_outer_surface_and_volume_cell_ids():
    grid = pv.ImageData(dimensions=(4, 4, 4)).cast_to_unstructured_grid()
    g = sg.capture(grid, window_size=(160, 160), camera="xy")
    # looking down -z we see the top layer of voxels: cell ids 18..26 of the 3x3x3 grid
    assert set(np.unique(g.cell_id[g.mask])) == set(range(18, 27))
    assert np.allclose(g.world[g.mask][:, 2], 3.0)


def test_multi_pass_ids_are_exact(monkeypatch):
    # 8 bits per pass: a 60k-triangle sphere needs 2 passes; ids must still be exact
    monkeypatch.setattr(_render, "BITS_PER_PASS", 8)
    sphere = pv.Sphere(theta_resolution=180, phi_resolution=170)
    assert sphere.n_cells > 2**8 * 2**7
    g8 = sg.capture(sphere, window_size=(200, 200), camera="xz")
    monkeypatch.setattr(_render, "BITS_PER_PASS", 24)
    g24 = sg.capture(sphere, window_size=(200, 200), camera="xz")
    assert np.array_equal(g8.cell_id, g24.cell_id)
    assert np.array_equal(g8.world, g24.world, equal_nan=True)


def test_point_and_cell_scalars():
    sphere, _ = _two_objects()
    sphere.point_data["elevation"] = np.asarray(sphere.points[:, 2] * 100.0, dtype=np.float32)
    sphere.cell_data["twice_id"] = np.arange(sphere.n_cells) * 2
    sphere.point_data["vec"] = np.asarray(sphere.points * 3.0)
    g = sg.capture(sphere, window_size=(160, 160), scalars=("elevation", "twice_id", "vec"))
    m = g.mask
    assert np.allclose(g.scalars["elevation"][m], g.world[m][:, 2] * 100.0, atol=1e-3)
    assert np.array_equal(g.scalars["twice_id"][m], (g.cell_id[m] * 2).astype(np.float32))
    assert g.scalars["vec"].shape == (*g.shape, 3)
    assert np.allclose(g.scalars["vec"][m], g.world[m] * 3.0, atol=1e-5)


def test_supersample_shapes_and_downsample():
    sphere, _ = _two_objects()
    g = sg.capture(sphere, window_size=(50, 40), supersample=3)
    assert g.shape == (120, 150)
    assert g.camera.window_size == (150, 120)
    assert g.output_shape == (40, 50)
    cov = g.downsample(g.mask.astype(np.float32))
    assert cov.shape == (40, 50)
    assert cov.min() == 0.0 and cov.max() == 1.0
    # partially covered output pixels exist at the silhouette: antialiasing information kept
    assert ((cov > 0) & (cov < 1)).sum() > 20
    assert np.array_equal(np.isnan(g.downsample(g.depth)), cov == 0)
    # ids are sampled, not averaged
    ids = g.downsample(g.cell_id)
    assert ids.dtype == np.int64 and ids.shape == (40, 50)
    assert np.array_equal(ids, g.cell_id[1::3, 1::3])
    with pytest.raises(sg.InputError, match="expected shape"):
        g.downsample(np.zeros((40, 50)))


def test_plotter_scene_uses_actors_transforms_and_camera_without_disturbing_it():
    sphere, box = _two_objects()
    pl = pv.Plotter(off_screen=True, window_size=(220, 180))
    actor = pl.add_mesh(sphere, color="tan")
    actor.position = (0.5, 0.0, 0.0)
    pl.add_mesh(box)
    pl.add_text("label")  # not a dataset: ignored
    pl.camera_position = [(5, -5, 4), (0, 0, -0.5), (0, 0, 1)]
    before_img = pl.screenshot(return_img=True)
    cam = pl.camera
    before = (cam.position, cam.focal_point, cam.up, cam.view_angle, cam.clipping_range)
    n_actors = len(pl.renderer.actors)

    g = sg.capture(pl)

    assert (cam.position, cam.focal_point, cam.up, cam.view_angle, cam.clipping_range) == before
    assert len(pl.renderer.actors) == n_actors
    assert np.array_equal(pl.screenshot(return_img=True), before_img)
    assert g.shape == (180, 220)
    assert g.camera.position == pytest.approx(before[0])
    # the actor's translation is applied: sphere pixels are at radius 1 around (0.5, 0, 0)
    r = np.linalg.norm(g.world[g.object_id == 0] - np.array([0.5, 0, 0]), axis=-1)
    assert r.size > 100 and np.allclose(r, 1.0, atol=2e-3)
    # the same scene given as datasets + camera gives the same buffers
    moved = sphere.translate((0.5, 0, 0), inplace=False)
    g2 = sg.capture([moved, box], window_size=(220, 180), camera=pl.camera)
    assert np.array_equal(g.mask, g2.mask)
    # float32 points translated by VTK vs by the actor matrix: same to float precision, except
    # a pixel or two on a triangle border that the rasteriser gives to the neighbour
    rel = np.abs(g.depth - g2.depth)[g.mask] / g.depth[g.mask]
    assert rel.max() < 1e-5
    assert np.mean(rel < 1e-6) > 0.999
    pl.close()


def test_plotter_never_shown_gets_pyvista_default_view():
    sphere, _ = _two_objects()
    pl = pv.Plotter(off_screen=True, window_size=(120, 100))
    pl.add_mesh(sphere)
    g = sg.capture(pl)
    d = np.subtract(g.camera.position, g.camera.focal_point)
    assert np.allclose(d / np.linalg.norm(d), np.ones(3) / np.sqrt(3))
    assert not pl.camera_set  # capture did not place the plotter's camera
    pl.close()


def test_inputs_are_not_modified():
    nut = pv.examples.load_nut()
    nut.point_data["s"] = np.arange(nut.n_points, dtype=float)
    snap = nut.copy(deep=True)
    names = (list(nut.point_data.keys()), list(nut.cell_data.keys()))
    cam = pv.Camera()
    cam.position, cam.focal_point = (200.0, 0.0, 0.0), (80.0, -80.0, -80.0)
    cam_before = (cam.position, cam.focal_point, cam.clipping_range)
    sg.capture(nut, window_size=(64, 64), camera=cam, scalars="s")
    assert (list(nut.point_data.keys()), list(nut.cell_data.keys())) == names
    assert nut == snap
    assert (cam.position, cam.focal_point, cam.clipping_range) == cam_before


def test_tight_clipping_range():
    sphere, _ = _two_objects()
    g = sg.capture(sphere, window_size=(100, 100), camera=[(0, 0, 10), (0, 0, 0), (0, 1, 0)])
    near, far = g.camera.clipping_range
    assert 9.0 - 0.01 <= near <= 9.0 - 1e-6 + 0.001 * 2
    assert 11.0 <= far <= 11.0 + 0.01


@pytest.mark.parametrize("view", ["xy", "xz", "yz", "yx", "zx", "zy", "iso"])
def test_named_views_fit_the_data(view):
    sphere, _ = _two_objects()
    g = sg.capture(sphere, window_size=(80, 60), camera=view)
    assert 0.1 < g.mask.mean() < 0.9
    assert not g.mask[0].any() and not g.mask[-1].any()  # fitted, not cropped


def test_parallel_eye_inside_the_data_is_moved_back_not_clipping():
    sphere, _ = _two_objects()
    # an orthographic eye at the sphere's centre: moving it back changes nothing in the image
    g = sg.capture(
        sphere,
        window_size=(80, 80),
        camera=[(0, 0, 0), (0, 0, -1), (0, 1, 0)],
        parallel_projection=True,
    )
    ref = sg.capture(
        sphere,
        window_size=(80, 80),
        camera=[(0, 0, 10), (0, 0, 9), (0, 1, 0)],
        parallel_projection=True,
    )
    assert g.mask.sum() > 1000
    assert np.array_equal(g.mask, ref.mask)
    assert np.allclose(g.world, ref.world, equal_nan=True, atol=1e-5)
    # the seen half is the one facing +z (the front of the sphere for this eye)
    assert (g.world[g.mask][:, 2] >= -1e-6).all()


def test_perspective_eye_inside_a_sphere_sees_the_inside():
    sphere, _ = _two_objects()
    g = sg.capture(sphere, window_size=(64, 48), camera=[(0, 0, 0), (0, 0, -1), (0, 1, 0)])
    assert g.mask.all()
    # every point seen is on the sphere, ahead of the eye, and its normal faces the eye
    assert np.allclose(np.linalg.norm(g.world, axis=-1), 1.0, atol=2e-3)
    assert (g.world[..., 2] < 0).all()
    assert (g.normal[..., 2] > 0.9).all()


def test_progress_bar_runs(capsys):
    sphere, _ = _two_objects()
    g = sg.capture(sphere, window_size=(32, 32), progress_bar=True)
    assert g.mask.any()
    assert "capture" in capsys.readouterr().err
