"""Captured G-buffers against analytic geometry (sphere, tilted plane), both projections."""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv

import sciviz_gbuf as sg
from tests.helpers.geometry import angle_deg, interior, rays_by_hand, to_eye

RADIUS = 2.0
CENTER = np.array([0.3, -0.2, 0.5])


@pytest.fixture(scope="module")
def sphere():
    s = pv.Icosphere(radius=RADIUS, nsub=7, center=CENTER)
    s.point_data["height"] = np.asarray(s.points[:, 2], dtype=np.float64)
    return s


def _sphere_hits(cam):
    o, d = rays_by_hand(cam)
    oc = o - CENTER
    b = np.einsum("ijk,ijk->ij", oc, d)
    c = np.einsum("ijk,ijk->ij", oc, oc) - RADIUS**2
    disc = b * b - c
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(disc)
    hit = disc > 0
    world = o + t[..., None] * d
    return hit, world, d


CAMERAS = {
    "perspective": dict(camera=[(7.0, -5.0, 4.0), tuple(CENTER), (0, 0, 1)]),
    "parallel": dict(camera=[(7.0, -5.0, 4.0), tuple(CENTER), (0, 0, 1)], parallel_projection=True),
}


@pytest.mark.parametrize("kind", list(CAMERAS))
def test_sphere_depth_world_normals_sz(sphere, kind):
    g = sg.capture(sphere, window_size=(320, 240), scalars=["height"], **CAMERAS[kind])
    cam = g.camera
    assert cam.parallel_projection == (kind == "parallel")
    hit, world, d = _sphere_hits(cam)
    inner = interior(g.mask)
    # coverage agrees with the analytic disc except on the 1-px silhouette band
    assert not (inner & ~hit).any()
    assert not (interior(hit) & ~g.mask).any()
    assert inner.sum() > 10000

    eye = np.asarray(cam.position)
    view = np.subtract(cam.focal_point, cam.position)
    view /= np.linalg.norm(view)
    depth_true = (world - eye) @ view
    # Against the true sphere the facets' own deviation (sagitta) is allowed, stretched along
    # the ray by 1/cos(incidence); exactness against the facets themselves is checked below.
    pts = np.asarray(sphere.points, dtype=np.float64)
    tri = sphere.regular_faces
    nrm = np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    sagitta = RADIUS - np.abs(np.einsum("ij,ij->i", pts[tri[:, 0]] - CENTER, nrm)).min()
    assert 0 < sagitta < 1e-4 * RADIUS
    radial = np.linalg.norm(g.world.astype(np.float64) - CENTER, axis=-1)[inner]
    assert (radial <= RADIUS * (1 + 1e-6)).all() and (radial >= RADIUS - sagitta * 1.001).all()
    cos_inc = np.abs(np.einsum("ijk,ijk->ij", d, (world - CENTER) / RADIUS))[inner]
    along_ray = np.linalg.norm(g.world - world, axis=-1)[inner]
    dist = np.linalg.norm(world - eye, axis=-1)[inner]
    assert (along_ray <= 1e-5 * dist + sagitta / cos_inc).all()
    depth_err = np.abs(g.depth - depth_true)[inner]
    assert (depth_err <= 1e-5 * depth_true[inner] + sagitta / cos_inc).all()
    # at near-normal incidence the tessellation error is far below the 1e-5 budget
    centre = cos_inc > 0.5
    assert (depth_err[centre] / depth_true[inner][centre]).max() <= 1e-5

    # normals: unit, facing the viewer, within the tessellation's angular error (~edge/radius)
    n_true = to_eye(cam, (world - CENTER) / RADIUS)
    n = g.normal[inner]
    assert np.allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-5)
    ang = angle_deg(n, n_true[inner])
    edge_angle = np.degrees(np.sqrt(4 * np.pi / sphere.n_cells * 4 / np.sqrt(3)))
    assert ang.max() <= edge_angle, (ang.max(), edge_angle)

    # sz = d^2 / (w z_v) (Saito Eq. 6) from the camera, w = pixel size on the focal plane
    dist = np.linalg.norm(np.subtract(cam.focal_point, cam.position))
    h = cam.window_size[1]
    if cam.parallel_projection:
        w = 2 * cam.parallel_scale / h
        sz_true = (2 * dist - depth_true) / w
    else:
        w = 2 * dist * np.tan(np.radians(cam.view_angle) / 2) / h
        sz_true = dist**2 / (w * depth_true)
    assert np.allclose(
        g.sz[inner],
        dist**2 / (w * g.depth[inner])
        if not cam.parallel_projection
        else (2 * dist - g.depth[inner]) / w,
        rtol=1e-6,
    )
    assert np.allclose(g.sz[inner][centre], sz_true[inner][centre], rtol=1e-5)
    assert cam.pixel_size == pytest.approx(w, rel=1e-12)

    # a linear point scalar interpolates exactly to the hit's z
    assert np.allclose(g.scalars["height"][inner], g.world[..., 2][inner], atol=1e-5 * RADIUS)

    # background
    bg = ~g.mask
    assert bg.any()
    for a in (g.depth, g.sz, g.world[..., 0], g.normal[..., 0], g.scalars["height"]):
        assert np.isnan(a[bg]).all()
    assert (g.object_id[bg] == -1).all() and (g.cell_id[bg] == -1).all()
    for a in (g.depth, g.sz, g.world, g.normal, g.scalars["height"]):
        assert a.dtype == np.float32


def _tilted_plane():
    plane = pv.Plane(
        center=(0, 0, 0), direction=(0, 0, 1), i_size=4, j_size=3, i_resolution=3, j_resolution=2
    )
    plane = (
        plane.rotate_x(35, inplace=False).rotate_y(-20, inplace=False).translate((0.5, 0.2, -0.3))
    )
    n = np.asarray(plane.point_data["Normals"][0], dtype=np.float64)
    return plane, n / np.linalg.norm(n), np.asarray(plane.points[0], dtype=np.float64)


@pytest.mark.parametrize("kind", ["perspective", "parallel"])
def test_tilted_plane_exact(kind):
    plane, n, p0 = _tilted_plane()
    cam = [(3.0, -6.0, 5.0), (0.4, 0.1, -0.2), (0, 0, 1)]
    g = sg.capture(
        plane, window_size=(300, 220), camera=cam, parallel_projection=kind == "parallel"
    )
    c = g.camera
    o, d = rays_by_hand(c)
    t = ((p0 - o) @ n) / (d @ n)
    world = o + t[..., None] * d
    inner = interior(g.mask)
    assert inner.sum() > 5000
    eye = np.asarray(c.position)
    view = np.subtract(c.focal_point, c.position)
    view /= np.linalg.norm(view)
    depth_true = (world - eye) @ view
    assert (np.abs(g.depth - depth_true)[inner] / depth_true[inner]).max() <= 1e-5
    err = (
        np.linalg.norm(g.world - world, axis=-1)[inner]
        / np.linalg.norm(world - eye, axis=-1)[inner]
    )
    assert err.max() <= 1e-5
    # the plane's normal, turned towards the viewer, in eye space: <= 0.01 degree everywhere
    n_eye = to_eye(c, n if (eye - p0) @ n > 0 else -n)
    ang = angle_deg(g.normal[g.mask], n_eye)
    assert ang.max() <= 0.01
    # texture coordinates of pv.Plane are linear in position: interpolation is exact
    assert g.uv is not None
    assert np.isfinite(g.uv[g.mask]).all()
    assert g.uv[g.mask].min() >= -1e-6 and g.uv[g.mask].max() <= 1 + 1e-6


def test_sphere_normals_from_data_are_used(sphere):
    s = sphere.copy()
    s.point_data["Normals"] = (np.asarray(s.points) - CENTER) / RADIUS
    s.point_data.active_normals_name = "Normals"  # type: ignore[attr-defined]
    g = sg.capture(s, window_size=(200, 200), camera="xy")
    _, world, _ = _sphere_hits(g.camera)
    inner = interior(g.mask)
    n_true = to_eye(g.camera, (world - CENTER) / RADIUS)
    ang = angle_deg(g.normal[inner], n_true[inner])
    # exact vertex normals: interpolation error is below half the edge angle
    assert ang.max() < 0.5 * np.degrees(np.sqrt(4 * np.pi / s.n_cells * 4 / np.sqrt(3)))


@pytest.mark.parametrize("parallel", [False, True])
def test_camera_helpers_agree_with_the_buffers(sphere, parallel):
    g = sg.capture(sphere, window_size=(90, 70), camera="yz", parallel_projection=parallel)
    # sz from the public helper equals the captured channel
    assert np.array_equal(g.camera.sz_from_depth(g.depth), g.sz, equal_nan=True)
    # pixel_rays (from VTK's matrices) equal the textbook rays, and every hit lies on its ray
    o, d = g.camera.pixel_rays()
    o2, d2 = rays_by_hand(g.camera)
    assert np.allclose(d, d2, atol=1e-12)
    w = o - o2  # origins differ only along the ray (near plane vs eye)
    assert np.allclose(w - np.sum(w * d2, axis=-1, keepdims=True) * d2, 0.0, atol=1e-9)
    v = g.world.astype(np.float64) - o
    off_ray = np.linalg.norm(v - np.sum(v * d, axis=-1, keepdims=True) * d, axis=-1)
    assert off_ray[g.mask].max() < 1e-5 * RADIUS
    assert g.camera.to_vtk().GetPosition() == pytest.approx(g.camera.position)
