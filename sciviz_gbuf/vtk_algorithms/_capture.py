"""``vtkGBufferCapture``: :func:`sciviz_gbuf.capture` as a VTK source (scene -> G-buffer image)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonDataModel import vtkDataSet, vtkImageData, vtkMultiBlockDataSet
from vtkmodules.vtkRenderingCore import vtkCamera, vtkRenderer

from ..core.camera import VIEWS, CameraInfo
from ..core.capture import (
    DEFAULT_WINDOW_SIZE,
    capture,
    check_scalars,
    check_window_size,
    resolve_camera,
)
from ..core.scene import is_plotter, scene_items
from ..errors import InputError
from ._pipeline import SDDP, GBufferAlgorithm, freeze, same_value

__all__ = ["vtkGBufferCapture"]


# ---------------------------------------------------------------------------- capture
def _renderer_scene(ren: vtkRenderer) -> list[pv.DataSet]:
    """World-space copies of the datasets of a vtkRenderer's visible actors."""
    out = []
    actors = ren.GetActors()
    actors.InitTraversal()
    for _ in range(actors.GetNumberOfItems()):
        actor = actors.GetNextActor()
        if not actor.GetVisibility() or actor.GetMapper() is None:
            continue
        mapper = actor.GetMapper()
        producer = mapper.GetInputAlgorithm()
        if producer is not None:
            # a mapper fed by a connection holds its producer's output, possibly out of date
            producer.Update()
        data = mapper.GetInputDataObject(0, 0)
        if not isinstance(data, (vtkDataSet, vtkMultiBlockDataSet)):
            continue
        m = actor.GetMatrix()
        mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
        ds = pv.wrap(data)
        if isinstance(ds, pv.MultiBlock):
            ds = ds.combine(merge_points=False)
        out.append(ds if np.allclose(mat, np.eye(4)) else ds.transform(mat, inplace=False))
    if not out:
        raise InputError("scene: the vtkRenderer has no visible actor with a dataset to capture")
    return out


def _camera_key(camera: object) -> Any:
    """What makes two camera arguments equal (vtkCameras by their state, not identity)."""
    if isinstance(camera, vtkCamera):
        return (
            "vtkCamera",
            tuple(camera.GetPosition()),
            tuple(camera.GetFocalPoint()),
            tuple(camera.GetViewUp()),
            camera.GetViewAngle(),
            bool(camera.GetParallelProjection()),
            camera.GetParallelScale(),
        )
    if isinstance(camera, CameraInfo):
        return ("CameraInfo", camera.to_json())
    return freeze(camera)


class vtkGBufferCapture(GBufferAlgorithm):
    """:func:`sciviz_gbuf.capture` as a VTK source: scene -> G-buffer ``vtkImageData``.

    The output is :meth:`GBuffer.to_pyvista` of the capture: one point per buffer pixel
    (``supersample`` times the window size), the channels (``depth``, ``sz``, ``normal``,
    ``world``, ``object_id``, ``cell_id``, ``mask`` as uint8, ``uv``, ``scalars:<name>``) as
    point arrays, the camera and metadata in field data, so :meth:`GBuffer.from_pyvista`
    (and the G-buffer filters of this module) rebuild the exact G-buffer.

    Parameters are set with ``SetScene``, ``SetWindowSize``, ``SetSupersample``, ``SetCamera``,
    ``SetCameraPosition``, ``SetParallelProjection``, ``SetScalars`` and ``SetFeatureAngle``
    (the arguments of :func:`~sciviz_gbuf.capture`). Each validates its value (raising
    :class:`InputError`) and calls ``Modified()`` only when the value changes.
    """

    def __init__(self) -> None:
        super().__init__(0)
        self._scene: object = None
        self._window_size: tuple[int, int] | None = None
        self._supersample = 1
        self._camera: object = None
        self._camera_key: Any = None
        self._parallel: bool | None = None
        self._scalars: tuple[str, ...] = ()
        self._feature_angle = 30.0

    # -- parameters
    def SetScene(self, scene: object) -> None:
        """A dataset, a sequence of them, a ``pyvista.Plotter`` or a ``vtkRenderer``.

        Its visible actors and, unless a camera is set, its camera are used (for a
        vtkRenderer: its active camera as it is, and its render window's size by default).
        The scene is not watched: call ``Modified()`` after editing it.
        """
        if scene is self._scene:
            return
        if not isinstance(scene, vtkRenderer):
            scene_items(scene)  # validates: raises InputError for an empty or bad scene
        self._scene = scene
        self.Modified()

    def GetScene(self) -> object:
        return self._scene

    def SetWindowSize(self, width: int | Sequence[int], height: int | None = None) -> None:
        """Output ``(width, height)``; ``None`` (the default): the scene's or 1024x768."""
        if width is None:
            size = None
        else:
            size = check_window_size(width if height is None else (width, height))
        if size != self._window_size:
            self._window_size = size
            self.Modified()

    def GetWindowSize(self) -> tuple[int, int]:
        """The window size that will be captured (resolved from the scene if not set)."""
        if self._window_size is not None:
            return self._window_size
        if is_plotter(self._scene):
            return tuple(int(v) for v in self._scene.window_size)  # type: ignore[union-attr]
        if isinstance(self._scene, vtkRenderer) and self._scene.GetRenderWindow() is not None:
            w, h = self._scene.GetRenderWindow().GetSize()
            if w > 0 and h > 0:
                return int(w), int(h)
        return DEFAULT_WINDOW_SIZE

    def SetSupersample(self, k: int) -> None:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise InputError(f"supersample: expected a positive integer, got {k!r}")
        if int(k) != self._supersample:
            self._supersample = int(k)
            self.Modified()

    def GetSupersample(self) -> int:
        return self._supersample

    def SetCamera(self, camera: object) -> None:
        """Anything :func:`capture` takes as ``camera`` (None: the scene's, else ``'iso'``).

        A ``vtkCamera`` is copied now; changing it later has no effect until set again.
        """
        if isinstance(camera, str):
            if camera not in VIEWS:
                raise InputError(
                    f"camera: unknown view {camera!r}; expected one of {sorted(VIEWS)}"
                )
        elif camera is not None:
            resolve_camera(camera, None, None)  # validates (raises InputError)
        key = _camera_key(camera)
        if (camera is None) == (self._camera is None) and same_value(key, self._camera_key):
            return
        if isinstance(camera, vtkCamera):
            copy = vtkCamera()
            copy.DeepCopy(camera)
            camera = copy
        self._camera = camera
        self._camera_key = key
        self.Modified()

    def SetCameraPosition(
        self,
        position: Sequence[float],
        focal_point: Sequence[float],
        view_up: Sequence[float],
    ) -> None:
        """Shorthand for ``SetCamera((position, focal_point, view_up))``."""
        self.SetCamera(
            tuple(tuple(float(v) for v in vec) for vec in (position, focal_point, view_up))
        )

    def GetCamera(self) -> object:
        return self._camera

    def SetParallelProjection(self, parallel: bool | None) -> None:
        """Force orthographic (True) or perspective (False); None: as the camera is."""
        if parallel is not None and not isinstance(parallel, (bool, np.bool_, int)):
            raise InputError(f"parallel_projection: expected a bool or None, got {parallel!r}")
        value = None if parallel is None else bool(parallel)
        if value != self._parallel:
            self._parallel = value
            self.Modified()

    def SetScalars(self, scalars: str | Sequence[str]) -> None:
        names = check_scalars(scalars)
        if names != self._scalars:
            self._scalars = names
            self.Modified()

    def SetFeatureAngle(self, angle: float) -> None:
        try:
            value = float(angle)
        except (TypeError, ValueError):
            value = float("nan")
        if not (np.isfinite(value) and 0 <= value <= 180):
            raise InputError(f"feature_angle: expected degrees in [0, 180], got {angle!r}")
        if value != self._feature_angle:
            self._feature_angle = value
            self.Modified()

    def _supersample_hint(self) -> int | None:
        return self._supersample

    # -- pipeline
    def RequestInformation(self, request, inInfo, outInfo):
        # downstream image filters need the extent before any data exists
        w, h = self.GetWindowSize()
        k = self._supersample
        info = outInfo.GetInformationObject(0)
        info.Set(SDDP.WHOLE_EXTENT(), (0, w * k - 1, 0, h * k - 1, 0, 0), 6)
        info.Set(vtkImageData.SPACING(), (1.0, 1.0, 1.0), 3)
        info.Set(vtkImageData.ORIGIN(), (0.0, 0.0, 0.0), 3)
        return 1

    def _execute(self, inInfo: Any, output: vtkImageData, out_info: Any) -> None:
        if self._scene is None:
            raise InputError("vtkGBufferCapture: no scene; call SetScene() first")
        scene = self._scene
        camera = self._camera
        if isinstance(scene, vtkRenderer):
            if camera is None:
                camera = scene.GetActiveCamera()
            scene = _renderer_scene(scene)
        gb = capture(
            scene,
            window_size=self.GetWindowSize(),
            camera=camera,
            parallel_projection=self._parallel,
            scalars=self._scalars,
            supersample=self._supersample,
            feature_angle=self._feature_angle,
        )
        output.ShallowCopy(gb.to_pyvista())
