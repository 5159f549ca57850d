"""G-buffers from a frame that was rendered anyway: its depth image, read back.

:func:`capture` renders the scene once more, offscreen, and intersects every pixel's ray with
the triangle found there: exact float32 channels of every kind. A live overlay that follows
the user's own frames cannot afford that second render on every new view (issue "Real-time
edge enhancement"). The frame's depth image is already there, and it is what the user sees;
:func:`gbuffer_from_zbuffer` turns it into the channels the edge operators read: linear
``depth``, Saito's ``sz`` (1990 Eq. 6), ``mask`` and normals from the depth (Nienhaus &
Döllner 2003 §3 render the normal and depth maps; from depth alone, the normals of planes are
exact, and a pixel next to a crease takes its own face's normal).

What it cannot give: world coordinates, object and cell ids, texture coordinates and scalars
(zeros / none), and interpolated normals (those of smooth-shaded meshes are the facets' here).
It holds what writes depth in that viewport (lines and points too). With multisampling, the
driver resolves the depth samples of each pixel its own way (llvmpipe: within a pixel of the
centre, which moves lines by up to a pixel); without it, the depth is the pixel centre's and
the result agrees with :func:`capture` to float32 round-off.
"""

from __future__ import annotations

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkFloatArray

from ..errors import InputError
from . import _frame_kernels as _kernels
from .camera import CameraInfo
from .gbuffer import GBuffer

__all__ = ["gbuffer_from_zbuffer", "read_zbuffer"]


def gbuffer_from_zbuffer(zbuffer: np.ndarray, camera: CameraInfo) -> GBuffer:
    """The G-buffer of a rendered frame's depth image.

    Parameters
    ----------
    zbuffer : (H, W) array
        Window depth in [0, 1] as OpenGL reads it (``vtkRenderWindow.GetZbufferData``):
        bottom row first, 1 where nothing was drawn.
    camera : CameraInfo
        The camera of that frame at ``window_size = (W, H)``
        (``CameraInfo.from_vtk(renderer.GetActiveCamera(), renderer.GetSize())``).

    Returns
    -------
    GBuffer
        ``depth``, ``sz``, ``normal`` (from the depth) and ``mask`` as :func:`capture` defines
        them; ``world`` zero, ``object_id`` / ``cell_id`` 0 on the surface (read-only views),
        no ``uv`` or scalars; ``supersample`` 1.
    """
    z = np.asarray(zbuffer)
    if z.ndim != 2 or z.size == 0 or not np.issubdtype(z.dtype, np.floating):
        raise InputError(f"zbuffer: expected an (H, W) float array, got {z.dtype} {z.shape}")
    if not isinstance(camera, CameraInfo):
        raise InputError(f"camera: expected a CameraInfo, got {type(camera).__name__}")
    h, w = z.shape
    if tuple(camera.window_size) != (w, h):
        raise InputError(
            f"camera: its window_size {tuple(camera.window_size)} is not the zbuffer's "
            f"(W, H) = {(w, h)}"
        )
    z = np.ascontiguousarray(z, dtype=np.float32)
    p = camera.projection_matrix_array
    depth = np.empty((h, w), np.float32)
    sz = np.empty((h, w), np.float32)
    normal = np.empty((h, w, 3), np.float32)
    mask = np.empty((h, w), np.bool_)
    _kernels.frame_buffers(
        z, p[2, 2], p[2, 3], p[3, 2], p[3, 3], bool(camera.parallel_projection),
        camera.distance, camera.pixel_size, depth, sz, normal, mask,
    )  # fmt: skip
    zeros3 = np.broadcast_to(np.float32(0.0), (h, w, 3))
    return GBuffer(
        depth=depth,
        sz=sz,
        normal=normal,
        world=zeros3,
        object_id=np.broadcast_to(np.int32(0), (h, w)),
        cell_id=np.broadcast_to(np.int64(0), (h, w)),
        mask=mask,
        camera=camera,
    )


def read_zbuffer(window, origin: tuple[int, int], size: tuple[int, int], out=None) -> np.ndarray:
    """The depth image of a window's region as OpenGL reads it: (H, W) float32, bottom row
    first. ``origin`` is the lower-left pixel, ``size`` = (W, H); ``out`` a ``vtkFloatArray``
    to reuse (the returned array is a view of it, valid until its next use)."""
    x0, y0 = (int(v) for v in origin)
    w, h = (int(v) for v in size)
    arr = vtkFloatArray() if out is None else out
    window.GetZbufferData(x0, y0, x0 + w - 1, y0 + h - 1, arr)
    return vtk_to_numpy(arr).reshape(h, w)
