"""PyVista integration: ``mesh.gbuf`` (dataset accessor) and ``plotter.gbuf`` (plotter component).

Registered through PyVista's own extension points (PyVista >= 0.48):
:func:`pyvista.register_dataset_accessor` and :func:`pyvista.register_plotter_component`. The
package declares the entry points ``gbuf = "sciviz_gbuf.pyvista_plugin"`` in the groups
``pyvista.accessors`` and ``pyvista.plotter_components``, so with the package installed
``pv.Sphere().gbuf`` works without importing :mod:`sciviz_gbuf`: PyVista imports this module on
the first ``.gbuf`` lookup. Importing this module registers both (idempotently).

Datasets::

    img = mesh.gbuf.capture(window_size=(800, 600))     # pyvista.ImageData, one point a pixel
    gb = img.gbuf.gbuffer()                              # the GBuffer back (lossless)
    pic = mesh.gbuf.edges(style="enhance")               # ImageData with an "RGB" point array
    topo = dem_grid.gbuf.topographic_map(interval=20)   # ImageData with "RGBA" on the grid

Plotters::

    pl.gbuf.capture()                                    # G-buffer of the active subplot
    pl.gbuf.enable_edge_enhancement(style="enhance")     # live overlay on the active subplot
    pl.gbuf.edge_enhancement_enabled                     # True
    pl.gbuf.disable_edge_enhancement()

All arguments are keyword-only; bad values raise :class:`sciviz_gbuf.errors.InputError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pyvista as pv

from . import live as _live
from .core.capture import capture as _capture
from .core.gbuffer import GBuffer
from .errors import InputError
from .readers.dem import read_dem
from .recipes.terrain import topographic_map as _topographic_map
from .styles import check_style, illustrate

__all__ = ["ACCESSOR_NAME", "GBufAccessor", "GBufPlotterComponent", "register"]

#: Name of the accessor and of the plotter component.
ACCESSOR_NAME = "gbuf"
# Field-data key GBuffer.to_pyvista stores its metadata under (marks a G-buffer image).
_META_KEY = "sciviz_gbuf_meta"


def _image_from_rgb(rgb: np.ndarray, name: str) -> pv.ImageData:
    """(H, W, k) float in [0, 1] or uint8, row 0 on top -> ImageData with uint8 point array."""
    a = np.asarray(rgb)
    if a.dtype != np.uint8:
        a = np.round(np.clip(np.nan_to_num(a, nan=1.0), 0.0, 1.0) * 255.0).astype(np.uint8)
    h, w = a.shape[:2]
    img = pv.ImageData(dimensions=(w, h, 1))
    # VTK images start at the bottom row: pixel (i, j) is point (j, H-1-i), as in to_pyvista
    img.point_data[name] = np.ascontiguousarray(a[::-1].reshape(h * w, a.shape[2]))
    img.set_active_scalars(name)
    return img


def _is_gbuffer_image(ds: object) -> bool:
    return isinstance(ds, pv.ImageData) and _META_KEY in ds.field_data


class GBufAccessor:
    """``dataset.gbuf``: G-buffers, edge pictures and topographic maps of a PyVista dataset.

    Parameters
    ----------
    dataset : pyvista.DataSet
        The dataset the accessor is attached to.
    """

    def __init__(self, dataset: Any) -> None:
        self._dataset = dataset

    def capture(
        self,
        *,
        window_size: Sequence[int] | None = None,
        camera: object = None,
        parallel_projection: bool | None = None,
        scalars: Sequence[str] | str = (),
        supersample: int = 1,
        feature_angle: float = 30.0,
        progress_bar: bool = False,
        up: str | None = None,
    ) -> pv.ImageData:
        """Capture the dataset's G-buffer (:func:`sciviz_gbuf.capture`) as an ImageData.

        Parameters
        ----------
        window_size, camera, parallel_projection, scalars, supersample, feature_angle
            As in :func:`sciviz_gbuf.capture`.
        up : {"x", "y", "z"}, optional
            The upright world axis of the named views (``--up`` of the CLI). Default: the
            convention of the file :func:`sciviz_gbuf.readers.read_mesh` read the dataset
            from (y for OFF/OBJ/PLY/glTF), else z. ``pyvista.read`` does not record the file: give
            ``up="y"`` for a y-up model read that way, or read it with ``read_mesh``.
        progress_bar : bool, default: False
            Show a progress bar.

        Returns
        -------
        pyvista.ImageData
            One point per buffer pixel (``GBuffer.to_pyvista``): every channel (``depth``,
            ``sz``, ``normal``, ``world``, ``object_id``, ``cell_id``, ``mask``, ``uv``,
            ``scalars:<name>``) is a point array, the camera and metadata are in field data.
            ``image.gbuf.gbuffer()`` (or ``GBuffer.from_pyvista(image)``) gives the
            :class:`~sciviz_gbuf.GBuffer` back, bit for bit.
        """
        gb = _capture(
            self._dataset,
            window_size=window_size,
            camera=camera,
            parallel_projection=parallel_projection,
            scalars=scalars,
            supersample=supersample,
            feature_angle=feature_angle,
            progress_bar=progress_bar,
            up=up,
        )
        return gb.to_pyvista()

    def gbuffer(self) -> GBuffer:
        """The :class:`~sciviz_gbuf.GBuffer` of an image made by :meth:`capture`.

        Raises
        ------
        InputError
            If the dataset is not such an image.
        """
        if not _is_gbuffer_image(self._dataset):
            raise InputError(
                "dataset: not a G-buffer image (expected the result of .gbuf.capture())"
            )
        return GBuffer.from_pyvista(self._dataset, source="dataset")

    def edges(
        self,
        *,
        style: str = "enhance",
        operator: str = "diagonal",
        crease_angle: float = 30.0,
        depth_jump: float = 1.0,
        width: float = 1.0,
        window_size: Sequence[int] | None = None,
        camera: object = None,
        parallel_projection: bool | None = None,
        supersample: int | None = None,
        up: str | None = None,
        progress_bar: bool = False,
    ) -> pv.ImageData:
        """An edge-enhanced picture of the dataset (:func:`~sciviz_gbuf.recipes.illustrate`):
        the picture ``sciviz-gbuf edges FILE -o out.png`` draws of the same file with the same
        options (same size, view, supersampling, up axis).

        On an image made by :meth:`capture` the stored G-buffer is used (no new render;
        ``window_size``, ``camera``, ``parallel_projection``, ``up`` and ``supersample`` must
        then be left unset).

        Parameters
        ----------
        style : {"enhance", "lines", "fig7", "edgemap"}, default: "enhance"
            ``enhance``: shaded, white inner edges, black profiles (2003); ``lines``: black
            profile and crease lines on white; ``fig7``: convex edges white, concave black (1990
            Fig. 7); ``edgemap``: the RGBA edge map itself.
        operator, crease_angle, depth_jump, width
            As in :func:`sciviz_gbuf.filters.edge_map`.
        window_size, camera, parallel_projection
            As in :func:`sciviz_gbuf.capture` (default ``(1024, 768)``, the ``iso`` view).
        supersample : int, optional
            Render at this many times the size and average down (antialiasing); default 2,
            as the CLI.
        up : {"x", "y", "z"}, optional
            The upright world axis, as in :meth:`capture`.
        progress_bar : bool, default: False
            Show a progress bar while capturing.

        Returns
        -------
        pyvista.ImageData
            One point per output pixel with the uint8 point array ``"RGB"`` (``"RGBA"`` for
            ``edgemap``: RGB inner edges, A profiles), active, so ``.plot(rgb=True)`` or
            ``.save("x.png")`` work directly.
        """
        style = check_style(style, "illustrate")
        if _is_gbuffer_image(self._dataset):
            given = {
                "window_size": window_size is not None,
                "camera": camera is not None,
                "parallel_projection": parallel_projection is not None,
                "up": up is not None,
                "supersample": supersample is not None,
            }
            if any(given.values()):
                names = "/".join(k for k, v in given.items() if v)
                raise InputError(
                    f"{names}: this is a captured G-buffer image; its view and size are fixed"
                )
            gb = self.gbuffer()
        else:
            gb = _capture(
                self._dataset,
                window_size=window_size,
                camera=camera,
                parallel_projection=parallel_projection,
                supersample=2 if supersample is None else supersample,
                progress_bar=progress_bar,
                up=up,
            )
        picture = illustrate(
            gb,
            style=style,
            operator=operator,
            crease_angle=crease_angle,
            depth_jump=depth_jump,
            width=width,
        )
        return _image_from_rgb(picture, "RGBA" if picture.shape[-1] == 4 else "RGB")

    def topographic_map(self, *, heights: str | None = None, **kwargs: Any) -> pv.ImageData:
        """A plan-view topographic map of a height grid (:func:`sciviz_gbuf.topographic_map`).

        Parameters
        ----------
        heights : str, optional
            Point array holding the heights. Default: ``"elevation"`` if present (the array of
            ``DEM.to_pyvista()``), else the active point scalars; a StructuredGrid without
            either uses its points' z.
        **kwargs
            Keyword arguments of :func:`sciviz_gbuf.topographic_map` (``interval``,
            ``major_interval``, ``bands``, ``relief``, ``progress_bar``, ...).

        Returns
        -------
        pyvista.ImageData
            On the grid: the same dimensions, origin and spacing (x, y), with the uint8 point
            array ``"RGBA"`` (active; nodata transparent).

        Raises
        ------
        InputError
            If the dataset is not a 2-D ImageData or an axis-aligned regular StructuredGrid
            in the x/y plane, or for a bad map parameter.
        """
        z, origin, spacing = _grid_heights(self._dataset, heights)
        dem = read_dem(z[::-1], spacing=spacing, geographic=False)  # row 0 north
        rgba = _topographic_map(dem, **kwargs)
        img = _image_from_rgb(rgba, "RGBA")
        img.origin = origin
        img.spacing = (spacing[0], spacing[1], 1.0)
        return img


def _grid_heights(
    ds: Any, name: str | None
) -> tuple[np.ndarray, tuple[float, float, float], tuple[float, float]]:
    """Heights (ny, nx) with row 0 south, the grid origin and (dx, dy) of a 2-D height grid."""
    if isinstance(ds, pv.ImageData):
        nx, ny, nz = ds.dimensions
        if nz != 1 or nx < 2 or ny < 2:
            raise InputError(
                f"dataset: expected a 2-D ImageData in the x/y plane (dimensions (nx, ny, 1)), "
                f"got dimensions {ds.dimensions}"
            )
        if not np.allclose(np.asarray(ds.direction_matrix), np.eye(3)):
            raise InputError("dataset: a rotated ImageData (direction matrix) is not supported")
        values = _height_array(ds, name, allow_z=False)
        dx, dy, _ = ds.spacing
        return values.reshape(ny, nx), tuple(ds.origin), (float(dx), float(dy))
    if isinstance(ds, pv.StructuredGrid):
        nx, ny, nz = ds.dimensions
        if nz != 1 or nx < 2 or ny < 2:
            raise InputError(
                f"dataset: expected a StructuredGrid of dimensions (nx, ny, 1), got {ds.dimensions}"
            )
        pts = np.asarray(ds.points, dtype=np.float64).reshape(ny, nx, 3)
        x, y = pts[..., 0], pts[..., 1]
        dx, dy = x[0, 1] - x[0, 0], y[1, 0] - y[0, 0]
        tol = 1e-6 * max(abs(dx), abs(dy))
        regular = (
            dx > 0
            and dy > 0
            and np.allclose(x, x[0, 0] + dx * np.arange(nx)[None, :], rtol=0, atol=tol * nx)
            and np.allclose(y, y[0, 0] + dy * np.arange(ny)[:, None], rtol=0, atol=tol * ny)
        )
        if not regular:
            raise InputError(
                "dataset: the StructuredGrid is not a regular x/y grid (x increasing along i, "
                "y along j, evenly spaced), as DEM.to_pyvista() makes"
            )
        if name is None and "elevation" not in ds.point_data and ds.active_scalars is None:
            values = pts[..., 2].ravel()
        else:
            values = _height_array(ds, name, allow_z=True)
        origin = (float(x[0, 0]), float(y[0, 0]), 0.0)
        return np.asarray(values, np.float64).reshape(ny, nx), origin, (float(dx), float(dy))
    raise InputError(
        f"dataset: topographic_map needs a 2-D ImageData or StructuredGrid of heights, "
        f"got {type(ds).__name__}"
    )


def _height_array(ds: Any, name: str | None, *, allow_z: bool) -> np.ndarray:
    if name is None:
        if "elevation" in ds.point_data:
            name = "elevation"
        elif ds.active_scalars_name is not None and ds.active_scalars_info.association.name == (
            "POINT"
        ):
            name = ds.active_scalars_name
        else:
            hint = ", or points' z" if allow_z else ""
            raise InputError(
                f"heights: no point array named 'elevation' and no active point scalars{hint}; "
                f"pass heights=<name> (point arrays: {list(ds.point_data.keys())})"
            )
    if name not in ds.point_data:
        raise InputError(
            f"heights: no point array {name!r}; point arrays: {list(ds.point_data.keys())}"
        )
    a = np.asarray(ds.point_data[name], dtype=np.float64)
    if a.ndim != 1:
        raise InputError(f"heights: {name!r} has {a.shape[1]} components; expected one")
    return a


class GBufPlotterComponent:
    """``plotter.gbuf``: G-buffer capture and live edge enhancement of a PyVista plotter.

    Parameters
    ----------
    plotter : pyvista.BasePlotter
        The plotter the component is attached to.
    """

    def __init__(self, plotter: Any) -> None:
        self._plotter = plotter
        # one live overlay per enhanced renderer (subplot), keyed by the renderer's id
        self._live: dict[int, _live.LiveEdges] = {}
        # live contour lines per actor, keyed by the actor's VTK address
        self._contours: dict[str, _live.LiveContours] = {}

    def capture(self, **kwargs: Any) -> pv.ImageData:
        """G-buffer of the active subplot (its visible actors and camera) as an ImageData.

        Parameters
        ----------
        **kwargs
            Keyword arguments of :func:`sciviz_gbuf.capture` (``window_size``, ``camera``,
            ``scalars``, ``supersample``, ``progress_bar``, ...).

        Returns
        -------
        pyvista.ImageData
            As :meth:`GBufAccessor.capture`.
        """
        return _capture(self._plotter, **kwargs).to_pyvista()

    def enable_edge_enhancement(
        self,
        *,
        style: str = "enhance",
        operator: str = "diagonal",
        crease_angle: float = 30.0,
        depth_jump: float = 1.0,
        width: float = 1.0,
        supersample: int = 1,
        inner_color: Sequence[float] = (1.0, 1.0, 1.0),
        profile_color: Sequence[float] = (0.0, 0.0, 0.0),
        opacity: float = 1.0,
        source: str = "auto",
    ) -> Any:
        """Draw the edge map over every frame of the active subplot, updated as the view moves.

        In a frame where the camera, the window size or any actor or its data changed since
        the previous one, the subplot's G-buffer is made anew (from that frame's own depth, or
        by an offscreen capture: ``source``) and its edge map composited over the normal
        rendering of that subplot only. Calling it again replaces the parameters.

        Parameters
        ----------
        style : {"enhance", "profile", "lines", "fig7"}, default: "enhance"
            ``enhance``: inner edges in ``inner_color``, profiles in ``profile_color`` (2003);
            ``profile``: profiles only; ``lines``: profile and crease lines in
            ``profile_color``; ``fig7``: convex edges ``inner_color``, concave edges and
            profiles ``profile_color`` (1990 Fig. 7).
        operator : {"diagonal", "c1"}, default: "diagonal"
        crease_angle, depth_jump, width
            As in :func:`sciviz_gbuf.filters.edge_map` (degrees, pixel footprints, pixels).
        supersample : int in [1, 4], default: 1
            Capture at k times the subplot size: antialiased lines, k² the cost.
        inner_color, profile_color : RGB floats in [0, 1]
            Default white and black.
        opacity : float in [0, 1], default: 1
            Scales the edge ink.
        source : {"auto", "frame", "capture", "gpu"}, default: "auto"
            Where the edges come from. ``gpu``: fragment shaders inside the frame read its
            depth and draw the edge map into it (no read-back; styles ``enhance`` and
            ``profile``, supersample 1; see :mod:`sciviz_gbuf.live.gpu`); ``auto`` takes it
            where the GL renderer is a graphics card's, and ``pl.gbuf.live.route`` says
            which route drew the last frame. ``frame``: the depth of the frame being drawn, read
            back once the subplot is drawn (no second render: the cost is the read-back and the
            edge map; normals from the depth, see :mod:`sciviz_gbuf.core.frame`; supersample
            1). ``capture``: a separate offscreen render of the subplot's surfaces (exact
            interpolated normals, supersampling). ``auto``: ``frame`` where it gives the same
            lines as ``capture`` (a window without multisampling, supersample 1), else
            ``capture``. With multisampling (PyVista's default anti-aliasing), the driver's
            depth resolve moves ``frame`` lines by up to a pixel, and a render pass of the
            subplot (SSAA, EDL, SSAO) draws into buffers of its own: ``auto`` captures there;
            ``pl.disable_anti_aliasing()`` lets it take the frame. Where the GPU route cannot
            draw (no depth to read), it warns once and the capture route takes over.

        Returns
        -------
        pyvista.Plotter
            The plotter, so calls chain.

        Notes
        -----
        The overlay is part of every frame the plotter's render window draws, so it shows
        wherever those frames go: interactive windows, ``show()``, ``screenshot()``, and the
        server-rendered Jupyter/trame views, which stream them: ``jupyter_backend='trame'``
        (PyVista's default; it starts in server rendering) and ``'server'``. Moving the camera
        there (dragging in the browser, or ``pl.camera...; pl.render()`` in a later cell)
        re-captures the edges for the new view. Client-side views re-render the scene with vtk.js
        in the browser and cannot show it: ``jupyter_backend='client'`` and ``'html'``, and the
        ``'trame'`` view once its toggle is switched to client-side rendering. When a client-side
        trame view shows the plotter, its next ``render()`` (``show()`` makes one) warns once.
        """
        params = _live.EdgeParams.checked(
            style=style,
            operator=operator,
            crease_angle=crease_angle,
            depth_jump=depth_jump,
            width=width,
            supersample=supersample,
            inner_color=inner_color,
            profile_color=profile_color,
            opacity=opacity,
            source=source,
        )
        renderer = self._plotter.renderer
        live = self._live.get(id(renderer))
        if live is not None:
            live.set_params(params)  # its session, textures and programs kept
        else:
            live = _live.LiveEdges(self._plotter, renderer, params)
            live.attach()
            self._live[id(renderer)] = live
        self._rerender()
        return self._plotter

    def _rerender(self) -> None:
        """Render once more if the plotter already rendered a frame.

        Off-screen, ``screenshot()`` reads the last frame without rendering again; without this
        the first screenshot after enabling/disabling would show the previous state.
        """
        pl = self._plotter
        if pl.render_window is not None and not getattr(pl, "_first_time", True):
            pl.render()

    def disable_edge_enhancement(self, *, all_subplots: bool = False) -> Any:
        """Remove the live edge overlay of the active subplot (or of all subplots).

        Every renderer, layer and observer the overlay added is removed: the next frame is
        bit for bit the plain rendering.

        Returns
        -------
        pyvista.Plotter
            The plotter, so calls chain.
        """
        keys = list(self._live) if all_subplots else [id(self._plotter.renderer)]
        # newest first, so each one gives its layer back (layers are a stack)
        return self._detach(self._live, reversed(keys))

    @property
    def edge_enhancement_enabled(self) -> bool:
        """Whether the active subplot has the live edge overlay."""
        return id(self._plotter.renderer) in self._live

    @property
    def live(self) -> _live.LiveEdges | None:
        """The live overlay of the active subplot (its ``updates`` count, last G-buffer)."""
        return self._live.get(id(self._plotter.renderer))

    def enable_contour_lines(
        self,
        actor: Any = None,
        *,
        interval: float,
        scalars: str | None = None,
        height: str | Sequence[float] | None = None,
        major_interval: float | None = None,
        base: float = 0.0,
        width: float = 1.0,
        major_width: float | None = None,
        profile: str = "linear",
        color: Sequence[float] = (0.0, 0.0, 0.0),
        opacity: float = 1.0,
        c_dense: float | None = None,
        dense_spacing: float | None = None,
        g_eps: float | None = None,
        c_sparse: float = 0.0,
    ) -> Any:
        """Draw contour lines on a surface actor, live, in the actor's own shaders.

        Saito & Takahashi's image-space contour lines (1990 Eq. 7-15), as
        :func:`sciviz_gbuf.filters.contour_lines` draws them, evaluated per fragment while
        the actor is drawn: one pass, no capture and no read-back (on a 2-core Mesa llvmpipe
        machine 0.91-0.96x the plain frame rate). A bird's-eye topographic map you can orbit:
        ``pl.gbuf.enable_contour_lines(actor, interval=20, major_interval=100)``. Calling it
        again for the same actor changes the parameters (new values compile nothing).

        Parameters
        ----------
        actor : vtkActor, optional
            The surface (what ``pl.add_mesh`` returns). Default: the active subplot's only
            mesh actor.
        interval : float > 0
            Level spacing ``q`` of Eq. 12, in field units.
        scalars : str, optional
            A one-component point array of the actor's data to draw the levels of (e.g.
            ``"Elevation"`` from ``mesh.elevation()``, a temperature, a CT value).
        height : {"x", "y", "z"} or 3-vector, optional
            The world coordinate along this axis as the field (default ``"z"`` when
            ``scalars`` is not given): heights of a terrain, at any model transform.
        major_interval, base, width, major_width, profile, c_dense, dense_spacing, g_eps,
        c_sparse
            As in :func:`sciviz_gbuf.filters.contour_lines` (widths in screen pixels; minors
            fade where they crowd, majors never).
        color : RGB floats in [0, 1], default: black
        opacity : float in [0, 1], default: 1

        Returns
        -------
        pyvista.Plotter
            The plotter, so calls chain.

        Notes
        -----
        Eq. 9's gradient is the field's screen-space derivative, exact for the field VTK
        interpolates linearly across each triangle. A level the surface nears without
        crossing (a summit within half a line width below it) draws a short mark that
        :func:`~sciviz_gbuf.filters.contour_lines` omits (it sees the neighbouring pixels);
        the maps' generalisation (smoothing, ring removal) is not applied.
        """
        options = _live.contour_options(
            interval=interval, major_interval=major_interval, base=base, width=width,
            major_width=major_width, profile=profile, c_dense=c_dense,
            dense_spacing=dense_spacing, g_eps=g_eps, c_sparse=c_sparse, color=color,
            opacity=opacity,
        )  # fmt: skip
        actor = self._contour_actor(actor)
        field = _live.ContourField.checked(actor, scalars, height)
        key = actor.__this__
        live = self._contours.get(key)
        if live is not None and vars(live.field) == vars(field):
            live.set_options(options)
        else:
            if live is not None:
                live.detach()
            live = _live.LiveContours(self._plotter, actor, field, options)
            live.attach()
            self._contours[key] = live
        self._rerender()
        return self._plotter

    def disable_contour_lines(self, actor: Any = None) -> Any:
        """Remove the live contour lines of ``actor`` (default: every actor that has them);
        the next frame is the plain one, bit for bit.

        Returns
        -------
        pyvista.Plotter
            The plotter, so calls chain.
        """
        keys = list(self._contours) if actor is None else [getattr(actor, "__this__", None)]
        return self._detach(self._contours, keys)

    def _detach(self, store: dict, keys: Any) -> Any:
        """Detach and forget the overlays of ``store`` under ``keys`` (in that order); render
        once more if any was there."""
        removed = False
        for key in keys:
            live = store.pop(key, None)
            if live is not None:
                live.detach()
                removed = True
        if removed:
            self._rerender()
        return self._plotter

    @property
    def contour_lines_enabled(self) -> bool:
        """Whether any actor of the plotter has live contour lines."""
        return bool(self._contours)

    def _contour_actor(self, actor: Any) -> Any:
        if actor is not None:
            return actor
        actors = [
            a
            for a in self._plotter.renderer.actors.values()
            if hasattr(a, "GetMapper") and a.GetMapper() is not None and a.GetVisibility()
            and hasattr(a, "GetShaderProperty")
        ]  # fmt: skip
        if len(actors) != 1:
            raise InputError(
                f"actor: the active subplot has {len(actors)} mesh actors; pass the one to draw "
                "contour lines on (pl.add_mesh returns it)"
            )
        return actors[0]

    def _drop_all(self) -> None:
        # closing: no re-render, the window is going away
        for key in reversed(list(self._live)):
            self._live.pop(key).detach()
        for key in list(self._contours):
            self._contours.pop(key).detach()

    def __plotter_close__(self) -> None:
        """PyVista lifecycle hook: drop every overlay and observer when the plotter closes."""
        self._drop_all()

    def __plotter_deep_clean__(self) -> None:
        """PyVista lifecycle hook (``deep_clean``): as on close."""
        self._drop_all()


def register() -> None:
    """Register ``gbuf`` on every PyVista dataset and plotter (idempotent).

    Raises
    ------
    RuntimeError
        If PyVista is older than 0.48 (no extension points) or ``gbuf`` would shadow one of
        PyVista's own attributes (PyVista's ValueError is passed on).
    """
    if not hasattr(pv, "register_dataset_accessor"):
        raise RuntimeError("sciviz_gbuf's PyVista plugin needs pyvista >= 0.48")
    # re-registering the same class is a no-op for accessors, but warns for components
    pv.register_dataset_accessor(ACCESSOR_NAME, pv.DataSet)(GBufAccessor)
    current = pv.BasePlotter.__dict__.get(ACCESSOR_NAME)
    if getattr(current, "_component_cls", None) is not GBufPlotterComponent:
        pv.register_plotter_component(ACCESSOR_NAME, pv.BasePlotter)(GBufPlotterComponent)


register()
