"""Mirrored, edge-enhanced scenes (Nienhaus & Döllner 2003 §5, Fig. 8).

The reflected G-buffer is checked against hand-built geometry: main-camera pixel rays (from
``tests.helpers.geometry.rays_by_hand``, which shares no code with the package), reflected at
the mirror plane and intersected analytically with a sphere.
"""

from __future__ import annotations

import numpy as np
import pytest
import pyvista as pv
from scipy import ndimage
from vtkmodules.vtkRenderingCore import vtkCamera

from sciviz_gbuf.core import capture
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.filters import profile_edges
from sciviz_gbuf.styles.mirror import default_style, mirror_enhance, mirror_gbuffers
from tests.helpers.geometry import angle_deg, interior, rays_by_hand

# A floor mirror (z = 0, front +z), a sphere off to the right above it, a cube entirely below
# it (behind the mirror) and a post that goes through it.
CENTRE = np.array([0.8, -0.3, 0.7])
RADIUS = 0.5
CAMERA = ((0.0, -6.0, 4.5), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
WINDOW = (240, 180)
MIRROR, SPHERE, CUBE, POST = 0, 1, 2, 3


def _scene() -> list[pv.DataSet]:
    return [
        pv.Plane(center=(0, 0, 0), direction=(0, 0, 1), i_size=4, j_size=3),
        pv.Sphere(radius=RADIUS, center=CENTRE, theta_resolution=90, phi_resolution=90),
        pv.Cube(center=(-0.5, 0.3, -1.0), x_length=0.6, y_length=0.6, z_length=0.6),
        pv.Cylinder(center=(-1.0, 0.6, -0.3), direction=(0, 0, 1), radius=0.15, height=1.2),
    ]


@pytest.fixture(scope="module")
def buffers():
    return mirror_gbuffers(_scene(), MIRROR, camera=CAMERA, window_size=WINDOW)


def _reflected_rays(main, point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)):
    """Main pixel rays by hand, reflected at a plane: hit point on the plane, new direction."""
    origin, d = rays_by_hand(main.camera)
    p, n = np.asarray(point, dtype=np.float64), np.asarray(normal, dtype=np.float64)
    t = ((p - origin) @ n) / (d @ n)
    hit = origin + t[..., None] * d
    return hit, d - 2.0 * (d @ n)[..., None] * n


def _sphere_hits(o, d):
    """First intersection of rays o + s d (unit d) with the sphere; NaN where they miss."""
    oc = o - CENTRE
    b = np.sum(oc * d, axis=-1)
    disc = b * b - (np.sum(oc * oc, axis=-1) - RADIUS**2)
    s = -b - np.sqrt(np.where(disc > 0, disc, np.nan))
    s = np.where(s > 0, s, np.nan)
    return o + s[..., None] * d


TILT = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
TILT_CENTRE = (0.2, 0.1, -0.1)


def _parallel_camera():
    cam = vtkCamera()
    cam.SetPosition(*CAMERA[0])
    cam.SetFocalPoint(*CAMERA[1])
    cam.SetViewUp(*CAMERA[2])
    cam.SetParallelProjection(True)
    cam.SetParallelScale(2.2)
    return cam


@pytest.mark.parametrize("case", ["floor", "tilted", "parallel"])
def test_reflected_world_is_the_reflected_ray_hit(case, buffers):
    point, normal = (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)
    if case == "floor":
        main, refl, plane = buffers
    elif case == "tilted":
        point, normal = TILT_CENTRE, TILT
        mirror = pv.Plane(center=point, direction=normal, i_size=5, j_size=4)
        scene = [mirror, _scene()[SPHERE]]
        main, refl, plane = mirror_gbuffers(scene, 0, camera=CAMERA, window_size=WINDOW)
    else:
        main, refl, plane = mirror_gbuffers(
            _scene(), MIRROR, camera=_parallel_camera(), window_size=WINDOW
        )
        assert main.camera.parallel_projection and refl.camera.parallel_projection
    np.testing.assert_allclose(plane.normal, normal, atol=1e-6)
    hit, rd = _reflected_rays(main, point, normal)
    truth = _sphere_hits(hit, rd)
    on_mirror = main.object_id == MIRROR
    analytic = on_mirror & np.isfinite(truth[..., 0])
    seen = on_mirror & (refl.object_id == SPHERE)
    assert analytic.sum() > 800  # the reflection is a sizeable disc
    # same pixels (up to the silhouette of the tessellated sphere)
    assert (analytic ^ seen).sum() <= 0.03 * analytic.sum()
    # same points, away from the silhouette where a facet and the sphere can disagree
    core = interior(analytic, 2) & seen
    err = np.linalg.norm(refl.world[core] - truth[core], axis=-1)
    assert core.sum() > 600
    assert np.median(err) < 1e-3 and err.max() < 5e-3, (np.median(err), err.max())
    # without the left-right flip the same comparison fails almost everywhere
    bad = np.linalg.norm(refl.world[:, ::-1][core] - truth[core], axis=-1)
    assert np.mean(bad < 0.01 * RADIUS) < 0.05


def test_reflected_camera_rays_and_normals(buffers):
    main, refl, _ = buffers
    # The stored camera (view matrix with x -> -x) gives the reflected main rays per pixel.
    _, rd = _reflected_rays(main)
    _, d = refl.camera.pixel_rays()
    assert angle_deg(d, rd).max() < 1e-5
    np.testing.assert_allclose(refl.camera.position, [0.0, -6.0, -4.5], atol=1e-12)
    # world_normal() of the flipped buffer is the sphere's real outward normal (exact: the
    # sphere's vertex normals interpolate linearly to (p - centre) / r)
    m = interior(refl.object_id == SPHERE, 2)
    true_n = (refl.world[m] - CENTRE) / RADIUS
    assert angle_deg(refl.world_normal()[m], true_n).max() < 0.01
    # eye-space normals face the viewer, like any G-buffer's
    assert (refl.normal[m][:, 2] > 0).all()


def test_objects_behind_the_mirror_do_not_show(buffers):
    main, refl, _ = buffers
    on_mirror = main.object_id == MIRROR
    assert not (refl.object_id == CUBE).any()
    post = refl.object_id == POST
    assert post.any()  # its upper half is reflected...
    assert refl.world[post][:, 2].min() > -1e-4  # ...its lower half is not
    # The test means something: without the clip, both would appear in the mirror.
    scene = _scene()
    raw = capture(scene[1:], window_size=WINDOW, camera=refl.camera)  # to_vtk(): unflipped
    ids = raw.object_id[:, ::-1]
    assert ((ids == CUBE - 1) & on_mirror).sum() > 100
    below = (ids == POST - 1) & on_mirror & (raw.world[:, ::-1, 2] < -0.05)
    assert below.sum() > 30


def test_reflected_profiles_in_the_mirror():
    """The acceptance point: the reflected object has its own profile edges in the mirror."""
    scene = _scene()
    kw = {"camera": CAMERA, "window_size": WINDOW, "supersample": 2}
    out = mirror_enhance(scene, MIRROR, **kw)
    main, refl, _ = mirror_gbuffers(scene, MIRROR, **kw)
    cover = main.downsample((main.object_id == MIRROR).astype(np.float32))
    inside = ndimage.binary_erosion(cover == 1.0, iterations=3)
    ink_refl = profile_edges(refl)
    ink_main = profile_edges(main)
    lines = inside & (ink_refl > 0.5)
    assert lines.sum() > 60  # the reflected sphere's outline
    grey = out.mean(axis=2)
    assert np.mean(grey[lines] < 0.35) > 0.9, np.percentile(grey[lines], [50, 90])
    # The naive way (edges from the main view only) has no line there: the mirror is a plane.
    assert (ink_main[inside] > 0.1).sum() == 0
    main_img = default_style(main)
    naive = main_img.mean(axis=2)
    assert np.mean(naive[lines] > 0.6) > 0.95
    # The mirror's own outline (against the paper) is kept, dark.
    rim = (
        (ink_main > 0.9)
        & (cover > 0.5)
        & ~ndimage.binary_dilation(
            main.downsample((main.object_id != MIRROR) & main.mask).astype(bool), iterations=2
        )
    )
    assert rim.sum() > 100
    np.testing.assert_allclose(out[rim], main_img[rim], atol=0.05)
    assert grey[rim].max() < 0.45 < 0.9 < np.median(grey[inside])
    # The reflection is tinted: on the mirror, blue >= red.
    calm = inside & (ink_refl == 0)
    assert (out[calm][:, 2] >= out[calm][:, 0]).all() and (out[calm][:, 2] > out[calm][:, 0]).any()
    # deterministic
    np.testing.assert_array_equal(out, mirror_enhance(scene, MIRROR, **kw))


def test_non_planar_mirror_is_rejected():
    scene = _scene()
    bent = scene[MIRROR].copy()
    bent.points[5, 2] += 0.05
    with pytest.raises(InputError, match="not planar"):
        mirror_gbuffers([bent, *scene[1:]], 0, camera=CAMERA, window_size=WINDOW)
    with pytest.raises(InputError, match="not planar"):
        mirror_gbuffers(scene[1:], 0, camera=CAMERA, window_size=WINDOW)  # a sphere


def test_camera_behind_the_mirror_is_rejected():
    scene = _scene()
    below = ((0.0, -6.0, -4.5), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    with pytest.raises(InputError, match="behind the mirror"):
        mirror_gbuffers(scene, MIRROR, camera=below, window_size=WINDOW)
    # the front is the side the faces point to: a plane facing down has the camera behind it
    scene[MIRROR] = pv.Plane(direction=(0, 0, -1), i_size=4, j_size=3)
    with pytest.raises(InputError, match="behind the mirror"):
        mirror_gbuffers(scene, MIRROR, camera=CAMERA, window_size=WINDOW)


def test_nothing_in_front_of_the_mirror():
    # Only an object behind the mirror: the reflected pass is all background (paper).
    scene = [_scene()[MIRROR], _scene()[CUBE]]
    main, refl, _ = mirror_gbuffers(scene, 0, camera=CAMERA, window_size=(80, 60))
    assert not refl.mask.any() and (refl.object_id == -1).all()
    out = mirror_enhance(scene, 0, camera=CAMERA, window_size=(80, 60))
    cover = main.downsample((main.object_id == 0).astype(np.float32))
    inside = ndimage.binary_erosion(cover == 1.0, iterations=2)
    np.testing.assert_allclose(out[inside], np.broadcast_to([0.9, 0.95, 1.0], out[inside].shape))
