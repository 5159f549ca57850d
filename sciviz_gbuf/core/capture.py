"""``capture``: one VTK offscreen render of a scene -> float32 G-buffers.

How (a visibility buffer, Burns & Hunt 2013): VTK rasterises the scene once, every triangle
flat-coloured with its own index (:mod:`sciviz_gbuf.core._render`). For each covered pixel the
ray through the pixel centre is then intersected in float64 with that triangle
(:mod:`sciviz_gbuf.core._capture_kernels`), which yields world coordinates, linear depth,
Saito's ``sz`` (1990 Eq. 6), interpolated normals, texture coordinates and scalars, all exact
to float32, from a single render however many channels are asked for.
"""

from __future__ import annotations

import atexit
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from vtkmodules.vtkRenderingCore import vtkCamera

from .. import _validate
from .._progress import progress
from ..errors import InputError
from . import _capture_kernels as _kernels
from . import _layer_kernels
from ._render import IdRenderer
from .camera import VIEWS, CameraInfo
from .framing import check_up, default_up, named_view_camera
from .gbuffer import GBuffer
from .scene import Surface, collect_surfaces, forget_prepared, is_plotter, scene_items

__all__ = [
    "BYTES_PER_LAYER",
    "BYTES_PER_PIXEL",
    "DEFAULT_WINDOW_SIZE",
    "LAYER_GAP_PX",
    "MAX_BUFFER_SIZE",
    "CaptureSession",
    "capture",
    "check_capture_size",
    "check_layers",
    "check_scalars",
    "check_window_size",
    "clear_capture_cache",
    "resolve_camera",
]

DEFAULT_WINDOW_SIZE = (1024, 768)
#: Largest buffer edge in pixels (window size times supersample); OpenGL's usual limit:
#: ``LIMITS["image_side"]``.
MAX_BUFFER_SIZE = int(_validate.LIMITS["image_side"])
#: Peak memory of a capture per buffer pixel (bytes): the render window's colour and depth
#: planes and their read-back, the triangle ids, the barycentrics and the G-buffer's own
#: channels (45 bytes, kept). 65 bytes of peak RSS were measured at 2048^2 and 4096^2
#: buffers; the margin covers the driver's framebuffer, which RSS may not show.
BYTES_PER_PIXEL = 96
#: Memory of each layer behind the first per buffer pixel (bytes): its channels (45) and
#: barycentrics (12), and the k-buffer's candidates (16 each, ``layers + 2`` of them).
BYTES_PER_LAYER = 57
#: A surface behind another is a layer of its own when it lies more than this many pixel
#: footprints deeper (thinner shells are one layer: the two sides of a sheet of paper).
LAYER_GAP_PX = 2.0
# Margin of the tight clipping range, relative to the depth extent of the data.
_CLIP_MARGIN = 1e-3


def check_window_size(window_size: object) -> tuple[int, int]:
    """``(width, height)`` as two positive integers, each at most ``LIMITS["image_side"]``."""
    try:
        w, h = window_size  # type: ignore[misc]
        ok = not any(isinstance(v, (bool, np.bool_, str, bytes)) for v in (w, h))
        ok = ok and all(float(v) == int(v) for v in (w, h))
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok or int(w) <= 0 or int(h) <= 0:
        raise InputError(
            "window_size: expected two positive integers (width, height), got "
            f"{_validate.brief(window_size)}"
        )
    side = int(_validate.LIMITS["image_side"])
    if int(w) > side or int(h) > side:
        raise InputError(
            f"window_size: expected at most {side} pixels per side (LIMITS['image_side']), "
            f"got {int(w)}x{int(h)}, which exceeds it"
        )
    return int(w), int(h)


def check_capture_size(window_size: object, supersample: object) -> tuple[int, int, int]:
    """``(width, height, supersample)`` of a capture that fits every bound, checked before
    anything is allocated: each side and ``supersample`` (``LIMITS["supersample"]``), the
    buffer side (``LIMITS["image_side"]``), the buffer pixels ``width x height x
    supersample^2`` (``LIMITS["image_pixels"]``) and their memory (:data:`BYTES_PER_PIXEL`
    each) against the memory available now.
    """
    width, height = check_window_size(window_size)
    k = _validate.count(supersample, "supersample", "supersample")
    size = (width * k, height * k)
    if max(size) > MAX_BUFFER_SIZE:
        raise InputError(
            f"window_size x supersample = {size[0]}x{size[1]} exceeds {MAX_BUFFER_SIZE} pixels "
            "per side (LIMITS['image_side'])"
        )
    pixels = size[0] * size[1]
    if pixels > _validate.LIMITS["image_pixels"]:
        raise InputError(
            f"window_size x supersample = {size[0]}x{size[1]} = {pixels} pixels exceeds "
            f"{_validate.LIMITS['image_pixels']:g} (LIMITS['image_pixels'])"
        )
    _validate.check_memory(
        pixels * BYTES_PER_PIXEL,
        "window_size",
        f"a {size[0]}x{size[1]} capture (window_size x supersample)",
    )
    return width, height, k


def check_scalars(scalars: object) -> tuple[str, ...]:
    if isinstance(scalars, str):
        return (scalars,)
    try:
        names = tuple(scalars)  # type: ignore[arg-type]
    except TypeError:
        raise InputError(f"scalars: expected array names, got {scalars!r}") from None
    for n in names:
        if not isinstance(n, str) or not n:
            raise InputError(f"scalars: expected non-empty array names, got {n!r}")
    return names


def resolve_camera(
    camera: object, scene: object, parallel: bool | None
) -> tuple[vtkCamera, str | None]:
    """A new camera for the capture, and the named view it still has to be framed as (None: a
    camera used as given)."""
    cam = vtkCamera()
    reset = None
    if camera is None and is_plotter(scene):
        cam.DeepCopy(scene.renderer.GetActiveCamera())
        # A Plotter that was never shown has not placed its camera yet: place it as it will.
        camera = cam if scene.renderer.camera_set else "iso"
    if camera is None:
        camera = "iso"
    if isinstance(camera, str):
        if camera not in VIEWS:
            raise InputError(f"camera: unknown view {camera!r}; expected one of {sorted(VIEWS)}")
        direction, up = VIEWS[camera]
        cam.SetFocalPoint(0.0, 0.0, 0.0)
        cam.SetPosition(*direction)
        cam.SetViewUp(*up)
        reset = camera
    elif isinstance(camera, CameraInfo):
        cam = camera.to_vtk()
    elif isinstance(camera, vtkCamera):
        if camera is not cam:
            cam.DeepCopy(camera)
    else:
        try:
            pos, foc, up = (np.asarray(v, dtype=np.float64).reshape(3) for v in camera)  # type: ignore[union-attr]
        except (TypeError, ValueError):
            raise InputError(
                "camera: expected None, a view name, a vtkCamera/pyvista.Camera, a CameraInfo "
                f"or (position, focal_point, view_up), got {camera!r}"
            ) from None
        if not (np.isfinite(pos).all() and np.isfinite(foc).all() and np.isfinite(up).all()):
            raise InputError("camera: position, focal point and view up must be finite")
        if np.allclose(pos, foc):
            raise InputError("camera: position and focal point coincide")
        cam.SetPosition(*pos)
        cam.SetFocalPoint(*foc)
        cam.SetViewUp(*up)
    if parallel is not None:
        if parallel and not cam.GetParallelProjection():
            # switching to orthographic keeps the focal plane's extent
            cam.SetParallelScale(cam.GetDistance() * np.tan(np.radians(cam.GetViewAngle()) / 2))
        cam.SetParallelProjection(bool(parallel))
    dop = np.subtract(cam.GetFocalPoint(), cam.GetPosition())
    if np.linalg.norm(np.cross(dop, cam.GetViewUp())) == 0.0:
        raise InputError("camera: view up is parallel to the viewing direction")
    return cam, reset


def _merge(surfaces: list[Surface]) -> tuple[np.ndarray, ...]:
    n_pts = np.cumsum([0] + [s.points.shape[0] for s in surfaces])
    points = np.concatenate([s.points for s in surfaces])
    normals = np.concatenate([s.normals for s in surfaces])
    triangles = np.concatenate([s.triangles + n_pts[i] for i, s in enumerate(surfaces)])
    tri_obj = np.concatenate(
        [np.full(s.triangles.shape[0], i, dtype=np.int32) for i, s in enumerate(surfaces)]
    )
    tri_cell = np.concatenate([s.cell_ids for s in surfaces])
    return points, normals, triangles, tri_obj, tri_cell, n_pts


def _fit_clipping(cam: vtkCamera, points: np.ndarray) -> None:
    """Near/far planes tight around the data (2003 §4.1.1): depth precision where it matters."""
    pos = np.asarray(cam.GetPosition())
    dop = np.asarray(cam.GetDirectionOfProjection())
    z = (points - pos) @ dop
    zmin, zmax = float(z.min()), float(z.max())
    margin = _CLIP_MARGIN * max(zmax - zmin, 1e-12 * max(abs(zmax), 1.0))
    if cam.GetParallelProjection() and zmin - margin <= 0.0:
        # Moving an orthographic eye backwards changes nothing in the image.
        shift = margin - zmin + (zmax - zmin)
        cam.SetPosition(*(pos - shift * dop))
        zmin += shift
        zmax += shift
    if zmax <= 0.0:
        raise InputError("camera: all of the scene is behind the camera")
    near = zmin - margin
    far = zmax + margin
    if near <= far * 1e-4:
        near = far * 1e-4  # the eye is inside the data: keep the depth buffer usable
    cam.SetClippingRange(near, far)


def _interpolate_point_arrays(
    per_object: list[np.ndarray | None], k: int, tid, bary, triangles, n_pts
) -> np.ndarray:
    """Interpolate each object's (n_i, k) point array (None: NaN) to (H, W, k) float32."""
    vals = np.full((int(n_pts[-1]), k), np.nan, dtype=np.float64)
    for i, a in enumerate(per_object):
        if a is not None:
            vals[n_pts[i] : n_pts[i + 1]] = a.reshape(a.shape[0], k)
    return _kernels.interpolate_points(tid, bary, triangles, vals)


def _interpolate_named(
    surfaces: list[Surface], name: str, tid: np.ndarray, bary: np.ndarray, triangles, n_pts
) -> np.ndarray:
    """One requested array, from each object's point or cell data; NaN where an object lacks it."""
    found = [s.array(name) for s in surfaces]
    for s, f in zip(surfaces, found, strict=True):
        if f is not None and f[1].dtype.kind not in "biuf":
            raise InputError(
                f"scalars: array {name!r} of {s.name} is not numeric (dtype {f[1].dtype})"
            )
    comps = {v.reshape(v.shape[0], -1).shape[1] for f in found if f is not None for v in [f[1]]}
    if len(comps) > 1:
        raise InputError(f"scalars: array {name!r} has different component counts {sorted(comps)}")
    k = comps.pop()
    n_tri = triangles.shape[0]
    tri_off = np.cumsum([0] + [s.triangles.shape[0] for s in surfaces])
    has_point = any(f is not None and f[0] == "point" for f in found)
    has_cell = any(f is not None and f[0] == "cell" for f in found)
    out = None
    if has_point:
        per_object = [f[1] if f is not None and f[0] == "point" else None for f in found]
        out = _interpolate_point_arrays(per_object, k, tid, bary, triangles, n_pts)
    if has_cell:
        vals = np.full((n_tri, k), np.nan, dtype=np.float32)
        for i, f in enumerate(found):
            if f is not None and f[0] == "cell":
                # cell data of the triangulated surface is already one value per triangle
                vals[tri_off[i] : tri_off[i + 1]] = f[1].reshape(f[1].shape[0], k)
        cells = _kernels.lookup_cells(tid, vals)
        out = cells if out is None else np.where(np.isnan(out), cells, out)
    assert out is not None
    return out[..., 0] if k == 1 else out


def capture(
    scene: object,
    *,
    window_size: Sequence[int] | None = None,
    camera: object = None,
    parallel_projection: bool | None = None,
    scalars: Sequence[str] | str = (),
    supersample: int = 1,
    feature_angle: float = 30.0,
    progress_bar: bool = False,
    up: str | None = None,
    layers: int = 1,
) -> GBuffer:
    """Render a scene offscreen with VTK and return its float32 G-buffers.

    Parameters
    ----------
    scene : pyvista.DataSet, sequence of datasets, or pyvista.Plotter
        Surfaces to capture. Volumes/grids are captured by their outer surface; lines and
        vertices are not surfaces and are left out. A Plotter contributes its visible actors
        (with their transforms) and, unless ``camera`` is given, its camera. Nothing given is
        modified.
    window_size : (int, int), optional
        Output image ``(width, height)``; default the Plotter's size or ``(1024, 768)``. Each
        side at most ``LIMITS["image_side"]`` = 16384, and so is each side of the buffers
        (``window_size * supersample``); their pixels at most ``LIMITS["image_pixels"]`` =
        2**28, and their memory (:data:`BYTES_PER_PIXEL` bytes each) at most what is
        available when the capture starts.
    camera : str, vtkCamera, CameraInfo or (position, focal_point, view_up), optional
        A view name (``'iso'``, ``'xy'``, ``'xz'``, ``'yz'``, ``'yx'``, ``'zx'``, ``'zy'``) looks
        along PyVista's ``view_*`` direction and is framed by the package's one rule (the
        points' projected box centred, filling 85 % of the limiting image dimension, see
        :func:`~sciviz_gbuf.core.framing.framed_camera`); a camera or camera position is used
        as given (a copy). The clipping range is always set tightly around the data.
    parallel_projection : bool, optional
        Force orthographic (True) or perspective (False); default: as the camera is.
    scalars : str or sequence of str
        Point or cell arrays to capture into ``GBuffer.scalars`` (NaN on objects lacking them).
    supersample : int in [1, 8], default: 1
        Render at ``supersample`` times the window size; :meth:`GBuffer.downsample` averages
        results back to the window size (antialiasing). At most ``LIMITS["supersample"]`` = 8.
    feature_angle : float, default: 30.0
        Normals are split at edges sharper than this many degrees: computed so for data
        without point normals (PyVista's ``split_sharp_edges``), and a file's own point normals
        are split where they are shared across such an edge or stray that far from their face
        (:func:`~sciviz_gbuf.core.scene.split_normals`: flat CAD faces shade flat); 180 keeps
        everything smooth and a file's normals as they are.
    progress_bar : bool, default: False
        Show a progress bar (PyVista convention).
    up : {"x", "y", "z"}, optional
        World axis upright in the ``'iso'`` view; default by the convention of the file the
        data was read from (``read_mesh``: y for OFF/OBJ/PLY/glTF, else z; see
        :func:`~sciviz_gbuf.core.framing.default_up`).
    layers : int in [1, 8], default: 1
        Surfaces kept along each pixel's ray, nearest first (the "extended" G-buffer of 1990
        §5.1): the first is the visible one, the others (``GBuffer.layers``) are G-buffers of
        the same channels for what lies behind it (a k-buffer rasteriser on the CPU,
        :mod:`~sciviz_gbuf.core._layer_kernels`). A surface counts as a layer when it lies
        more than :data:`LAYER_GAP_PX` pixel footprints behind the one before it. Each layer
        costs :data:`BYTES_PER_LAYER` more bytes per buffer pixel (a 1024 x 768 capture with
        ``layers=3``, ``supersample=2``: about 0.5 GiB more at peak, 0.3 GiB kept), at most
        ``LIMITS["layers"]`` = 8.

    Returns
    -------
    GBuffer
        Buffers of shape ``(height * supersample, width * supersample)``.

    Raises
    ------
    InputError
        Empty scene, bad window size, NaN coordinates, unknown scalar name, bad camera; a
        capture beyond the limits above or larger than the memory available.
    """
    if window_size is None:
        window_size = tuple(scene.window_size) if is_plotter(scene) else DEFAULT_WINDOW_SIZE
    width, height, supersample = check_capture_size(window_size, supersample)
    layers = check_layers(layers, width * height * supersample**2)
    if up is not None:
        up = check_up(up)
    with progress(progress_bar, 4, "capture") as bar:
        with CaptureSession(scene, feature_angle=feature_angle, scalars=scalars) as session:
            bar.step("render")
            return session._capture(
                (width, height), supersample, camera, parallel_projection, up, bar.step,
                layers=layers,
            )  # fmt: skip


def check_layers(layers: object, pixels: int) -> int:
    """``layers`` checked: an integer in [1, ``LIMITS["layers"]``] whose memory
    (:data:`BYTES_PER_LAYER` per buffer pixel and layer behind the first, on top of
    :data:`BYTES_PER_PIXEL`) is available now."""
    n = _validate.count(layers, "layers", "layers")
    if n > 1:
        _validate.check_memory(
            pixels * (BYTES_PER_PIXEL + (n - 1) * BYTES_PER_LAYER + (n + 2) * 16),
            "layers",
            f"a capture of {n} layers",
        )
    return n


@dataclass
class _SceneEntry:
    """What a capture keeps of one scene's geometry: its merged triangle soup, the offscreen
    window with that soup uploaded and the framings of its named views."""

    arrays: tuple[np.ndarray, ...]
    merged: tuple[np.ndarray, ...]
    renderer: IdRenderer | None = None
    framings: dict[tuple, tuple] = field(default_factory=dict)

    def matches(self, arrays: tuple[np.ndarray, ...]) -> bool:
        # identity, not ids: the entry holds the arrays, so none of them can be freed and
        # its id reused while the entry exists
        return len(arrays) == len(self.arrays) and all(
            a is b for a, b in zip(arrays, self.arrays, strict=True)
        )

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None


class _SceneCache:
    """The last captured scene's :class:`_SceneEntry`, so a re-capture of an unchanged scene
    (the prepared surfaces are the same objects, :func:`.scene.collect_surfaces`) uploads no
    geometry and opens no window. One entry: a session takes it while it captures (no two
    sessions share a window) and gives its own back when it closes."""

    def __init__(self) -> None:
        self._entry: _SceneEntry | None = None
        self._lock = threading.Lock()

    def take(self, arrays: tuple[np.ndarray, ...]) -> _SceneEntry | None:
        with self._lock:
            entry = self._entry
            if entry is not None and entry.matches(arrays):
                self._entry = None
                return entry
        return None

    def give(self, entry: _SceneEntry) -> None:
        with self._lock:
            old, self._entry = self._entry, entry
        if old is not None and old is not entry:
            old.close()

    def clear(self) -> None:
        with self._lock:
            old, self._entry = self._entry, None
        if old is not None:
            old.close()


_SCENES = _SceneCache()
atexit.register(_SCENES.clear)  # release the kept GL context before VTK's own teardown


def clear_capture_cache() -> None:
    """Forget what captures keep between calls: the prepared surfaces of the datasets captured
    last (:data:`.scene.PREPARED_ENTRIES` of them) and the offscreen window of the last scene,
    with its geometry. Captures after this prepare and upload afresh; nothing else changes."""
    _SCENES.clear()
    forget_prepared()


def _surface_arrays(surfaces: list[Surface]) -> tuple[np.ndarray, ...]:
    return tuple(a for s in surfaces for a in (s.points, s.triangles, s.normals, s.cell_ids))


class CaptureSession:
    """Captures of one scene from any number of cameras, keeping what does not depend on the
    camera: the scene's surfaces (triangulated, normals split at ``feature_angle``), their
    merged triangle soup and the offscreen window with that geometry uploaded. Each
    :meth:`capture` only renders the visibility buffer and resolves its pixels: what the live
    overlay and the explorer pay per new view.

    Parameters
    ----------
    scene, feature_angle, scalars
        As in :func:`capture`, read when the session is made: a later change of the scene is
        not seen (make a new session).

    Use as a context manager, or call :meth:`close` to release the window.
    """

    def __init__(
        self, scene: object, *, feature_angle: float = 30.0, scalars: Sequence[str] | str = ()
    ) -> None:
        if not (0.0 <= _validate.finite(feature_angle, "feature_angle") <= 180.0):
            raise InputError(f"feature_angle: expected degrees in [0, 180], got {feature_angle!r}")
        self.names = check_scalars(scalars)
        self.scene = scene
        surfaces = collect_surfaces(scene, feature_angle=float(feature_angle))
        for name in self.names:
            if all(s.array(name) is None for s in surfaces):
                avail = sorted(
                    {
                        k
                        for s in surfaces
                        for k in (*s.mesh.point_data.keys(), *s.mesh.cell_data.keys())
                        if not k.startswith("__sciviz")
                    }
                )
                raise InputError(
                    f"scalars: no object in the scene has an array named {name!r}; "
                    f"available: {avail}"
                )
        self.surfaces = surfaces
        arrays = _surface_arrays(surfaces)
        entry = _SCENES.take(arrays)
        if entry is None:
            entry = _SceneEntry(arrays=arrays, merged=_merge(surfaces))
        self._entry = entry
        self._merged = entry.merged
        self._reused: tuple[np.ndarray, ...] | None = None
        # The world up of named views, from the scene (its data's file conventions).
        self._default_up: str | None = None

    def __enter__(self) -> CaptureSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Hand the offscreen window back (the session can still capture: it opens a new one).

        The window, with the scene's geometry uploaded, is kept for the next capture of the
        same unchanged scene (one scene is kept; :func:`clear_capture_cache` releases it)."""
        entry = self._entry
        if entry.renderer is not None:
            _SCENES.give(entry)
            self._entry = _SceneEntry(arrays=entry.arrays, merged=entry.merged)

    def capture(
        self,
        *,
        window_size: Sequence[int] | None = None,
        camera: object = None,
        parallel_projection: bool | None = None,
        supersample: int = 1,
        up: str | None = None,
        reuse: bool = False,
        layers: int = 1,
    ) -> GBuffer:
        """The G-buffer of the session's scene from ``camera``: the same as
        :func:`capture` of that scene with these arguments (see there).

        ``reuse``: write the buffers into those of the previous ``reuse=True`` capture of the
        same size (which then change: for a consumer that keeps nothing from frame to frame,
        like the live overlay); a first touch of fresh memory for every frame can cost more
        than the capture itself.
        """
        if window_size is None:
            scene = self.scene
            window_size = tuple(scene.window_size) if is_plotter(scene) else DEFAULT_WINDOW_SIZE
        width, height, supersample = check_capture_size(window_size, supersample)
        if up is not None:
            up = check_up(up)
        reuse = _validate.boolean(reuse, "reuse")
        layers = check_layers(layers, width * height * supersample**2)
        return self._capture(
            (width, height), supersample, camera, parallel_projection, up, reuse=reuse,
            layers=layers,
        )  # fmt: skip

    def _outputs(self, shape: tuple[int, int], reuse: bool) -> tuple[np.ndarray, ...]:
        """world, depth, normal, bary, object_id, cell_id, sz arrays of ``shape``."""
        out = self._reused if reuse else None
        if out is None or out[1].shape != shape:
            h, w = shape
            out = (
                np.empty((h, w, 3), np.float32),
                np.empty((h, w), np.float32),
                np.empty((h, w, 3), np.float32),
                np.empty((h, w, 3), np.float32),
                np.empty((h, w), np.int32),
                np.empty((h, w), np.int64),
                np.empty((h, w), np.float32),
            )
            if reuse:
                self._reused = out
        return out

    def _capture(
        self, window, supersample, camera, parallel_projection, up, step=None, reuse=False,
        layers=1,
    ):  # fmt: skip
        scene = self.scene
        self._supersample = int(supersample)
        size = (window[0] * supersample, window[1] * supersample)
        points, _normals, triangles, *_ = self._merged
        cam, reset = resolve_camera(camera, scene, parallel_projection)
        entry = self._entry
        if entry.renderer is None:
            entry.renderer = IdRenderer(points, triangles)
        renderer = entry.renderer
        renderer.window.SetSize(*size)
        if reset is not None:
            if up is None:
                if self._default_up is None:
                    self._default_up = default_up([d for _, d, _ in scene_items(scene)])
                up = self._default_up
            # the framing is a fit over every point: remembered with the scene's geometry
            frame_key = (reset, size, up, cam.GetViewAngle(), bool(cam.GetParallelProjection()))
            framed = entry.framings.get(frame_key)
            if framed is None:
                framed = entry.framings[frame_key] = named_view_camera(
                    points, reset, aspect=size[0] / size[1], up=up,
                    view_angle=cam.GetViewAngle(), parallel=bool(cam.GetParallelProjection()),
                )  # fmt: skip
            pos, foc, vup = framed
            cam.SetPosition(*pos)
            cam.SetFocalPoint(*foc)
            cam.SetViewUp(*vup)
            if cam.GetParallelProjection():
                cam.SetParallelScale(cam.GetDistance() * np.tan(np.radians(cam.GetViewAngle()) / 2))
        _fit_clipping(cam, points)
        tid = renderer.render(cam, size)
        info = CameraInfo.from_vtk(cam, size)
        if step is not None:
            step("geometry")

        first = self._resolve(tid, info, self._outputs(tid.shape, reuse))
        behind = ()
        if layers > 1:
            behind = tuple(
                self._resolve(t, info, self._outputs(tid.shape, False))
                for t in self._peel(tid, first.depth, info, layers - 1)
            )
        if step is not None:
            step("attributes")
        if step is not None:
            step("done")
        if behind:
            first.layers = behind
        return first

    def _resolve(self, tid: np.ndarray, info: CameraInfo, outputs) -> GBuffer:
        """The G-buffer of one layer from its triangle-index image ``tid``."""
        points, normals, triangles, tri_obj, tri_cell, n_pts = self._merged
        world, depth, normal, bary, object_id, cell_id, sz = outputs
        inv_clip = np.linalg.inv(info.world_to_clip())
        _kernels.resolve_hits_into(
            tid,
            points,
            triangles,
            normals,
            inv_clip,
            np.asarray(info.position, dtype=np.float64),
            info.direction,
            np.ascontiguousarray(info.view_matrix_array[:3, :3]),
            info.parallel_projection,
            world,
            depth,
            normal,
            bary,
        )
        mask = tid >= 0
        _kernels.labels_and_sz_into(
            tid,
            depth,
            tri_obj,
            tri_cell,
            info.distance,
            info.pixel_size,
            info.parallel_projection,
            object_id,
            cell_id,
            sz,
        )
        surfaces = self.surfaces
        uv = None
        tcs = [s.texture_coordinates() for s in surfaces]
        if any(t is not None for t in tcs):
            uv = _interpolate_point_arrays(tcs, 2, tid, bary, triangles, n_pts)
        captured = {
            n: _interpolate_named(surfaces, n, tid, bary, triangles, n_pts) for n in self.names
        }
        return GBuffer(
            depth=depth,
            sz=sz,
            normal=normal,
            world=world,
            object_id=object_id,
            cell_id=cell_id,
            mask=mask,
            camera=info,
            uv=uv,
            scalars=captured,
            supersample=int(self._supersample),
            object_names=[s.name for s in surfaces],
        )

    def _peel(
        self, tid: np.ndarray, depth: np.ndarray, info: CameraInfo, n: int
    ) -> list[np.ndarray]:
        """Triangle-index images of the ``n`` surfaces behind the first layer (``tid``,
        ``depth``), nearest first: the CPU k-buffer of :mod:`._layer_kernels`.

        A surface is a layer of its own when it lies more than :data:`LAYER_GAP_PX` pixel
        footprints (at that depth) behind the layer before it."""
        points, _normals, triangles, *_ = self._merged
        h, w = tid.shape
        clip = np.c_[points, np.ones(len(points))] @ info.world_to_clip().T
        with np.errstate(divide="ignore", invalid="ignore"):
            ndc = clip[:, :3] / clip[:, 3:4]
            sx = (ndc[:, 0] + 1.0) * 0.5 * w - 0.5
            sy = (1.0 - ndc[:, 1]) * 0.5 * h - 0.5
            d = (points - np.asarray(info.position, dtype=np.float64)) @ info.direction
            if info.parallel_projection:
                inv_d = d.copy()
            else:
                inv_d = np.where((d > 0) & (clip[:, 3] > 0), 1.0 / d, np.nan)
        foot = info.pixel_size / (1.0 if info.parallel_projection else info.distance)
        depth64 = depth.astype(np.float64)
        scale = np.ones_like(depth64) if info.parallel_projection else np.nan_to_num(depth64)
        tol = LAYER_GAP_PX * foot * scale
        # a few candidates more than asked: consecutive layers must be apart too
        m = n + 3
        cand_tid = np.empty((m, h, w), np.int64)
        cand_depth = np.empty((m, h, w), np.float64)
        _layer_kernels.peel_layers(
            np.ascontiguousarray(sx), np.ascontiguousarray(sy), np.ascontiguousarray(inv_d),
            triangles, tid, depth, tol, bool(info.parallel_projection), cand_tid, cand_depth,
        )  # fmt: skip
        out = [np.full((h, w), -1, np.int64) for _ in range(n)]
        count = np.zeros((h, w), np.int64)
        last = np.where(tid >= 0, depth64, np.inf)
        for j in range(m):
            dj = cand_depth[j]
            gap = (
                tol
                if info.parallel_projection
                else LAYER_GAP_PX * foot * np.where(np.isfinite(last), last, 0.0)
            )
            take = (cand_tid[j] >= 0) & (count < n) & (dj > last + gap)
            for k in range(n):
                sel = take & (count == k)
                out[k][sel] = cand_tid[j][sel]
            last = np.where(take, dj, last)
            count += take
        return out
