"""Multi-layer G-buffers (``capture(layers=k)``, issue 24 item 2) against analytic geometry:
two nested spheres (four surfaces along central rays), a box behind a plate; layers 2.. to the
tolerances layer 1 meets today (tests/core/test_capture_geometry.py), in both projections and
supersampled; saved and loaded losslessly; bad requests refused."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf.errors import InputError
from tests.helpers.geometry import angle_deg, interior, rays_by_hand, to_eye

CENTER = np.array([0.3, -0.2, 0.5])
RADII = (2.0, 1.0)
CAMERAS = {
    "perspective": dict(camera=[(7.0, -5.0, 4.0), tuple(CENTER), (0, 0, 1)]),
    "parallel": dict(camera=[(7.0, -5.0, 4.0), tuple(CENTER), (0, 0, 1)], parallel_projection=True),
}


@pytest.fixture(scope="module")
def spheres():
    return [pv.Icosphere(radius=r, nsub=6, center=CENTER) for r in RADII]


def _sagitta(sphere, radius) -> float:
    pts = np.asarray(sphere.points, dtype=np.float64)
    tri = sphere.regular_faces
    nrm = np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return radius - np.abs(np.einsum("ij,ij->i", pts[tri[:, 0]] - CENTER, nrm)).min()


def _ray_hits(cam, radius):
    """Entry and exit distances of each pixel's ray through a sphere (NaN: a miss)."""
    o, d = rays_by_hand(cam)
    oc = o - CENTER
    b = np.einsum("ijk,ijk->ij", oc, d)
    c = np.einsum("ijk,ijk->ij", oc, oc) - radius**2
    with np.errstate(invalid="ignore"):
        s = np.sqrt(b * b - c)
    return o, d, -b - s, -b + s


@pytest.mark.parametrize("supersample", [1, 2])
@pytest.mark.parametrize("kind", list(CAMERAS))
def test_nested_spheres_layers_are_the_analytic_intersections(spheres, kind, supersample):
    g = sg.capture(spheres, window_size=(160, 120), layers=4, supersample=supersample,
                   **CAMERAS[kind])  # fmt: skip
    assert len(g.layers) == 3
    cam = g.camera
    o, d, out_in, out_out = _ray_hits(cam, RADII[0])
    _, _, in_in, in_out = _ray_hits(cam, RADII[1])
    hit_outer, hit_inner = np.isfinite(out_in), np.isfinite(in_in)
    # along a ray through both: outer front, inner front, inner back, outer back
    order = [out_in, np.where(hit_inner, in_in, out_out), in_out, out_out]
    counts = [hit_outer, hit_outer, hit_inner, hit_inner]
    # the rims of both discs (a pixel band) are where tessellation and the true spheres part
    rims = ~(interior(hit_outer, 2) | ~hit_outer) | ~(interior(hit_inner, 2) | ~hit_inner)
    sag = max(_sagitta(s, r) for s, r in zip(spheres, RADII, strict=True))
    view = np.subtract(cam.focal_point, cam.position)
    view /= np.linalg.norm(view)
    edge_angle = np.degrees(np.sqrt(4 * np.pi / spheres[0].n_cells * 4 / np.sqrt(3)))
    eye = np.asarray(cam.position)
    for k, layer in enumerate([g, *g.layers]):
        assert layer.shape == g.shape and layer.camera is cam
        ok = ~rims
        # coverage: layer k exists exactly where the ray meets k + 1 surfaces
        assert not (ok & (layer.mask != counts[k])).any(), k
        inner = ok & counts[k]
        assert inner.sum() > 1000 * supersample**2 / (4 if k >= 2 else 1)
        t = order[k]
        world = o + t[..., None] * d
        depth_true = (world - eye) @ view
        r_k = RADII[1] if (k in (1, 2)) else RADII[0]
        r_k = np.where(hit_inner | (k in (0, 3)), r_k, RADII[0])  # a miss of the inner: outer back
        cos_inc = np.abs(np.einsum("ijk,ijk->ij", d, (world - CENTER) / r_k[..., None]))
        err = np.abs(layer.depth - depth_true)[inner]
        assert (err <= 1e-5 * depth_true[inner] + sag / cos_inc[inner]).all(), (k, err.max())
        n_world = (world - CENTER) / r_k[..., None]
        # turned to the viewer's side (against the ray), as the captured normals are
        n_world *= -np.sign(np.einsum("ijk,ijk->ij", n_world, d))[..., None]
        n_true = to_eye(cam, n_world)
        ang = angle_deg(layer.normal[inner], n_true[inner])
        assert ang.max() <= edge_angle, (k, ang.max(), edge_angle)
        radial = np.linalg.norm(layer.world.astype(np.float64) - CENTER, axis=-1)[inner]
        assert (np.abs(radial - r_k[inner]) <= sag * 1.001 + 1e-6 * r_k[inner]).all()
        # which sphere: the inner one for layers 2 and 3 where the ray meets it
        expect = np.where(hit_inner & (k in (1, 2)), 1, 0)
        assert (layer.object_id[inner] == expect[inner]).all(), k
    # the first layer is exactly a one-layer capture's
    one = sg.capture(spheres, window_size=(160, 120), supersample=supersample, **CAMERAS[kind])
    for name, arr in one.channels().items():
        np.testing.assert_array_equal(arr, g.channels()[name], err_msg=name)


def test_box_behind_a_plate():
    """A plate in front of a box: layer 2 is the box's front face where the plate hides it, its
    back face elsewhere; the object ids say which."""
    plate = pv.Plane(center=(0, 0, 2.0), direction=(0, 0, 1), i_size=3, j_size=3)
    box = pv.Box(bounds=(-1, 1, -1, 1, -1, 1))
    cam = [(0.0, 0.0, 10.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
    g = sg.capture([plate, box], window_size=(200, 200), camera=cam, layers=3,
                   parallel_projection=True)  # fmt: skip
    l2, l3 = g.layers
    centre = interior(l2.mask & (l2.object_id == 1), 2)
    assert centre.sum() > 3000
    # plate at z = 2 (depth 8), box front z = 1 (depth 9), back z = -1 (depth 11)
    np.testing.assert_allclose(g.depth[centre], 8.0, atol=1e-5)
    np.testing.assert_allclose(l2.depth[centre], 9.0, atol=1e-5)
    np.testing.assert_allclose(l3.depth[centre], 11.0, atol=1e-5)
    np.testing.assert_allclose(l2.world[centre][:, 2], 1.0, atol=1e-5)
    np.testing.assert_allclose(np.abs(l2.normal[centre][:, 2]), 1.0, atol=1e-6)
    assert (g.object_id[centre] == 0).all() and (l3.object_id[centre] == 1).all()
    # where only the plate is: nothing behind
    only_plate = interior(g.mask, 2) & ~l2.mask
    assert only_plate.sum() > 1000 and not l3.mask[only_plate].any()


def test_layers_save_and_load(tmp_path, spheres):
    g = sg.capture(spheres, window_size=(64, 48), layers=3, **CAMERAS["perspective"])
    for suffix in (".npz", ".vti"):
        back = sg.GBuffer.load(g.save(tmp_path / f"g{suffix}"))
        assert len(back.layers) == 2
        for a, b in zip([g, *g.layers], [back, *back.layers], strict=True):
            for name, arr in a.channels().items():
                np.testing.assert_array_equal(arr, b.channels()[name], err_msg=name)


@pytest.mark.parametrize("bad", [0, 9, 2.5, "3", True, None])
def test_bad_layer_counts_are_refused(spheres, bad):
    with pytest.raises(InputError, match="layers"):
        sg.capture(spheres, window_size=(32, 24), layers=bad)
