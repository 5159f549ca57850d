"""Live edge enhancement of a PyVista renderer: an edge-map overlay refreshed per frame.

Why not a render pass: PyVista installs its own passes with ``renderer.SetPass`` (SSAO, EDL,
shadows, depth peeling) and overwrites ours. Instead, every time the render window starts a
frame (its ``StartEvent``) we check whether the view or the scene of the enhanced renderer
changed since the last frame; if so we capture that renderer's scene offscreen in a *separate*
window (a :class:`~sciviz_gbuf.core.capture.CaptureSession`, its own render window, so no
re-entry into the user's; kept while the scene stays the same, so a new view only renders the
visibility buffer again: the surfaces, their normals and the uploaded geometry are reused),
compute the edge map and upload it as an RGBA image. The image is drawn by a ``vtkActor2D``
(``vtkImageMapper``, one texel per pixel) in an overlay ``vtkRenderer`` on a new top layer with
the enhanced renderer's viewport: so it is composited (alpha blending) over exactly that
subplot, in every frame the window renders: interactive windows, ``show()``, ``screenshot()``
and every view that streams this window's frames. ``detach`` removes the observer, the renderer
and the extra layer, so the window renders bit for bit as before.

Trame / Jupyter (``trame-pyvista``): the server-rendered views stream this window's frames, so
they carry the overlay, re-captured whenever the camera moves (from Python or by dragging in
the browser, which drives the server-side interactor): ``jupyter_backend='server'``
(``PyVistaRemoteView``) and ``'trame'`` (``PyVistaRemoteLocalView``, which starts in server
rendering). Client-side views re-render the scene with vtk.js / VTK-wasm in the browser from
serialized geometry; the observer never runs there and the 2-D image actor is not serialized,
so they show the plain scene: ``jupyter_backend='client'`` (``PyVistaLocalView``), ``'html'``,
``'wasm'``, and the ``'trame'`` view after its toggle is switched to client-side rendering.
On the plotter's ``render()`` calls (``show()`` makes one after creating the view) we look the
plotter up in trame-pyvista's viewer registry and warn once if a client-side view shows it.

The GPU route (``source="gpu"``, :mod:`.gpu`) draws no image of ours: at the enhanced
renderer's ``EndEvent`` its shaders read the frame's own depth and blend the edges into the
subplot, every frame, with no read-back. Where it cannot (a window without a depth texture, a
context without float textures or the shaders), it warns once and the CPU capture route takes
over.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkRenderingCore import vtkActor2D, vtkImageMapper, vtkRenderer

from .. import _validate
from ..core.camera import CameraInfo
from ..core.capture import CaptureSession
from ..core.frame import gbuffer_from_zbuffer, read_zbuffer
from ..core.gbuffer import GBuffer
from ..errors import InputError
from ..filters import edge_map, profile_and_crease_edges
from ..styles import check_style, styles_for
from ..styles.illustration import fig7_edge_map
from .gpu import GpuEdgePass, GpuUnavailable, gl_info, is_hardware

__all__ = [
    "CLIENT_SIDE_WARNING",
    "GPU_STYLES",
    "LIVE_STYLES",
    "SOURCES",
    "EdgeParams",
    "LiveEdges",
    "client_side_views",
    "overlay_rgba",
]

# trame views that stream the server's render window (the overlay is in their frames)
_SERVER_RENDERED_VIEWS = frozenset({"PyVistaRemoteView", "PyVistaRCAView"})

#: Warned (once per overlay) when the plotter is shown by a client-side (vtk.js) trame view.
CLIENT_SIDE_WARNING = (
    "sciviz_gbuf live edges: this plotter is shown by a client-side trame view (vtk.js "
    "re-renders the scene in the browser, e.g. jupyter_backend='client'), which cannot show the "
    "edge overlay: it is composited into server-rendered frames. Use jupyter_backend='server' "
    "or 'trame' (server rendering, PyVista's default) to see it."
)

#: Styles of the live overlay (an RGBA image composited over the normal rendering), from the
#: styles registry.
LIVE_STYLES = styles_for("live")

#: Where the overlay's edges come from: ``capture`` renders the subplot's scene once more
#: offscreen (exact channels, any supersample); ``frame`` reads the depth of the frame being
#: drawn back to the CPU (no second render; see :mod:`sciviz_gbuf.core.frame`); ``gpu``
#: computes the edge map from that depth in shaders inside the frame (:mod:`.gpu`: no
#: read-back, supersample 1, the styles of :data:`GPU_STYLES`); ``auto`` takes ``gpu`` where
#: the GL renderer is a graphics card's, else ``frame`` where it is exact (a window without
#: multisampling, supersample 1), else ``capture``.
SOURCES = ("auto", "capture", "frame", "gpu")

#: Styles the GPU route draws (the 2003 edge map); ``lines`` and ``fig7`` clean and thin
#: whole lines (connected pieces, hysteresis), which stay on the CPU routes.
GPU_STYLES = ("enhance", "profile")


def _color(value: object, name: str) -> tuple[float, float, float]:
    """An RGB triple as Python floats (VTK properties take doubles: no float32 rounding)."""
    _validate.rgb(value, name)
    r, g, b = (float(v) for v in np.asarray(value, dtype=np.float64).reshape(-1))
    return r, g, b


@dataclass(frozen=True)
class EdgeParams:
    """Validated parameters of the live overlay (see ``enable_edge_enhancement``)."""

    style: str = "enhance"
    operator: str = "diagonal"
    crease_angle: float = 30.0
    depth_jump: float = 1.0
    width: float = 1.0
    supersample: int = 1
    inner_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    profile_color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    opacity: float = 1.0
    source: str = "auto"

    @classmethod
    def checked(
        cls,
        *,
        style: str,
        operator: str,
        crease_angle: float,
        depth_jump: float,
        width: float,
        supersample: int,
        inner_color: Sequence[float],
        profile_color: Sequence[float],
        opacity: float,
        source: str = "auto",
    ) -> EdgeParams:
        """Validate everything up front: a bad value must fail at the call, not mid-frame."""
        style = check_style(style, "live")
        if operator not in ("diagonal", "c1"):
            raise InputError(f"operator: expected 'diagonal' or 'c1', got {operator!r}")
        if (
            isinstance(supersample, bool)
            or not isinstance(supersample, (int, np.integer))
            or not 1 <= supersample <= 4
        ):
            raise InputError(f"supersample: expected an integer in [1, 4], got {supersample!r}")
        source = _validate.choice(source, "source", SOURCES)
        if source in ("frame", "gpu") and supersample != 1:
            raise InputError(
                f"supersample: source={source!r} reads the frame's own depth, at its own size: "
                f"expected 1, got {supersample!r}"
            )
        if source == "gpu" and style not in GPU_STYLES:
            raise InputError(
                f"style: source='gpu' draws {' or '.join(map(repr, GPU_STYLES))}, got "
                f"{style!r} (its lines are cleaned on the CPU: use source='capture' or 'frame')"
            )
        return cls(
            style=style,
            operator=operator,
            crease_angle=_validate.number_in(crease_angle, "crease_angle", 1e-6, 180.0),
            depth_jump=_validate.number_in(depth_jump, "depth_jump", 1e-6),
            width=_validate.number_in(width, "width", 1.0, 64.0),
            supersample=int(supersample),
            inner_color=_color(inner_color, "inner_color"),
            profile_color=_color(profile_color, "profile_color"),
            opacity=_validate.number_in(opacity, "opacity", 0.0, 1.0),
            source=source,
        )


def _edge_planes(gb: GBuffer, params: EdgeParams) -> tuple[np.ndarray, np.ndarray]:
    """The style's inner-edge and profile intensities at the output size."""
    opts = {"crease_angle": params.crease_angle, "depth_jump": params.depth_jump}
    if params.style == "enhance":
        emap = edge_map(gb, operator=params.operator, width=params.width, **opts)
        return emap[..., 0], emap[..., 3]
    if params.style == "profile":
        emap = edge_map(gb, operator=params.operator, width=params.width, **opts)
        return np.zeros_like(emap[..., 0]), emap[..., 3]
    if params.style == "lines":
        prof = np.maximum(*profile_and_crease_edges(gb, width=params.width, signed=False, **opts))
        return np.zeros_like(prof), prof
    emap = fig7_edge_map(gb, width=params.width, **opts)  # fig7
    return emap[..., 0], emap[..., 3]


def _inked(
    inner: np.ndarray, prof: np.ndarray, params: EdgeParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flat indices of the inked pixels, their straight colour (n, 3) and alpha (n,)."""
    # Only inked pixels need work (a few per cent of a frame): gather them, compose, scatter.
    ink = np.flatnonzero((inner > 0) | (prof > 0))  # NaN compares False: no ink
    i = np.clip(inner.reshape(-1)[ink], 0.0, 1.0).astype(np.float32) * params.opacity
    p = np.clip(prof.reshape(-1)[ink], 0.0, 1.0).astype(np.float32) * params.opacity
    alpha = i + p - i * p  # 1 - (1 - i)(1 - p): inner edges first, profiles over them
    premult = np.outer(p, params.profile_color) + np.outer(i * (1.0 - p), params.inner_color)
    return ink, premult / np.maximum(alpha, 1e-12)[:, None], alpha


def overlay_rgba(gb: GBuffer, params: EdgeParams) -> np.ndarray:
    """The overlay image of a G-buffer: (H, W, 4) float32, straight (not premultiplied) alpha.

    Compositing it over an image with ``src * a + dst * (1 - a)`` equals
    :func:`sciviz_gbuf.filters.enhance` of that image with the style's edge map: inner edges
    first (``lerp(dst, inner_color, R)``), then the profiles (``lerp(., profile_color, A)``).
    """
    inner, prof = _edge_planes(gb, params)
    h, w = inner.shape
    out = np.zeros((h, w, 4), np.float32)
    ink, rgb, alpha = _inked(inner, prof, params)
    flat = out.reshape(-1, 4)
    flat[ink, :3] = rgb
    flat[ink, 3] = alpha
    return out


def client_side_views(plotter: Any) -> list[str]:
    """Class names of the trame views rendering ``plotter`` in the browser (vtk.js, VTK-wasm).

    Looks the plotter up in the viewer registry of ``trame-pyvista`` (or of ``pyvista.trame``
    before PyVista 0.49) without importing it; a ``PyVistaRemoteLocalView`` counts while its
    rendering-mode toggle is on client-side rendering. Empty if none (or no trame loaded).
    """
    out = []
    for module in ("trame_pyvista.ui", "pyvista.trame.ui"):
        registry = getattr(sys.modules.get(module), "_VIEWERS", None)
        viewer = registry.get(getattr(plotter, "_id_name", None)) if registry else None
        if viewer is None:
            continue
        for view in list(getattr(viewer, "views", ())):
            name = type(view).__name__
            if name in _SERVER_RENDERED_VIEWS:
                continue
            if name == "PyVistaRemoteLocalView":
                try:
                    if viewer.server.state[viewer.SERVER_RENDERING]:
                        continue
                except Exception:  # unknown trame version: assume the server-rendered default
                    continue
            out.append(name)
    return sorted(set(out))


def _activate(renderers: Any, index: int) -> None:
    """Make renderer ``index`` (flat) the active one (the API wants a (row, column) for grids)."""
    loc = np.atleast_1d(renderers.index_to_loc(int(index)))
    renderers.set_active_renderer(*(int(v) for v in loc))


class LiveEdges:
    """The live overlay of one renderer (subplot) of one plotter.

    Parameters
    ----------
    plotter : pyvista.BasePlotter
    renderer : pyvista.Renderer
        The subplot to enhance; only its viewport gets the overlay.
    params : EdgeParams
    """

    def __init__(self, plotter: Any, renderer: Any, params: EdgeParams) -> None:
        self._plotter = plotter
        self._renderer = renderer
        self.params = params
        self._key: object = None
        self._busy = False
        #: Number of G-buffer captures so far (to check that still frames cost nothing).
        self.updates = 0
        #: The G-buffer of the last new view (its arrays are rewritten by the next one).
        self.last_gbuffer: GBuffer | None = None
        self._image = vtkImageData()
        self._pixels: np.ndarray | None = None  # numpy view of the uploaded image (_set_ink)
        self._last_ink = np.zeros(0, np.int64)
        self._image.SetDimensions(1, 1, 1)
        self._set_pixels(np.zeros((1, 1, 4), np.uint8))
        mapper = vtkImageMapper()
        mapper.SetInputData(self._image)
        # unsigned char through window 255 / level 127.5 is the identity: texels are pixels
        mapper.SetColorWindow(255.0)
        mapper.SetColorLevel(127.5)
        self._actor = vtkActor2D()
        self._actor.SetMapper(mapper)
        self._actor.SetPosition(0, 0)
        self._overlay = vtkRenderer()
        self._overlay.SetInteractive(False)  # picking and interaction go to the subplot below
        self._overlay.AddViewProp(self._actor)
        self._window: Any = None
        # The scene's capture session (surfaces, triangle soup, offscreen window with the
        # geometry uploaded) while the scene stays the same; a new view only re-renders ids.
        self._session: CaptureSession | None = None
        self._scene_key: object = None
        self._observer: int | None = None
        self._overlay_observer: int | None = None
        self._zbuffer = vtkFloatArray()  # the frame route's read-back, kept between frames
        #: The route of the last frame: "capture", "frame" or "gpu".
        self.route: str | None = None
        self._layer: int | None = None
        self._warned_client_side = False
        self._end_observer: int | None = None
        self._gpu: GpuEdgePass | None = None
        #: Why the GPU route cannot draw in this window (None: it can, or was not tried).
        self.gpu_unavailable: str | None = None
        self._hardware: bool | None = None  # the window's GL renderer, once known

    # ------------------------------------------------------------------ lifecycle
    def attach(self) -> None:
        """Add the overlay renderer on a new top layer and start observing frames."""
        window = self._plotter.render_window
        if window is None:
            raise InputError("plotter: the plotter is closed; there is no window to enhance")
        self._window = window
        n = window.GetNumberOfLayers()
        window.SetNumberOfLayers(n + 1)
        self._layer = n
        self._overlay.SetLayer(n)  # layers > 0 keep the colour buffer: we draw over it
        self._overlay.SetViewport(self._renderer.GetViewport())
        window.AddRenderer(self._overlay)
        self._observer = window.AddObserver("StartEvent", self._on_start)
        # The overlay's own renderer starts after every lower layer is drawn: the frame route
        # reads the enhanced subplot's depth there, before the overlay draws over it.
        self._overlay_observer = self._overlay.AddObserver("StartEvent", self._on_overlay_start)
        # The GPU route draws into the frame once the subplot is drawn, before later layers.
        self._end_observer = self._renderer.AddObserver("EndEvent", self._on_renderer_end)
        # PyVista calls these on every plotter.render(), even when rendering is suppressed
        self._plotter.add_on_render_callback(self._on_plotter_render, render_event=False)
        self._on_plotter_render(self._plotter)

    def detach(self) -> None:
        """Remove everything :meth:`attach` added; the window renders exactly as before."""
        window, self._window = self._window, None
        if window is None:
            return
        if self._observer is not None:
            window.RemoveObserver(self._observer)
            self._observer = None
        if self._overlay_observer is not None:
            self._overlay.RemoveObserver(self._overlay_observer)
            self._overlay_observer = None
        if self._end_observer is not None:
            self._renderer.RemoveObserver(self._end_observer)
            self._end_observer = None
        self._release_gpu()
        # PyVista has no public way to remove one render callback (only to clear them all)
        callbacks = getattr(self._plotter, "_on_render_callbacks", None)
        if callbacks is not None:
            callbacks.discard(self._on_plotter_render)
        window.RemoveRenderer(self._overlay)
        # Give back every layer above the highest one still in use (ours, and those of overlays
        # of other subplots removed before us), never one another renderer still uses.
        renderers = window.GetRenderers()
        used = [
            renderers.GetItemAsObject(k).GetLayer() for k in range(renderers.GetNumberOfItems())
        ]
        needed = max(used, default=0) + 1
        if self._layer is not None and needed <= self._layer < window.GetNumberOfLayers():
            window.SetNumberOfLayers(needed)
        self._layer = None
        self._key = None
        self._close_session()

    def _release_gpu(self) -> None:
        if self._gpu is not None:
            self._gpu.release()
        self._gpu = None

    def set_params(self, params: EdgeParams) -> None:
        """New parameters for the next frame: the capture session, the GPU route's programs
        and textures are kept (on the GPU they are uniforms: nothing is compiled)."""
        self.params = params
        self._key = None

    @property
    def gpu_frames(self) -> int:
        """Frames the GPU route has drawn (every frame while it is the route)."""
        return 0 if self._gpu is None else self._gpu.frames

    def gpu_edge_planes(self) -> tuple[np.ndarray, np.ndarray]:
        """The GPU route's last inner-edge and profile planes, (H, W) float32, row 0 on top
        (read back from the GPU: for tests and checks)."""
        if self._gpu is None:
            raise InputError("gpu_edge_planes: the GPU route has not drawn a frame")
        return self._gpu.edge_planes()

    def _close_session(self) -> None:
        if self._session is not None:
            self._session.close()
        self._session = None
        self._scene_key = None

    # ------------------------------------------------------------------ per frame
    def _on_plotter_render(self, plotter: Any) -> None:
        """Warn once if a client-side trame view shows this plotter (it cannot show us)."""
        if self._warned_client_side:
            return
        views = client_side_views(plotter)
        if views:
            self._warned_client_side = True
            warnings.warn(f"{CLIENT_SIDE_WARNING} (views: {', '.join(views)})", UserWarning,
                          stacklevel=3)  # fmt: skip

    def _view_key(self) -> tuple:
        """Everything the overlay depends on; a new frame with the same key reuses it."""
        ren = self._renderer
        cam = ren.GetActiveCamera()
        cam_key = (
            cam.GetPosition(),
            cam.GetFocalPoint(),
            cam.GetViewUp(),
            cam.GetViewAngle(),
            cam.GetParallelProjection(),
            cam.GetParallelScale(),
            cam.GetWindowCenter(),
            cam.GetUseHorizontalViewAngle(),
        )
        return (
            cam_key,
            tuple(ren.GetSize()),
            tuple(ren.GetViewport()),
            self._props_key(),
        )

    def _props_key(self) -> tuple:
        """The scene of the renderer: its actors, their visibility, transforms and data; the
        capture session is kept while it is the same."""
        props = []
        for name, actor in self._renderer.actors.items():
            mapper = actor.GetMapper() if hasattr(actor, "GetMapper") else None
            data = mapper.GetInputDataObject(0, 0) if mapper is not None else None
            # VTK addresses, not id(): the Python wrappers may be new objects on each access
            props.append(
                (
                    name,
                    actor.__this__,
                    actor.GetVisibility(),
                    actor.GetMTime(),
                    data.__this__ if data is not None else None,
                    data.GetMTime() if data is not None else 0,
                )
            )
        return tuple(props)

    def _gpu_wanted(self) -> bool:
        """Whether this frame goes to the GPU route (``gpu``, or ``auto`` on a graphics card)."""
        if self.gpu_unavailable is not None:
            return False
        source = self.params.source
        if source == "gpu":
            return True
        if source != "auto" or self.params.style not in GPU_STYLES:
            return False
        if self.params.supersample != 1 or self._window is None:
            return False
        if self._hardware is None:
            if not gl_info(self._window)["renderer"]:
                return False  # no frame rendered yet: no context to ask; next frame
            self._hardware = is_hardware(self._window)
        return self._hardware

    def _route(self) -> str:
        """``gpu``, ``frame`` or ``capture`` for this frame (see :data:`SOURCES`)."""
        if self._gpu_wanted():
            return "gpu"
        source = self.params.source
        if source == "gpu":
            return "capture"  # the GPU route cannot draw here (warned once)
        if source == "auto":
            # Exact only where the depth is the pixel centre's: one sample per pixel, drawn by
            # the renderer itself (a render pass such as PyVista's SSAA, EDL or SSAO draws
            # into buffers of its own, and its depth is not the frame's).
            window = self._window
            single = window is not None and window.GetMultiSamples() <= 1
            plain = self._renderer.GetPass() is None
            return "frame" if single and plain and self.params.supersample == 1 else "capture"
        return source

    def _on_start(self, _obj: object, _event: str) -> None:
        """The window starts a frame: the capture route updates before anything is drawn."""
        route = self._route()
        if route == "gpu" and self.route != "gpu":
            self._set_pixels(np.zeros((1, 1, 4), np.uint8))  # no CPU image over its lines
            self._key = None
        if route == "capture":
            self._refresh("capture")

    def _gpu_failed(self, why: str) -> None:
        """Give up the GPU route in this window and say so once; the CPU routes take over."""
        self.gpu_unavailable = why
        self._release_gpu()
        warnings.warn(f"sciviz_gbuf live edges: the GPU route cannot draw here ({why}); "
                      "using the CPU capture route", RuntimeWarning, stacklevel=2)  # fmt: skip

    def _on_renderer_end(self, renderer: Any, _event: str) -> None:
        """The subplot is drawn, its framebuffer bound: the GPU route draws into it now."""
        if self._busy or renderer.GetSelector() is not None:
            return  # a hardware selector's frame holds ids, not colours: leave it alone
        if self._route() != "gpu" or self._window is None:
            return
        try:
            if self._gpu is None:
                self._gpu = GpuEdgePass(self._window)
            self._gpu.draw(renderer, self.params)
            self.route = "gpu"
        except GpuUnavailable as exc:
            # this frame goes without edges (a capture now would switch GL contexts in the
            # middle of the user's frame); the next frame captures on the CPU
            self._gpu_failed(str(exc))

    def _on_overlay_start(self, _obj: object, _event: str) -> None:
        """The subplot is drawn, the overlay is next: the frame route reads its depth now."""
        if self._route() == "frame":
            self._refresh("frame")

    def _refresh(self, route: str) -> None:
        if self._busy:  # our own capture never renders this window, but never loop anyway
            return
        key = (route, self._view_key())
        if key == self._key:
            return
        self._busy = True
        try:
            self.update(route)
            self._key = key
        except Exception as exc:  # an observer must not raise into VTK: warn, show nothing
            self._set_pixels(np.zeros((1, 1, 4), np.uint8))
            self._key = key
            warnings.warn(f"sciviz_gbuf live edges: overlay disabled for this frame: {exc}",
                          RuntimeWarning, stacklevel=2)  # fmt: skip
        finally:
            self._busy = False

    def capture(self) -> GBuffer | None:
        """G-buffer of the renderer's scene with its camera at its pixel size (None: empty)."""
        ren = self._renderer
        w, h = (int(v) for v in ren.GetSize())
        if w < 1 or h < 1:
            return None
        key = self._props_key()
        if self._session is None or key != self._scene_key:
            self._close_session()
            renderers = self._plotter.renderers
            old = renderers.active_index
            # the session reads the active renderer's actors: point it at ours meanwhile
            _activate(renderers, next(i for i, r in enumerate(renderers) if r is ren))
            try:
                self._session = CaptureSession(self._plotter)
            except InputError as exc:
                if "no visible actor" in str(exc):
                    return None  # an empty subplot has no edges
                raise
            finally:
                _activate(renderers, old)
            self._scene_key = key
        return self._session.capture(
            window_size=(w, h),
            camera=ren.GetActiveCamera(),
            supersample=self.params.supersample,
            reuse=True,  # nothing is kept from frame to frame (last_gbuffer: until the next)
        )

    def frame_gbuffer(self) -> GBuffer | None:
        """G-buffer of the subplot from the depth of the frame being drawn (None: empty)."""
        ren = self._renderer
        w, h = (int(v) for v in ren.GetSize())
        if w < 1 or h < 1 or self._window is None:
            return None
        z = read_zbuffer(self._window, ren.GetOrigin(), (w, h), out=self._zbuffer)
        gb = gbuffer_from_zbuffer(z, CameraInfo.from_vtk(ren.GetActiveCamera(), (w, h)))
        return gb if gb.mask.any() else None

    def update(self, route: str = "capture") -> None:
        """Make the G-buffer by ``route`` now and upload a new overlay (called by the frame
        observers: ``capture`` before the frame, ``frame`` after the subplot is drawn)."""
        self._overlay.SetViewport(self._renderer.GetViewport())
        gb = self.frame_gbuffer() if route == "frame" else self.capture()
        self.route = route
        self.updates += 1
        self.last_gbuffer = gb
        if gb is None:
            self._set_pixels(np.zeros((1, 1, 4), np.uint8))
            return
        self._set_ink(*_edge_planes(gb, self.params))

    def _set_ink(self, inner: np.ndarray, prof: np.ndarray) -> None:
        """Upload ``np.round(overlay_rgba * 255)`` as uint8, writing only the inked pixels of
        this frame and clearing those of the last into one kept image: a frame touches a few
        per cent of its pixels, not four full-size float images."""
        h, w = inner.shape
        if self._pixels is None or self._pixels.shape != (h, w, 4):
            self._set_pixels(np.zeros((h, w, 4), np.uint8))
            self._pixels = self._pixels_vtk_view()
            self._last_ink = np.zeros(0, np.int64)
        ink, rgb, alpha = _inked(inner, prof, self.params)
        # VTK images start at the bottom row: flat index r * w + c goes to (h - 1 - r) * w + c.
        flat = self._pixels.reshape(-1, 4)
        flat[self._last_ink] = 0
        dst = (h - 1 - ink // w) * w + ink % w
        # the float32 overlay_rgba stores, rounded as its caller did
        flat[dst, :3] = np.round(rgb.astype(np.float32) * np.float32(255.0)).astype(np.uint8)
        flat[dst, 3] = np.round(alpha * np.float32(255.0)).astype(np.uint8)
        self._last_ink = dst
        self._image.GetPointData().GetScalars().Modified()
        self._image.Modified()

    def _pixels_vtk_view(self) -> np.ndarray:
        """The (H, W, 4) uint8 numpy view of the image's scalars (bottom row first)."""
        arr = self._image.GetPointData().GetScalars()
        w, h, _ = self._image.GetDimensions()
        return vtk_to_numpy(arr).reshape(h, w, 4)

    def _set_pixels(self, rgba: np.ndarray) -> None:
        h, w = rgba.shape[:2]
        self._image.SetDimensions(w, h, 1)
        # VTK images start at the bottom row
        flat = np.ascontiguousarray(rgba[::-1].reshape(h * w, 4))
        arr = numpy_to_vtk(flat, deep=True)
        arr.SetName("edges")
        self._image.GetPointData().SetScalars(arr)
        self._image.Modified()
        self._pixels = None  # a new array: the kept view (if any) is not it
