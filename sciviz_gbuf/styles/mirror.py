"""Edge enhancement of a scene with a planar mirror (Nienhaus & Döllner 2003 §5, Fig. 8).

The paper renders a mirrored scene in "two rendering passes, one for the scene without mirror
and one for the mirror", and applies the edge-enhancement algorithm twice, "for the original
scene and for the mirrored scene. The scene is rendered from different viewpoints and, hence,
the edges are detected correctly". Edges found in the main view alone cannot do this: there
the mirror is one flat plane, whose G-buffer has no discontinuity where the reflected objects
have their profiles.

Here the two passes are two :func:`~sciviz_gbuf.capture` calls:

1. the main pass, the whole scene from the given camera;
2. the reflected pass, from the camera reflected about the mirror plane (position, focal point
   and view up), of the scene without the mirror and with every other object clipped to the
   mirror's front half-space (what lies behind a mirror is not seen in it).

Reflection reverses handedness: the reflected camera's right vector is *minus* the reflection
of the main camera's right vector, so the ray through main pixel ``(r, c)``, reflected at the
plane, is the ray of the reflected camera's pixel ``(r, W - 1 - c)``. The reflected G-buffer is
therefore flipped left-right, its eye-space normals get ``x -> -x`` and its camera's view matrix
is pre-multiplied by ``diag(-1, 1, 1, 1)``. After this, pixel ``(r, c)`` of both G-buffers
belongs to the same (main-view) ray, and the reflected G-buffer is exactly the G-buffer of the
main camera looking at the mirror image of the scene, except that ``world`` holds the *real*
world point that the reflected ray hits (and ``world_normal()`` its real normal).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np
import pyvista as pv

from ..core.camera import CameraInfo
from ..core.capture import capture
from ..core.gbuffer import GBuffer
from ..core.scene import make_surface
from ..errors import InputError
from ..filters import edge_map, enhance, profile_edges
from .illustration import shade_image

__all__ = ["MirrorPlane", "default_style", "mirror_enhance", "mirror_gbuffers", "mirror_plane"]

#: Largest distance of a mirror point from its fitted plane, relative to the mirror's size.
PLANARITY_TOLERANCE = 1e-5
# Width in output pixels of the main view's profile lines under which the main image is kept
# over the reflection, so that the mirror's outline (and the profiles of objects in front of
# it) stay as the main style drew them; 2 covers the 2003 lines, which straddle the edge.
_OUTLINE_WIDTH = 2.0


@dataclasses.dataclass(frozen=True)
class MirrorPlane:
    """The plane of a planar mirror.

    Attributes
    ----------
    origin : (3,) float64
        The centroid of the mirror's points (a point of the plane).
    normal : (3,) float64
        Unit normal towards the mirror's front: the side its faces are oriented to, where the
        camera must be.
    """

    origin: np.ndarray
    normal: np.ndarray

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """Distance of ``(..., 3)`` points from the plane, positive in front."""
        return (np.asarray(points, dtype=np.float64) - self.origin) @ self.normal

    def reflect_points(self, points: np.ndarray) -> np.ndarray:
        """Mirror images of ``(..., 3)`` points."""
        p = np.asarray(points, dtype=np.float64)
        return p - 2.0 * self.signed_distance(p)[..., None] * self.normal

    def reflect_vectors(self, vectors: np.ndarray) -> np.ndarray:
        """Mirror images of ``(..., 3)`` direction vectors (no translation)."""
        v = np.asarray(vectors, dtype=np.float64)
        return v - 2.0 * (v @ self.normal)[..., None] * self.normal

    def householder(self) -> np.ndarray:
        """The reflection as a 4x4 homogeneous matrix (float64, determinant -1)."""
        n = self.normal
        m = np.eye(4)
        m[:3, :3] -= 2.0 * np.outer(n, n)
        m[:3, 3] = 2.0 * float(self.origin @ n) * n
        return m


def _as_dataset(obj: object, what: str) -> pv.DataSet:
    try:
        ds = pv.wrap(obj)
    except Exception as exc:  # pyvista raises several types for unwrappable objects
        raise InputError(
            f"{what}: expected a PyVista/VTK dataset, got {type(obj).__name__}"
        ) from exc
    if not isinstance(ds, pv.DataSet):
        raise InputError(f"{what}: expected a PyVista/VTK dataset, got {type(obj).__name__}")
    return ds


def _check_scene(scene: object, mirror: object) -> tuple[list[pv.DataSet], int]:
    if isinstance(scene, (str, bytes)) or not isinstance(scene, Sequence):
        raise InputError(f"scene: expected a list of PyVista datasets, got {type(scene).__name__}")
    items = [_as_dataset(d, f"scene[{i}]") for i, d in enumerate(scene)]
    if not items:
        raise InputError("scene: empty; expected a list of PyVista datasets")
    if isinstance(mirror, bool) or not isinstance(mirror, (int, np.integer)):
        raise InputError(f"mirror: expected the index of the mirror in scene, got {mirror!r}")
    if not -len(items) <= int(mirror) < len(items):
        raise InputError(f"mirror: index {mirror} out of range for a scene of {len(items)}")
    return items, int(mirror) % len(items)


def mirror_plane(mesh: pv.DataSet, *, tolerance: float = PLANARITY_TOLERANCE) -> MirrorPlane:
    """Fit a plane to a mirror's points and orient it by the mirror's faces.

    Parameters
    ----------
    mesh : pyvista.DataSet
        The mirror: a planar surface (e.g. ``pyvista.Plane``).
    tolerance : float
        Largest allowed distance of a point from the least-squares plane, relative to the
        diagonal of the mirror's bounding box.

    Returns
    -------
    MirrorPlane

    Raises
    ------
    InputError
        Fewer than three points, collinear points, points off the plane, or faces whose
        orientations cancel (the front of the mirror is undefined).
    """
    pts = np.asarray(mesh.points, dtype=np.float64)
    if pts.shape[0] < 3 or not np.isfinite(pts).all():
        raise InputError("mirror: needs at least three finite points")
    centre = pts.mean(axis=0)
    # Least-squares plane: the direction of least spread of the centred points.
    _, s, vt = np.linalg.svd(pts - centre, full_matrices=False)
    size = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
    if size == 0.0 or s[1] <= 1e-9 * s[0]:
        raise InputError("mirror: its points are collinear or coincide; it spans no plane")
    normal = vt[2]
    off = float(np.abs((pts - centre) @ normal).max())
    if off > tolerance * size:
        raise InputError(
            f"mirror: not planar; a point lies {off:.3g} from the fitted plane "
            f"({off / size:.2e} of its size, tolerance {tolerance:.0e})"
        )
    # The front is where the faces point to (the area-weighted sum of their normals).
    surf = make_surface("mirror", mesh, None, 180.0)  # the triangles capture() will draw
    tri, sp = surf.triangles, surf.points
    cross = np.cross(sp[tri[:, 1]] - sp[tri[:, 0]], sp[tri[:, 2]] - sp[tri[:, 0]])
    along = float(cross.sum(axis=0) @ normal)
    if abs(along) < 0.5 * float(np.linalg.norm(cross, axis=1).sum()):
        raise InputError(
            "mirror: its faces are not consistently oriented, so its front side is undefined"
        )
    if along < 0.0:
        normal = -normal
    return MirrorPlane(origin=centre, normal=normal)


def _reflected_camera(main: CameraInfo, plane: MirrorPlane):
    """A vtkCamera: the main camera's eye, focal point and view up reflected about the plane."""
    cam = main.to_vtk()  # keeps view angle, projection and parallel scale
    cam.SetPosition(*plane.reflect_points(np.asarray(main.position)))
    cam.SetFocalPoint(*plane.reflect_points(np.asarray(main.focal_point)))
    cam.SetViewUp(*plane.reflect_vectors(np.asarray(main.view_up)))
    return cam


def _empty_gbuffer(cam, size: tuple[int, int], supersample: int, names: list[str]) -> GBuffer:
    """An all-background G-buffer (nothing in front of the mirror)."""
    w, h = size
    cam.SetClippingRange(1e-3 * max(cam.GetDistance(), 1e-12), 1e3 * max(cam.GetDistance(), 1))
    nan = np.float32(np.nan)
    return GBuffer(
        depth=np.full((h, w), nan),
        sz=np.full((h, w), nan),
        normal=np.full((h, w, 3), nan),
        world=np.full((h, w, 3), nan),
        object_id=np.full((h, w), -1, dtype=np.int32),
        cell_id=np.full((h, w), -1, dtype=np.int64),
        mask=np.zeros((h, w), dtype=bool),
        camera=CameraInfo.from_vtk(cam, size),
        supersample=supersample,
        object_names=list(names),
    )


def _flip_left_right(gb: GBuffer, ids: np.ndarray, names: list[str]) -> GBuffer:
    """The reflected pass lined up with the main view (see the module docstring).

    Columns reversed; eye-space normals and the view matrix get ``x -> -x`` so that eye space,
    pixel positions and normals stay consistent for the edge operators (the crease-sign test
    uses eye-space positions from pixel columns); object ids mapped back to the scene's indices.
    """
    flip = np.diag([-1.0, 1.0, 1.0, 1.0])
    view = flip @ gb.camera.view_matrix_array
    camera = dataclasses.replace(gb.camera, view_matrix=tuple(float(v) for v in view.ravel()))
    normal = gb.normal[:, ::-1].copy()
    normal[..., 0] *= -1.0
    # index -1 (background) picks the appended -1
    lut = np.append(np.asarray(ids, dtype=np.int32), np.int32(-1))
    object_id = lut[gb.object_id[:, ::-1]]
    return GBuffer(
        depth=gb.depth[:, ::-1].copy(),
        sz=gb.sz[:, ::-1].copy(),
        normal=normal,
        world=gb.world[:, ::-1].copy(),
        object_id=object_id,
        cell_id=gb.cell_id[:, ::-1].copy(),
        mask=gb.mask[:, ::-1].copy(),
        camera=camera,
        uv=None if gb.uv is None else gb.uv[:, ::-1].copy(),
        scalars={k: v[:, ::-1].copy() for k, v in gb.scalars.items()},
        supersample=gb.supersample,
        object_names=list(names),
    )


def mirror_gbuffers(
    scene: Sequence[pv.DataSet],
    mirror: int,
    *,
    camera: object,
    window_size: Sequence[int] = (640, 480),
    supersample: int = 1,
) -> tuple[GBuffer, GBuffer, MirrorPlane]:
    """The two G-buffers of a mirrored scene (Nienhaus & Döllner 2003 §5, Fig. 8).

    Parameters
    ----------
    scene : list of pyvista.DataSet
        The objects; ``object_id`` in both G-buffers is the index in this list.
    mirror : int
        Index of the planar mirror in ``scene``. Its front is the side its faces point to.
    camera : str, vtkCamera, CameraInfo or (position, focal_point, view_up)
        The main camera, as for :func:`~sciviz_gbuf.capture`.
    window_size : (int, int), default: (640, 480)
        Output size ``(width, height)`` of both passes.
    supersample : int, default: 1
        As for :func:`~sciviz_gbuf.capture`.

    Returns
    -------
    main : GBuffer
        The whole scene, mirror included, from ``camera``.
    reflected : GBuffer
        The scene without the mirror, clipped to the mirror's front half-space, from the
        reflected camera, flipped left-right so that its pixel ``(r, c)`` is the main ray of
        pixel ``(r, c)`` after reflection at the mirror plane (meaningful where
        ``main.object_id == mirror``). ``world`` holds real world points; ``normal`` is in the
        (left-right mirrored) eye space of the flipped image; ``camera`` has the reflected
        position, focal point and view up and a view matrix with ``x -> -x``, so that
        ``camera.pixel_rays()`` are the reflected rays and ``world_normal()`` is right
        (``camera.to_vtk()`` drops that flip and is the camera actually rendered).
    plane : MirrorPlane
        The mirror's plane, normal towards its front.

    Raises
    ------
    InputError
        Bad scene or index, a non-planar mirror, or a camera behind (or in) the mirror plane.
    """
    items, mirror = _check_scene(scene, mirror)
    plane = mirror_plane(items[mirror])
    main = capture(items, window_size=window_size, camera=camera, supersample=supersample)
    cam = main.camera
    size = float(np.linalg.norm(np.subtract(*np.reshape(items[mirror].bounds, (3, 2)).T)))
    if cam.parallel_projection:
        # An orthographic eye can be moved back freely: what counts is the viewing direction.
        if float(cam.direction @ plane.normal) >= 0.0:
            raise InputError("camera: looks at the back of the mirror (or along its plane)")
    elif float(plane.signed_distance(np.asarray(cam.position))) <= 1e-9 * max(size, 1e-300):
        raise InputError(
            "camera: is behind the mirror (or in its plane); the mirror's front is the side "
            f"its faces point to, normal {np.round(plane.normal, 6).tolist()}"
        )

    # Reflected pass: the mirror is left out, and what lies behind it is clipped away, since a
    # mirror shows only its front half-space (the reflected eye is behind the plane).
    kept, ids = [], []
    for i, ds in enumerate(items):
        if i == mirror:
            continue
        part = ds.clip(normal=plane.normal, origin=plane.origin, invert=False)
        if part.n_cells:
            kept.append(part)
            ids.append(i)
    rcam = _reflected_camera(cam, plane)
    k = main.supersample
    if kept:
        refl = capture(kept, window_size=window_size, camera=rcam, supersample=k)
    else:
        w, h = cam.window_size
        refl = _empty_gbuffer(rcam, (w, h), k, [])
    names = list(main.object_names)
    return main, _flip_left_right(refl, np.asarray(ids, dtype=np.int32), names), plane


def default_style(gb: GBuffer) -> np.ndarray:
    """Shade plus the 2003 edge map: white inner edges, black profiles (2003 §5.1)."""
    return enhance(shade_image(gb), edge_map(gb))


def _rgb(img: object, shape: tuple[int, int], which: str) -> np.ndarray:
    a = np.asarray(img, dtype=np.float32)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=2)
    if a.shape != (*shape, 3):
        raise InputError(
            f"style: expected an (H, W, 3) or (H, W) image of shape {shape} for the {which} "
            f"view, got {a.shape}"
        )
    return np.clip(np.nan_to_num(a, nan=1.0), 0.0, 1.0)


def mirror_enhance(
    scene: Sequence[pv.DataSet],
    mirror: int,
    *,
    camera: object,
    window_size: Sequence[int] = (640, 480),
    supersample: int = 2,
    style: Callable[[GBuffer], np.ndarray] = default_style,
    mirror_tint: Sequence[float] = (0.9, 0.95, 1.0),
) -> np.ndarray:
    """Edge-enhanced image of a scene with a planar mirror (Nienhaus & Döllner 2003 §5, Fig. 8).

    Both G-buffers of :func:`mirror_gbuffers` are enhanced separately with ``style``, so the
    reflected objects get their own profiles and inner edges, detected from the reflected
    viewpoint. The reflected image, multiplied by ``mirror_tint``, then replaces the main image
    on the mirror's visible pixels, weighted by the mirror's coverage of each output pixel
    (antialiased border). Where the main view has profile ink (the mirror's outline, and
    profiles of objects in front of it) the main image is kept, so the outline stays.

    Parameters
    ----------
    scene, mirror, camera, window_size, supersample
        As for :func:`mirror_gbuffers`.
    style : callable GBuffer -> (H, W, 3) or (H, W) float image in [0, 1]
        The enhancement of one view at its output size; default :func:`default_style`
        (``enhance(shade_image(gb), edge_map(gb))``).
    mirror_tint : RGB in [0, 1], default: (0.9, 0.95, 1.0)
        Multiplies the reflected image: a slightly bluish, darker glass.

    Returns
    -------
    (H, W, 3) float32 RGB in [0, 1].
    """
    tint = np.asarray(mirror_tint, dtype=np.float32)
    if tint.shape != (3,) or not (
        np.isfinite(tint).all() and (0 <= tint).all() and (tint <= 1).all()
    ):
        raise InputError(f"mirror_tint: expected three values in [0, 1], got {mirror_tint!r}")
    if not callable(style):
        raise InputError(f"style: expected a callable GBuffer -> RGB image, got {style!r}")
    items, mirror = _check_scene(scene, mirror)
    main, refl, _ = mirror_gbuffers(
        items, mirror, camera=camera, window_size=window_size, supersample=supersample
    )
    shape = main.output_shape
    img_main = _rgb(style(main), shape, "main")
    img_refl = _rgb(style(refl), shape, "reflected")
    # Fraction of each output pixel where the mirror itself is the visible surface.
    cover = main.downsample((main.object_id == mirror).astype(np.float32))
    outline = profile_edges(main, width=_OUTLINE_WIDTH)
    weight = (cover * (1.0 - outline))[..., None]
    out = img_main + (img_refl * tint - img_main) * weight
    return np.clip(out, 0.0, 1.0).astype(np.float32, copy=False)
