"""The GPU route of the live overlay: the 2003 edge map computed by fragment shaders inside
the user's own frame (Nienhaus & Döllner 2003, "an algorithm for real-time NPR").

Why this shape (VTK 9.4-9.7 from Python): a render pass cannot be written in Python (the
OpenGL passes are abstract or never call Python overrides), and PyVista rebuilds its pass
chain over anything set with ``SetPass``. What works is an observer on the enhanced renderer's
``EndEvent``: the GL context is current, the window's render framebuffer is bound and holds
the subplot just drawn, colour and depth. There the route

1. reads that framebuffer's own depth texture (no read-back, no copy; sample 0 where it is
   multisampled) and writes linear ``sz`` and the normals from depth into a float texture
   (:data:`.glsl.GBUFFER_FS`, the GPU statement of :mod:`sciviz_gbuf.core.frame`);
2. computes the edge map into a second float texture (:data:`.glsl.EDGE_FS`, the statement
   of :func:`sciviz_gbuf.filters.edge_map`);
3. widens, colours and blends it over the subplot's viewport (:data:`.glsl.COMPOSITE_FS`).

Each pass is a ``vtkOpenGLQuadHelper`` (the full-screen quad VTK's own passes use); its
program is the one the window's shader cache returns for the same sources, so parameters are
uniforms and a change of one never compiles anything. GL state the passes change (blending,
depth test, scissor, culling, viewport, framebuffer bindings) goes through the window's
``vtkOpenGLState`` and is put back, so VTK's state cache stays true. Frames drawn for a
hardware selector (``pl.pick``, ``vtkHardwareSelector``) are left alone: their colours are
ids.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from vtkmodules.vtkCommonCore import VTK_FLOAT
from vtkmodules.vtkRenderingOpenGL2 import (
    vtkOpenGLFramebufferObject,
    vtkOpenGLQuadHelper,
    vtkOpenGLRenderUtilities,
    vtkTextureObject,
)

from ..core.camera import CameraInfo
from . import glsl

__all__ = ["SOFTWARE_RENDERERS", "GpuEdgePass", "GpuUnavailable", "gl_info", "is_hardware"]

# OpenGL enums (vtkOpenGLState takes them as numbers)
_GL_DRAW_FRAMEBUFFER = 0x8CA9
_GL_BLEND, _GL_DEPTH_TEST, _GL_SCISSOR_TEST, _GL_CULL_FACE = 0x0BE2, 0x0B71, 0x0C11, 0x0B44
_GL_SRC_ALPHA, _GL_ONE_MINUS_SRC_ALPHA, _GL_ZERO, _GL_ONE = 0x0302, 0x0303, 0, 1
_GL_TEXTURE_2D_MULTISAMPLE = 0x9100

#: Substrings (lower case) of the GL renderer strings of rasterisers that run on the CPU:
#: there the shaders cost about what the numba route costs, so ``auto`` keeps the CPU routes.
SOFTWARE_RENDERERS = (
    "llvmpipe",
    "softpipe",
    "swiftshader",
    "software rasterizer",
    "lavapipe",
    "gdi generic",
    "microsoft basic render",
)

_VS = vtkOpenGLRenderUtilities.GetFullScreenQuadVertexShader()


class GpuUnavailable(RuntimeError):
    """The GPU route cannot draw in this window (the message says why)."""


def gl_info(window: Any) -> dict[str, str]:
    """``vendor``, ``renderer`` and ``version`` strings of a window's GL context ("" where the
    window has not rendered yet: the context is made by the first render)."""
    out = {"vendor": "", "renderer": "", "version": ""}
    for line in str(window.ReportCapabilities()).splitlines():
        for key in out:
            prefix = f"OpenGL {key} string:"
            if line.startswith(prefix):
                out[key] = line[len(prefix) :].strip()
    return out


def is_hardware(window: Any) -> bool:
    """Whether a window's GL renderer is a graphics card's (not a CPU rasteriser such as Mesa
    llvmpipe); False while unknown (no frame rendered yet)."""
    name = gl_info(window)["renderer"].lower()
    return bool(name) and not any(s in name for s in SOFTWARE_RENDERERS)


def _clip_terms(camera: Any, aspect: float) -> list[float]:
    """The clip matrix's depth rows ``[2][2], [2][3], [3][2], [3][3]`` as VTK renders with it."""
    m = camera.GetProjectionTransformMatrix(aspect, -1.0, 1.0)
    return [m.GetElement(2, 2), m.GetElement(2, 3), m.GetElement(3, 2), m.GetElement(3, 3)]


class GpuEdgePass:
    """The three passes of one subplot's GPU overlay and their GL resources.

    Parameters
    ----------
    window : vtkOpenGLRenderWindow
        The window it draws in (its context owns the textures and programs).
    """

    def __init__(self, window: Any) -> None:
        self._window = window
        self._quads: dict[str, Any] = {}
        self._size: tuple[int, int] | None = None
        self._gtex: Any = None
        self._gfbo: Any = None
        self._etex: Any = None
        self._efbo: Any = None
        #: Frames drawn so far.
        self.frames = 0
        self._checked: tuple | None = None  # the pass and size whose depth was seen

    # ------------------------------------------------------------------ resources
    def _allocate(self, w: int, h: int) -> None:
        """Two RGBA float32 textures of the subplot's size, each in a framebuffer of its own
        (``(n, sz)`` and the edge map: float, so the operators see the values the CPU route
        computes, not 8-bit steps)."""
        self._release_targets()
        window = self._window
        state = window.GetState()
        state.PushFramebufferBindings()  # UnBind binds framebuffer 0: keep the frame's
        try:
            for name in ("g", "e"):
                tex = vtkTextureObject()
                tex.SetContext(window)
                if not tex.Allocate2D(w, h, 4, VTK_FLOAT):
                    raise GpuUnavailable("the GL context cannot allocate float textures")
                fbo = vtkOpenGLFramebufferObject()
                fbo.SetContext(window)
                fbo.Bind()
                fbo.AddColorAttachment(0, tex)
                fbo.ActivateDrawBuffer(0)
                if not fbo.CheckFrameBufferStatus(_GL_DRAW_FRAMEBUFFER):
                    raise GpuUnavailable("a float colour framebuffer is incomplete")
                fbo.UnBind()
                setattr(self, f"_{name}tex", tex)
                setattr(self, f"_{name}fbo", fbo)
        finally:
            state.PopFramebufferBindings()
        self._size = (w, h)

    def _release_targets(self) -> None:
        for name in ("_gfbo", "_efbo", "_gtex", "_etex"):
            obj = getattr(self, name)
            if obj is not None:
                obj.ReleaseGraphicsResources(self._window)
            setattr(self, name, None)
        self._size = None

    def release(self) -> None:
        """Free the textures, framebuffers and quads (the context is made current first)."""
        if self._window is None:
            return
        self._window.MakeCurrent()
        self._release_targets()
        for quad in self._quads.values():
            quad.ReleaseGraphicsResources(self._window)
        self._quads.clear()
        self._window = None

    def _program(self, fs: str) -> tuple[Any, Any]:
        """The quad of ``fs`` and its program, bound (compiled once per window: the shader
        cache returns the program of the same sources)."""
        if fs not in self._quads:
            self._quads[fs] = vtkOpenGLQuadHelper(self._window, _VS, fs, "")
        prog = self._window.GetShaderCache().ReadyShaderProgram(_VS, fs, "")
        if prog is None:
            raise GpuUnavailable("the edge shaders did not compile in this GL context")
        return self._quads[fs], prog

    def program_ids(self) -> list[str]:
        """The VTK addresses of the compiled programs (a parameter change must not add any)."""
        cache = self._window.GetShaderCache()
        return sorted(cache.ReadyShaderProgram(_VS, fs, "").__this__ for fs in self._quads)

    # ------------------------------------------------------------------ per frame
    def draw(self, renderer: Any, params: Any) -> None:
        """Draw the edge overlay of ``renderer`` (just rendered, its framebuffer bound) with
        ``params`` (an :class:`.overlay.EdgeParams`)."""
        window = self._window
        w, h = (int(v) for v in renderer.GetSize())
        x0, y0 = (int(v) for v in renderer.GetOrigin())
        if w < 1 or h < 1:
            return
        depth = window.GetRenderFramebuffer().GetDepthAttachmentAsTextureObject()
        if depth is None:
            raise GpuUnavailable("the window's framebuffer has no depth texture to read")
        if self._size != (w, h):
            self._allocate(w, h)
        cam = renderer.GetActiveCamera()
        info = CameraInfo.from_vtk(cam, (w, h))
        parallel = int(bool(cam.GetParallelProjection()))
        state = window.GetState()
        saved = {cap: state.GetEnumState(cap) for cap in
                 (_GL_BLEND, _GL_DEPTH_TEST, _GL_SCISSOR_TEST, _GL_CULL_FACE)}  # fmt: skip
        state.PushFramebufferBindings()
        try:
            for cap in saved:
                state.vtkglDisable(cap)
            state.vtkglViewport(0, 0, w, h)
            # 1: sz and normals from the frame's depth
            self._gfbo.Bind(_GL_DRAW_FRAMEBUFFER)
            self._gfbo.ActivateDrawBuffer(0)
            multi = depth.GetTarget() == _GL_TEXTURE_2D_MULTISAMPLE
            quad, prog = self._program(glsl.gbuffer_fs(multi))
            depth.Activate()
            prog.SetUniformi("zTex", depth.GetTextureUnit())
            prog.SetUniform2i("origin", [x0, y0])
            prog.SetUniform4f("proj", _clip_terms(cam, w / h))
            self._camera_uniforms(prog, w, h, parallel, info)
            quad.Render()
            depth.Deactivate()
            # 2: the edge map
            self._efbo.Bind(_GL_DRAW_FRAMEBUFFER)
            self._efbo.ActivateDrawBuffer(0)
            quad, prog = self._program(glsl.EDGE_FS)
            self._gtex.Activate()
            prog.SetUniformi("gTex", self._gtex.GetTextureUnit())
            self._camera_uniforms(prog, w, h, parallel, info)
            prog.SetUniformf("jump", float(params.depth_jump))
            prog.SetUniformf("crease", float(params.crease_angle))
            prog.SetUniformi("operator", 1 if params.operator == "c1" else 0)
            prog.SetUniformi("inner_on", 0 if params.style == "profile" else 1)
            quad.Render()
            self._gtex.Deactivate()
        finally:
            state.PopFramebufferBindings()
        key = (None if renderer.GetPass() is None else renderer.GetPass().__this__, w, h)
        if key != self._checked:
            self._check_depth(renderer)
            self._checked = key
        try:
            # 3: over the subplot, in the frame's own framebuffer
            state.vtkglViewport(x0, y0, w, h)
            state.vtkglEnable(_GL_BLEND)
            # colour blended; the frame's alpha kept (PyVista reads it for transparent
            # backgrounds)
            state.vtkglBlendFuncSeparate(_GL_SRC_ALPHA, _GL_ONE_MINUS_SRC_ALPHA, _GL_ZERO, _GL_ONE)
            quad, prog = self._program(glsl.COMPOSITE_FS)
            self._etex.Activate()
            prog.SetUniformi("eTex", self._etex.GetTextureUnit())
            prog.SetUniform2i("size", [w, h])
            prog.SetUniform2i("origin", [x0, y0])
            # edge_map's lines already straddle the edge (two pixels): one pixel less
            prog.SetUniformi("foot", max(1, round(float(params.width)) - 1))
            prog.SetUniformf("opacity", float(params.opacity))
            prog.SetUniform3f("innerColor", list(params.inner_color))
            prog.SetUniform3f("profileColor", list(params.profile_color))
            quad.Render()
            self._etex.Deactivate()
        finally:
            for cap, on in saved.items():
                (state.vtkglEnable if on else state.vtkglDisable)(cap)
            state.ResetGLBlendFuncState()
            state.ResetGLViewportState()
        self.frames += 1

    def _check_depth(self, renderer: Any) -> None:
        """Once per render pass and size: a subplot with visible actors must have left its
        depth in the frame. A pass that draws into buffers of its own and copies only the
        colour back (VTK's Gaussian blur, PyVista's ``add_blurring``) leaves the depth of its
        own full-screen quad, one value over the whole viewport (or none), and the route
        would draw nothing, silently. (A real scene gives that only as a wall filling the
        view square to a parallel camera; there the CPU route draws the same nothing.)"""
        w, h = self._size
        pbo = self._gtex.Download()
        g = np.empty((h, w, 4), np.float32)
        if not pbo.Download2D(VTK_FLOAT, g, [w, h], 4, [0, 0]):
            raise GpuUnavailable("the normal texture could not be read back")
        valid = np.any(g[..., :3] != 0.0, axis=-1)
        sz = g[..., 3][valid]
        flat = sz.size == 0 or (valid.all() and sz.min() == sz.max())
        if renderer.VisibleActorCount() > 0 and flat:
            name = "none" if renderer.GetPass() is None else renderer.GetPass().GetClassName()
            raise GpuUnavailable(f"the frame's depth is empty under the render pass {name}")

    @staticmethod
    def _camera_uniforms(prog: Any, w: int, h: int, parallel: int, info: CameraInfo) -> None:
        prog.SetUniform2i("size", [w, h])
        prog.SetUniformi("parallel", parallel)
        prog.SetUniformf("dist", float(info.distance))
        prog.SetUniformf("pixel", float(info.pixel_size))

    def edge_planes(self) -> tuple[np.ndarray, np.ndarray]:
        """The last frame's inner-edge and profile planes, (H, W) float32 each, row 0 on top
        (a read-back from the GPU: for tests and the benchmark's ``--check``, not per frame)."""
        if self._size is None or self._etex is None:
            raise GpuUnavailable("no frame has been drawn by the GPU route yet")
        w, h = self._size
        self._window.MakeCurrent()
        pbo = self._etex.Download()
        out = np.empty((h, w, 4), np.float32)
        if not pbo.Download2D(VTK_FLOAT, out, [w, h], 4, [0, 0]):
            raise GpuUnavailable("the edge texture could not be read back")
        out = out[::-1]
        return np.ascontiguousarray(out[..., 0]), np.ascontiguousarray(out[..., 1])
