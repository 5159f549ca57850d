"""Camera description stored with every G-buffer, and the pixel rays it defines.

A :class:`CameraInfo` is a plain, serialisable record of the VTK camera that made a G-buffer:
enough to re-create the camera, to unproject pixels and to evaluate Saito's perspective depth
``sz`` (1990 Eq. 6).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import InputError

__all__ = ["VIEWS", "CameraInfo"]

#: Named views as in PyVista's ``view_xy`` & co: (direction from focal point to eye, view up).
VIEWS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "iso": ((1.0, 1.0, 1.0), (0.0, 0.0, 1.0)),
    "xy": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "yx": ((0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),
    "xz": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "zx": ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
    "yz": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "zy": ((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
}


@dataclass(frozen=True)
class CameraInfo:
    """The camera of a G-buffer, in world units.

    Attributes
    ----------
    position, focal_point, view_up : tuple of float
        As in ``vtkCamera``.
    view_angle : float
        Vertical view angle in degrees (perspective projection).
    parallel_projection : bool
        True for an orthographic camera.
    parallel_scale : float
        Half the height of the viewport in world units (parallel projection).
    clipping_range : tuple of float
        Near and far clipping distances, set tightly around the visible data.
    window_size : tuple of int
        ``(width, height)`` in pixels of the rendered buffers (includes any supersampling).
    view_matrix, projection_matrix : tuple of 16 float
        Row-major 4x4 matrices exactly as VTK used them (world -> eye -> clip).
    """

    position: tuple[float, float, float]
    focal_point: tuple[float, float, float]
    view_up: tuple[float, float, float]
    view_angle: float
    parallel_projection: bool
    parallel_scale: float
    clipping_range: tuple[float, float]
    window_size: tuple[int, int]
    view_matrix: tuple[float, ...] = field(repr=False)
    projection_matrix: tuple[float, ...] = field(repr=False)

    # ------------------------------------------------------------------ derived
    @property
    def distance(self) -> float:
        """``d`` of Saito Eq. 6: distance from the eye to the focal (screen) plane."""
        return float(np.linalg.norm(np.subtract(self.focal_point, self.position)))

    @property
    def direction(self) -> np.ndarray:
        """Unit viewing direction (eye towards focal point), float64."""
        v = np.subtract(self.focal_point, self.position, dtype=np.float64)
        return v / np.linalg.norm(v)

    @property
    def pixel_size(self) -> float:
        """``w`` of Saito Eq. 6: the length of one pixel on the focal plane, in world units."""
        # P[1, 1] is cot(view_angle / 2) (or 1 / parallel_scale): reading it from the matrix VTK
        # used also covers cameras with a horizontal view angle or a custom projection.
        p11 = self.projection_matrix[5]
        height = self.window_size[1]
        if self.parallel_projection:
            return 2.0 / (p11 * height)
        return 2.0 * self.distance / (p11 * height)

    @property
    def view_matrix_array(self) -> np.ndarray:
        """World -> eye 4x4 matrix (float64)."""
        return np.asarray(self.view_matrix, dtype=np.float64).reshape(4, 4)

    @property
    def projection_matrix_array(self) -> np.ndarray:
        """Eye -> clip 4x4 matrix (float64)."""
        return np.asarray(self.projection_matrix, dtype=np.float64).reshape(4, 4)

    def world_to_clip(self) -> np.ndarray:
        """Composite world -> clip matrix (float64)."""
        return self.projection_matrix_array @ self.view_matrix_array

    def sz_from_depth(self, depth: np.ndarray) -> np.ndarray:
        """Saito's perspective depth ``sz = d**2 / (w * z_v)`` (1990 Eq. 6), float32.

        For a parallel projection the first-order expansion of Eq. 6 about the focal plane,
        ``sz = (2 d - z_v) / w``, is used: the same units (pixels) and the same sign (larger is
        nearer), so gradients of ``sz`` equal the surface slope in both projections.
        """
        d, w = self.distance, self.pixel_size
        z = np.asarray(depth, dtype=np.float64)
        if self.parallel_projection:
            out = (2.0 * d - z) / w
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                out = d * d / (w * z)
        return out.astype(np.float32)

    def pixel_rays(self) -> tuple[np.ndarray, np.ndarray]:
        """Origins and unit directions of the rays through every pixel centre.

        Returns
        -------
        origin, direction : ndarray, shape (H, W, 3), float64
            Row 0 is the top image row. Origins lie on the near clipping plane.
        """
        w, h = self.window_size
        inv = np.linalg.inv(self.world_to_clip())
        x = (2.0 * (np.arange(w) + 0.5) / w) - 1.0
        y = (2.0 * ((h - 1 - np.arange(h)) + 0.5) / h) - 1.0
        xx, yy = np.meshgrid(x, y)
        ends = []
        for z in (-1.0, 1.0):
            ndc = np.stack([xx, yy, np.full_like(xx, z), np.ones_like(xx)], axis=-1)
            p = ndc @ inv.T
            ends.append(p[..., :3] / p[..., 3:4])
        d = ends[1] - ends[0]
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        return ends[0], d

    # ------------------------------------------------------------------ conversion
    def to_vtk(self):
        """A new ``vtkCamera`` with these parameters."""
        from vtkmodules.vtkRenderingCore import vtkCamera

        cam = vtkCamera()
        cam.SetPosition(*self.position)
        cam.SetFocalPoint(*self.focal_point)
        cam.SetViewUp(*self.view_up)
        cam.SetViewAngle(self.view_angle)
        cam.SetParallelProjection(self.parallel_projection)
        cam.SetParallelScale(self.parallel_scale)
        cam.SetClippingRange(*self.clipping_range)
        return cam

    def to_json(self) -> str:
        """Serialise (lossless: floats are written with ``repr`` precision)."""
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> CameraInfo:
        """Inverse of :meth:`to_json`."""
        try:
            d = json.loads(text)
            return cls(
                position=tuple(d["position"]),
                focal_point=tuple(d["focal_point"]),
                view_up=tuple(d["view_up"]),
                view_angle=float(d["view_angle"]),
                parallel_projection=bool(d["parallel_projection"]),
                parallel_scale=float(d["parallel_scale"]),
                clipping_range=tuple(d["clipping_range"]),
                window_size=tuple(int(v) for v in d["window_size"]),
                view_matrix=tuple(d["view_matrix"]),
                projection_matrix=tuple(d["projection_matrix"]),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"camera record is not valid: {exc}") from exc

    @classmethod
    def from_vtk(cls, cam, window_size: Sequence[int]) -> CameraInfo:
        """Record a ``vtkCamera`` as used for a render of ``window_size`` = (width, height)."""
        from vtkmodules.vtkCommonMath import vtkMatrix4x4

        w, h = int(window_size[0]), int(window_size[1])

        def flat(m: vtkMatrix4x4) -> tuple[float, ...]:
            return tuple(m.GetElement(i, j) for i in range(4) for j in range(4))

        near, far = cam.GetClippingRange()
        return cls(
            position=tuple(cam.GetPosition()),
            focal_point=tuple(cam.GetFocalPoint()),
            view_up=tuple(cam.GetViewUp()),
            view_angle=float(cam.GetViewAngle()),
            parallel_projection=bool(cam.GetParallelProjection()),
            parallel_scale=float(cam.GetParallelScale()),
            clipping_range=(float(near), float(far)),
            window_size=(w, h),
            view_matrix=flat(cam.GetModelViewTransformMatrix()),
            projection_matrix=flat(cam.GetProjectionTransformMatrix(w / h, -1.0, 1.0)),
        )
