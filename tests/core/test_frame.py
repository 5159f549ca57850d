"""G-buffers from a frame's own depth image agree with ``capture`` of the same view."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from vtkmodules.vtkRenderingCore import vtkCamera

import sciviz_gbuf as sg
from sciviz_gbuf.core import CameraInfo, gbuffer_from_zbuffer, read_zbuffer
from sciviz_gbuf.errors import InputError


def _frame(mesh, size=(160, 120), parallel=False, azimuth=25.0, elevation=20.0):
    """A plotter without multisampling, its frame's G-buffer and a capture of the same view."""
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.add_mesh(mesh)
    pl.disable_anti_aliasing()
    pl.render_window.SetMultiSamples(0)
    if parallel:
        pl.enable_parallel_projection()
    pl.camera.azimuth += azimuth
    pl.camera.elevation += elevation
    pl.screenshot()
    ren = pl.renderer
    z = read_zbuffer(pl.render_window, ren.GetOrigin(), ren.GetSize())
    got = gbuffer_from_zbuffer(z, CameraInfo.from_vtk(ren.GetActiveCamera(), ren.GetSize()))
    ref = sg.capture(pl)
    pl.close()
    return got, ref


@pytest.mark.parametrize("parallel", [False, True])
def test_frame_channels_equal_the_capture_to_float32(parallel):
    box = pv.Box(bounds=(-1, 1, -0.6, 0.6, -0.3, 0.3)).triangulate()  # flat faces, creases
    got, ref = _frame(box, parallel=parallel)
    np.testing.assert_array_equal(got.mask, ref.mask)
    m = ref.mask
    assert m.sum() > 3000
    np.testing.assert_allclose(got.depth[m], ref.depth[m], rtol=2e-6)
    np.testing.assert_allclose(got.sz[m], ref.sz[m], rtol=2e-6)
    assert np.isnan(got.depth[~m]).all() and np.isnan(got.normal[~m]).all()
    # every pixel takes its own face's normal, the pixels next to a crease included
    dots = (got.normal[m].astype(np.float64) * ref.normal[m]).sum(-1)
    assert np.percentile(dots, 0.5) > np.cos(np.radians(1.0)), np.degrees(np.arccos(dots.min()))
    np.testing.assert_allclose(np.linalg.norm(got.normal[m], axis=-1), 1.0, atol=1e-6)
    assert got.supersample == 1 and got.camera.window_size == (160, 120)


def test_frame_edges_equal_the_capture_edges():
    nut = sg.datasets.load_nut()
    got, ref = _frame(nut, size=(320, 240))
    a = sg.filters.edge_map(got, crease_angle=30.0)
    b = sg.filters.edge_map(ref, crease_angle=30.0)
    prof, inner = b[..., 3] >= 0.9, (b[..., 0] >= 0.9) & (b[..., 3] <= 0.1)
    assert prof.sum() > 500 and inner.sum() > 300
    assert (a[..., 3][prof] >= 0.9).mean() >= 0.99
    assert (a[..., 0][inner] >= 0.9).mean() >= 0.95
    strong = (a[..., 3] >= 0.9) | (a[..., 0] >= 0.9)
    assert ((b[..., 3] > 0.3) | (b[..., 0] > 0.3))[strong].mean() >= 0.99  # no stray lines


def _camera(w: int, h: int, parallel: bool) -> CameraInfo:
    cam = vtkCamera()
    cam.SetPosition(0, 0, 5)
    cam.SetClippingRange(1, 10)
    cam.SetParallelProjection(parallel)
    return CameraInfo.from_vtk(cam, (w, h))


@settings(max_examples=60, deadline=None)
@given(
    z=hnp.arrays(
        np.float32,
        hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=7),
        elements=st.one_of(
            st.floats(0, 1, width=32),
            st.sampled_from([np.nan, np.inf, -np.inf, -0.5, 2.0, 1.0, 0.0]),
        ),
    ),
    parallel=st.booleans(),
)
def test_odd_depth_images_give_unit_normals_on_the_mask_only(z, parallel):
    h, w = z.shape
    gb = gbuffer_from_zbuffer(z, _camera(w, h, parallel))
    ok = (z >= 0) & (z < 1)
    np.testing.assert_array_equal(gb.mask, ok[::-1])
    m = gb.mask
    assert np.isfinite(gb.depth[m]).all() and (gb.depth[m] > 0).all()
    assert np.isfinite(gb.sz[m]).all()
    np.testing.assert_allclose(np.linalg.norm(gb.normal[m], axis=-1), 1.0, atol=1e-5)
    assert np.isnan(gb.depth[~m]).all() and np.isnan(gb.normal[~m]).all()
    assert not np.shares_memory(gb.depth, z)


def test_bad_inputs_are_refused_by_name():
    cam = _camera(4, 3, False)
    with pytest.raises(InputError, match="zbuffer"):
        gbuffer_from_zbuffer(np.zeros((3, 4, 2), np.float32), cam)
    with pytest.raises(InputError, match="zbuffer"):
        gbuffer_from_zbuffer(np.zeros((3, 4), np.int32), cam)
    with pytest.raises(InputError, match="window_size"):
        gbuffer_from_zbuffer(np.zeros((4, 3), np.float32), cam)
    with pytest.raises(InputError, match="camera"):
        gbuffer_from_zbuffer(np.zeros((3, 4), np.float32), "iso")
