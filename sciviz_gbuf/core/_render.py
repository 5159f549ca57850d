"""The one VTK offscreen render of a capture: which triangle is visible in each pixel.

Every triangle of the scene is drawn in a flat, unlit colour that encodes its index (24 bits
per render, like VTK's own ``vtkHardwareSelector``): a fragment-shader replacement writes
``gl_PrimitiveID + 1`` as the colour, so the geometry is uploaded once, with its shared
vertices (cell colours would triple them, and be uploaded again for every pass). The 8-bit
framebuffer then carries an exact integer per pixel; all float channels are evaluated
afterwards from the geometry itself (see :mod:`sciviz_gbuf.core._capture_kernels`), so they
are exact to float precision instead of being interpolated 8-bit colours or a non-linear
z-buffer.
"""

from __future__ import annotations

import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints, vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper, vtkRenderer

# The OpenGL2 module registers the render window/mapper factory overrides.
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  # isort: skip

from ..errors import RenderError
from ._capture_kernels import accumulate_codes

__all__ = ["BITS_PER_PASS", "IdRenderer", "new_render_window"]

BITS_PER_PASS = 24


def new_render_window():
    """An offscreen render window that works headless.

    Without an X display on Linux, VTK's default window class would first try X and warn; EGL
    (Mesa's llvmpipe here, or a GPU) renders offscreen without any display.
    """
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

    win = None
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        try:
            from vtkmodules.vtkRenderingOpenGL2 import vtkEGLRenderWindow

            win = vtkEGLRenderWindow()
        except ImportError:  # pragma: no cover - wheels without EGL fall back to the factory
            win = None
    if win is None:
        win = vtkRenderWindow()
    win.SetOffScreenRendering(True)
    win.SetMultiSamples(0)  # MSAA would blend ids at triangle borders
    return win


class IdRenderer:
    """Renders triangle indices of one merged triangle soup, any number of times.

    Parameters
    ----------
    points : ndarray (n, 3) float64
        World coordinates.
    triangles : ndarray (m, 3) int64
        Point indices.
    """

    def __init__(self, points: np.ndarray, triangles: np.ndarray) -> None:
        self.n_triangles = int(triangles.shape[0])
        self.n_passes = max(1, -(-int(self.n_triangles + 1).bit_length() // BITS_PER_PASS))
        poly = vtkPolyData()
        pts = vtkPoints()
        pts.SetData(numpy_to_vtk(np.ascontiguousarray(points, dtype=np.float64), deep=True))
        poly.SetPoints(pts)
        cells = vtkCellArray()
        offsets = np.arange(0, 3 * self.n_triangles + 1, 3, dtype=np.int64)
        cells.SetData(
            numpy_to_vtkIdTypeArray(offsets, deep=True),
            numpy_to_vtkIdTypeArray(np.ascontiguousarray(triangles.ravel(), np.int64), deep=True),
        )
        poly.SetPolys(cells)
        self._poly = poly
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(poly)
        mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.LightingOff()
        prop.SetAmbient(1.0)
        prop.SetDiffuse(0.0)
        prop.SetSpecular(0.0)
        prop.BackfaceCullingOff()
        prop.FrontfaceCullingOff()
        # The colour of a fragment: bits [shift, shift + BITS_PER_PASS) of its triangle index + 1
        # (so that the black background decodes to -1), 8 bits per channel. k / 255 converts to
        # the 8-bit value k exactly.
        shader = actor.GetShaderProperty()
        shader.AddFragmentShaderReplacement(
            "//VTK::Light::Dec",
            False,
            "//VTK::Light::Dec\nuniform int idShift;\nuniform int idMask;\n",
            False,
        )
        shader.AddFragmentShaderReplacement(
            "//VTK::Light::Impl",
            False,
            "//VTK::Light::Impl\n"
            "  int idCode = ((gl_PrimitiveID + 1) >> idShift) & idMask;\n"
            "  gl_FragData[0] = vec4(float(idCode & 255) / 255.0, "
            "float((idCode >> 8) & 255) / 255.0, float((idCode >> 16) & 255) / 255.0, 1.0);\n",
            False,
        )
        self._uniforms = shader.GetFragmentCustomUniforms()
        self.renderer = vtkRenderer()
        self.renderer.AddActor(actor)
        self.renderer.SetBackground(0.0, 0.0, 0.0)
        self.renderer.UseFXAAOff()
        self.renderer.SetUseDepthPeeling(False)
        self.window = new_render_window()
        self.window.AddRenderer(self.renderer)
        self._readback = vtkUnsignedCharArray()  # reused: no fresh memory per frame

    def render(self, camera, size: tuple[int, int]) -> np.ndarray:
        """Triangle index per pixel, shape (H, W) int64, row 0 on top, -1 for background (the
        renderer's own array, rewritten by its next render)."""
        width, height = size
        self.window.SetSize(width, height)
        self.renderer.SetActiveCamera(camera)
        # Only used within one capture: kept for the next (no fresh memory touched per frame).
        out = getattr(self, "_tid", None)
        if out is None or out.shape != (height, width):
            out = self._tid = np.zeros((height, width), dtype=np.int64)
        else:
            out.fill(0)
        for p in range(self.n_passes):
            self._uniforms.SetUniformi("idShift", p * BITS_PER_PASS)
            self._uniforms.SetUniformi("idMask", (1 << BITS_PER_PASS) - 1)
            self.window.Render()
            actual = tuple(self.window.GetActualSize())
            if actual != (width, height):
                raise RenderError(
                    f"the offscreen window is {actual[0]}x{actual[1]}, not the requested "
                    f"{width}x{height} (is the size above the OpenGL limit?)"
                )
            buf = self._readback
            if self.window.GetPixelData(0, 0, width - 1, height - 1, 0, buf, 0) == 0:
                raise RenderError("could not read back the offscreen framebuffer")
            px = vtk_to_numpy(buf).reshape(height, width, 3)
            accumulate_codes(px, p * BITS_PER_PASS, out)
        out -= 1  # code 0 is the black background
        return out

    def close(self) -> None:
        """Release the OpenGL context."""
        self.window.Finalize()
