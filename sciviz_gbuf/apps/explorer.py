"""Interactive exploration of one scene: capture once, re-run only the filters per parameter.

:class:`Explorer` owns a surface (a mesh file, a DEM as a height field, or the bone surface of
a DICOM series), a cached :class:`~sciviz_gbuf.GBuffer` and the current parameters.
:meth:`Explorer.render_image` runs only the image-space filters and styles on the cached
buffer; only :meth:`Explorer.set_camera` captures again. The web front end (``sciviz-gbuf
explore``) lives in :mod:`sciviz_gbuf.cli.explore`.
"""

from __future__ import annotations

import base64
import dataclasses
import io
import math
import numbers
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np
import pyvista as pv

from .._validate import LIMITS, at_most, number_in
from ..compose import to_uint8
from ..core.capture import capture
from ..core.framing import check_up, default_up, framed_camera
from ..core.gbuffer import GBuffer
from ..datasets import load_nut
from ..errors import InputError
from ..filters import color_bands, contour_lines, edge_map
from ..readers import DEM, kind_of, read_dem, read_scene, suffixes
from ..recipes.medical import ct_surface
from ..recipes.terrain import (
    CONTOUR_COLOR,
    composite,
    contour_intervals,
    map_grid,
    map_layers,
    map_min_ring,
)
from ..styles import check_style, gooch, hatch, styles_for, toon
from ..styles.fused import FUSED_CONSTANTS, fused_style, rgba_on_paper
from ..styles.illustration import (
    fig7_edge_map,
    illustrate,
    is_dark,
    line_ink,
    profile_ink,
    thin_edge_map,
)

__all__ = [
    "CAMERA_BOUNDS",
    "DEM_SUFFIXES",
    "PARAM_BOUNDS",
    "RELIEF_VARIANTS",
    "STYLES",
    "VIEWS",
    "Explorer",
    "Params",
    "encode_jpeg_data_url",
    "load_scene",
    "style_image",
]

#: Style name -> one-line description (the explorer's styles of the styles registry).
STYLES = styles_for("explore")
#: File suffixes read as DEMs (from the readers' one format table).
DEM_SUFFIXES = suffixes("dem")
_CONTOUR_COLOR = np.array([0.45, 0.22, 0.05], dtype=np.float32)
#: Views of a DEM: the plan-view topographic map, or the height field captured in 3-D.
VIEWS = ("map", "3d")
#: Relief shades of the map (:func:`~sciviz_gbuf.filters.hillshade` variants).
RELIEF_VARIANTS = ("regular", "multidirectional", "combined", "igor")

_F32_MAX = float(np.finfo(np.float32).max)
_LINE = float(LIMITS["line_width"])
#: Bounds of the numeric :class:`Params`: name -> ``(low, high, low_excluded, integer)``.
#: Line widths and band counts are those of the Python API (:data:`~sciviz_gbuf._validate.LIMITS`);
#: the map's majors are drawn twice as wide as ``map_width``, so it gets half the width limit;
#: intervals are float32 numbers like the G-buffer's heights (their level counts are checked
#: against the height range in :meth:`Explorer.render_image`).
PARAM_BOUNDS: dict[str, tuple[float, float, bool, bool]] = {
    "crease_angle": (0.0, 180.0, True, False),
    "depth_jump": (0.0, 1e4, True, False),
    "width": (1.0, _LINE, False, False),
    "contour_interval": (0.0, _F32_MAX, False, False),
    "contour_width": (0.0, _LINE, True, False),
    "bands": (0, LIMITS["bands"], False, True),
    "light_azimuth": (-360.0, 360.0, False, False),
    "light_elevation": (-90.0, 90.0, False, False),
    "map_azimuth": (-360.0, 360.0, False, False),
    "map_altitude": (0.0, 90.0, False, False),
    "z_factor": (0.0, 1e4, True, False),
    "map_interval": (0.0, _F32_MAX, False, False),
    "major_every": (1, LIMITS["levels"], False, True),
    "map_width": (0.0, _LINE / 2, True, False),
    "map_bands": (0, LIMITS["bands"], False, True),
}


def _short(value: object, limit: int = 60) -> str:
    """``repr(value)`` cut to ``limit`` characters: a browser may send megabytes in one value
    and the message must stay one short line."""
    text = repr(value).replace("\n", " ")
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _bounded(
    value: object, name: str, low: float, high: float, *, strict: bool, integer: bool
) -> float:
    """``value`` as a float if it is a real number (an integer if ``integer``) in
    ``[low, high]`` (``(low, high]`` if ``strict``), else an InputError naming ``name``."""
    kind = "an integer" if integer else "a number"
    span = f"{'(' if strict else '['}{low:g}, {high:g}]"
    typed = isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))
    if not typed or (integer and not isinstance(value, numbers.Integral)):
        raise InputError(f"{name}: expected {kind} in {span}, got {_short(value)}")
    try:
        v = float(value)
    except OverflowError:  # an int beyond float range is out of every bound
        v = math.inf
    if strict and not v > low:
        raise InputError(f"{name}: expected {kind} in {span}, got {_short(value)}")
    return number_in(v, name, low, high)


@dataclass(frozen=True)
class Params:
    """Enhancement parameters of one picture (all image-space: no capture needed).

    Attributes
    ----------
    style : str
        One of :data:`STYLES`.
    crease_angle, depth_jump, width : float
        Edge thresholds (degrees, pixel footprints) and line width (output pixels).
    contour_interval, contour_width : float
        Contour lines of the height (the world coordinate along the explorer's up axis, z by
        default) every ``contour_interval`` data units (0: none), ``contour_width`` pixels
        wide.
    bands : int
        Number of colour bands over the visible height range (0: none).
    light_azimuth, light_elevation : float
        Eye-space light: azimuth in degrees counter-clockwise from the image's right, elevation
        in degrees towards the viewer.
    view : str
        ``"3d"`` (the captured surface, all the parameters above) or, for a DEM, ``"map"``:
        the plan-view topographic map of :func:`~sciviz_gbuf.recipes.terrain.topographic_map`
        on the DEM grid, with the ``map_*`` parameters below only.
    map_azimuth, map_altitude, z_factor, relief : float, float, float, str
        The map's relief shade, as in :func:`~sciviz_gbuf.filters.hillshade` (GDAL: azimuth
        clockwise from north, altitude in degrees; a variant of :data:`RELIEF_VARIANTS`).
    map_interval, major_every, map_width : float, int, float
        Minor contour interval in height units (0: no contours), a major line every
        ``major_every`` (>= 1) minors, minor line width in pixels (majors twice that; minors
        thin out where they crowd, majors never).
    map_bands : int
        Hypsometric tint: 0 none (white paper), 1 a continuous ramp, n >= 2 n equal colour
        bands over the DEM's height range.
    """

    style: str = "enhance"
    crease_angle: float = 30.0
    depth_jump: float = 1.0
    width: float = 1.0
    contour_interval: float = 0.0
    contour_width: float = 1.0
    bands: int = 0
    light_azimuth: float = 129.0
    light_elevation: float = 50.0
    view: str = "3d"
    map_azimuth: float = 315.0
    map_altitude: float = 45.0
    z_factor: float = 1.0
    relief: str = "regular"
    map_interval: float = 0.0
    major_every: int = 5
    map_width: float = 1.0
    map_bands: int = 0

    def light(self) -> tuple[float, float, float]:
        """The unit eye-space light direction (x right, y up, z to the viewer)."""
        az, el = math.radians(self.light_azimuth), math.radians(self.light_elevation)
        return (math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el))

    def checked(self) -> Params:
        """These parameters, or an :class:`InputError` naming the first bad one.

        Every parameter is bounded above as well as below (:data:`PARAM_BOUNDS`; the line
        widths and band counts by :data:`~sciviz_gbuf._validate.LIMITS`, as in the Python
        API), so no value a browser can send makes one update compute for minutes."""
        if not isinstance(self.style, str):
            raise InputError(f"style: expected a style name, got {_short(self.style)}")
        check_style(self.style, "explore")
        for name, (low, high, strict, integer) in PARAM_BOUNDS.items():
            _bounded(getattr(self, name), name, low, high, strict=strict, integer=integer)
        if not isinstance(self.view, str) or self.view not in VIEWS:
            raise InputError(f"view: expected one of {list(VIEWS)}, got {_short(self.view)}")
        if not isinstance(self.relief, str) or self.relief not in RELIEF_VARIANTS:
            raise InputError(
                f"relief: expected one of {list(RELIEF_VARIANTS)}, got {_short(self.relief)}"
            )
        return self

    def map_kwargs(self, height_range: tuple[float, float]) -> dict[str, object]:
        """The keyword arguments of :func:`~sciviz_gbuf.recipes.terrain.topographic_map`
        that draw this map of a DEM whose heights span ``height_range``."""
        q = float(self.map_interval)
        lo, hi = height_range
        n = self.map_bands
        if n == 0:
            bands: object = False
        elif n == 1 or not hi > lo:
            bands = "continuous"
        else:
            bands = [lo + (hi - lo) * k / n for k in range(1, n)]
        return {
            "contours": q > 0,
            "interval": q if q > 0 else 1.0,
            "major_interval": (q if q > 0 else 1.0) * self.major_every,
            "width": float(self.map_width),
            "major_width": 2.0 * float(self.map_width),
            "bands": bands,
            "azimuth": float(self.map_azimuth),
            "altitude": float(self.map_altitude),
            "z_factor": float(self.z_factor),
            "variant": self.relief,
        }


#: Points of the scene the orbit camera frames, at most about this many.
_FRAME_POINTS = 20_000

#: Bounds of the orbit camera: name -> ``(low, high, low_excluded)`` (degrees, zoom factor).
CAMERA_BOUNDS: dict[str, tuple[float, float, bool]] = {
    "azimuth": (-360.0, 360.0, False),
    "elevation": (-90.0, 90.0, False),
    "zoom": (0.01, 100.0, False),
}


@dataclass
class _Camera:
    azimuth: float = 45.0
    elevation: float = 30.0
    zoom: float = 1.0


def load_scene(path: str | os.PathLike | None) -> tuple[pv.DataSet, str]:
    """The surface to explore and its kind (``"mesh"``, ``"dem"`` or ``"dicom"``).

    A folder is a DICOM series (bone surface of :func:`~sciviz_gbuf.recipes.medical.ct_surface`);
    a file with a suffix of :data:`DEM_SUFFIXES` a DEM (its height field in metres), a ``.bpt``
    file its Bezier patches; anything else a mesh file (see
    :func:`~sciviz_gbuf.readers.read_scene`); ``None`` the bundled machine nut.
    """
    if path is None:
        return load_nut(), "mesh"
    p = Path(path)
    if not p.exists():
        raise InputError(f"FILE: no such file or folder {str(p)!r}")
    data, kind = read_scene(p)
    if kind == "patches":  # a Bezier patch set is explored as its tessellated surface
        return data.to_mesh(), "mesh"
    if kind in ("dicom", "volume"):  # a CT volume is explored as its bone surface
        return ct_surface(data), "dicom"
    if kind == "dem":
        return _dem_surface(data), "dem"
    return data, "mesh"


def _dem_surface(dem: DEM) -> pv.DataSet:
    # A step keeps the height field near one vertex per output pixel: capture stays fast.
    step = max(1, int(max(dem.shape) // 1024))
    return dem.to_pyvista(step=step)


def encode_jpeg_data_url(rgb: np.ndarray, *, quality: int = 85) -> str:
    """A ``data:image/jpeg;base64,...`` URL of an 8-bit RGB image (Pillow; a few ms at 1024²)."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb)).save(buf, format="JPEG", quality=quality)
    return "data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


@dataclass
class Explorer:
    """A scene with a cached G-buffer and the current enhancement parameters.

    Parameters
    ----------
    scene : pyvista.DataSet
        The surface (see :func:`load_scene`).
    window_size : (width, height)
        Size of the G-buffer and the pictures.
    kind : str
        ``"mesh"``, ``"dem"`` or ``"dicom"``: sets the default camera (DEMs are seen from
        higher up).
    dem : DEM, optional
        The DEM grid itself (``kind="dem"``): enables the plan-view map (``view="map"``, then
        the default) on its grid, decimated to at most about 2048 cells a side.
    up : {"x", "y", "z"}, optional
        The world axis upright in the picture: the orbit camera turns around it (azimuth) and
        rises towards it (elevation), and heights (contours, bands) are measured along it.
        Default: the convention of the file the scene was read from
        (:func:`~sciviz_gbuf.core.framing.default_up`: y for OFF/OBJ/PLY/glTF, z otherwise).

    Attributes
    ----------
    gbuffer : GBuffer
        The cached capture at the current camera (captured when first needed: a DEM opened
        in its map view is not captured until the 3-D view is shown).
    params : Params
        The parameters of the last :meth:`render_image`.
    captures : int
        How many times the scene has been captured (1 after construction, 0 for a DEM in its
        map view).
    last_ms : float
        Milliseconds the last :meth:`render_image` took (filters and styles only).
    layer_runs : dict
        How many times each cached layer (``"emap"``, ``"map_relief"``, ...) was computed.
    map_range : (float, float)
        The DEM's height range (the map's band range), (0, 1) without a DEM.
    """

    scene: pv.DataSet
    window_size: tuple[int, int] = (1024, 768)
    kind: str = "mesh"
    params: Params | None = None
    dem: DEM | None = None
    up: str | None = None
    captures: int = 0
    last_ms: float = 0.0
    layer_runs: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        w, h = (int(v) for v in self.window_size)
        if w < 16 or h < 16:
            raise InputError(f"--size: expected at least 16x16 pixels, got {w}x{h}")
        at_most(max(w, h), "--size", "image_side")
        at_most(w * h, "--size (width x height)", "image_pixels")
        self.window_size = (w, h)
        if not isinstance(self.scene, pv.DataSet) or self.scene.n_points == 0:
            raise InputError("scene: expected a non-empty PyVista dataset")
        self.up = default_up(self.scene) if self.up is None else check_up(self.up)
        self._up = "xyz".index(self.up)
        # The points the orbit camera frames (a strided subset of a big scene: its projected
        # extent to well under a pixel at any view).
        pts = np.asarray(self.scene.points, dtype=np.float64)
        self._frame_points = pts[:: max(1, len(pts) // _FRAME_POINTS)]
        self.camera = _Camera(elevation=55.0 if self.kind == "dem" else 30.0)
        self._map_layers: dict[tuple, object] = {}
        self.map_range = (0.0, 1.0)
        if self.dem is not None:
            self._set_dem(self.dem)
        if self.params is None:
            self.params = self._default_params()
        self._gbuffer: GBuffer | None = None
        self._layers: dict[tuple, np.ndarray] = {}
        # The 3-D view's height range until a capture measures it (the contour slider's range).
        self.height_range = self.map_range
        if self.params.view != "map":
            self._capture()

    @property
    def gbuffer(self) -> GBuffer:
        """The cached capture at the current camera (captured now if there is none yet)."""
        if self._gbuffer is None:
            self._capture()
        return self._gbuffer

    def _set_dem(self, dem: DEM) -> None:
        if not isinstance(dem, DEM):
            raise InputError(f"dem: expected a sciviz_gbuf.readers.DEM, got {type(dem).__name__}")
        # A step keeps the map near 2048 cells a side at most (one cell per picture pixel).
        step = max(1, math.ceil(max(dem.shape) / 2048))
        if step > 1:
            x0, dx, rx, y0, ry, dy = dem.transform
            dem = dataclasses.replace(
                dem,
                heights=np.ascontiguousarray(dem.heights[::step, ::step]),
                mask=np.ascontiguousarray(dem.mask[::step, ::step]),
                transform=(x0, dx * step, rx * step, y0, ry * step, dy * step),
                pixel_size=(dem.pixel_size[0] * step, dem.pixel_size[1] * step),
            )
        # A DEM smaller than the window is mapped at the window's size, heights resampled
        # smoothly (as topographic_map(size=)), instead of a small picture the browser blows
        # up into stair-stepped lines.
        h, w = dem.shape
        fit = min(self.window_size[0] / w, self.window_size[1] / h)
        if fit > 1.0 and isinstance(dem.heights, np.ndarray):
            dem = map_grid(dem, size=(max(1, round(w * fit)), max(1, round(h * fit))))
        self.dem = dem
        self.kind = "dem"
        z = dem.heights
        lo, hi, q, major = contour_intervals(z, None, None)
        self.map_range = (lo, hi)
        self._map_auto = (q, max(1, round(major / q)) if major else 5, hi, lo)

    def _default_params(self) -> Params:
        """The starting parameters: for a DEM its map with round contour intervals and about
        one colour band per major interval."""
        if self.dem is None:
            return Params()
        q, every, hi, lo = self._map_auto
        majors = (hi - lo) / (q * every) if q > 0 else 0.0
        return Params(
            view="map", map_interval=q, major_every=every, map_bands=int(min(max(majors, 2), 16))
        )

    @classmethod
    def from_file(
        cls,
        path: str | os.PathLike | None,
        *,
        window_size: Sequence[int] = (1024, 768),
        up: str | None = None,
    ) -> Explorer:
        """An explorer of a mesh file, DEM or DICOM folder (see :func:`load_scene`); ``up``:
        the upright world axis, default by the file's convention (``--up``)."""
        up = None if up is None else check_up(up)  # before the (slow) read
        p = None if path is None else Path(path)
        if p is not None and p.is_file() and kind_of(p) == "dem":
            dem = read_dem(p)
            return cls(
                _dem_surface(dem), window_size=tuple(window_size), kind="dem", dem=dem, up=up
            )
        scene, kind = load_scene(path)
        if up is None and p is not None and p.is_file():
            up = default_up(p)  # the convention of the file's format, whatever read it
        return cls(scene, window_size=tuple(window_size), kind=kind, up=up)

    def camera_tuple(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """``(position, focal_point, view_up)`` of the orbit camera (30° view angle).

        The orbit is around the up axis ``u`` (:attr:`up`): with the right-handed frame
        ``(e1, e2, u)`` of the cyclically next axes (z up: x, y; y up: z, x; x up: y, z) the
        eye is in direction ``cos(el) (cos(az) e1 + sin(az) e2) + sin(el) u`` from the object,
        and ``u`` is upright in the picture (``e2`` when looking straight along it). At zoom 1
        the object's projected box is centred and fills 85 % of the limiting image side
        (:func:`~sciviz_gbuf.core.framing.framed_camera`); zoom ``k`` brings the eye ``k``
        times closer to the focal point.
        """
        az, el = math.radians(self.camera.azimuth), math.radians(self.camera.elevation)
        axes = np.eye(3)
        e1, e2, u = (axes[(self._up + k) % 3] for k in (1, 2, 0))
        d = math.cos(el) * (math.cos(az) * e1 + math.sin(az) * e2) + math.sin(el) * u
        view_up = u if abs(self.camera.elevation) < 89.0 else e2
        # At zoom 1 the object is framed by the one rule of every picture (its projected box
        # centred, filling 85 % of the limiting side), not its bounding sphere (which leaves
        # an elongated object small); zoom moves the eye towards the focal point.
        w, h = self.window_size
        pos, focal, up = framed_camera(
            (), d, view_up, view_angle=30.0, aspect=w / h, points=self._frame_points
        )
        focal_v = np.asarray(focal)
        eye = focal_v + (np.asarray(pos) - focal_v) / self.camera.zoom
        return tuple(eye.tolist()), tuple(focal), tuple(up)

    def _layer(self, key: tuple, make, cache: dict | None = None) -> np.ndarray:
        """A filter result of the cached G-buffer, computed once per parameter ``key``: a slider
        change re-runs only the filters that depend on it."""
        cache = self._layers if cache is None else cache
        if key not in cache:
            # Keep the last few results per layer only: sliders visit many values.
            same = [k for k in cache if k[0] == key[0]]
            for k in same[:-3]:
                del cache[k]
            cache[key] = make()
            self.layer_runs[key[0]] = self.layer_runs.get(key[0], 0) + 1
        return cache[key]

    def _layered_image(self, p: Params) -> np.ndarray:
        """:func:`style_image` with cached layers (the edge map per edge threshold, band tint,
        contour ink) and one fused pass for the rest: the shade of ``N.L`` per style and the
        composite to uint8 (within one grey level of it; tested). A light or style change
        re-runs only that pass."""
        gb = self.gbuffer
        if gb.supersample != 1 or gb.normal.dtype != np.float32:
            # not the explorer's own
            return style_image(gb, p, height_range=self.height_range, up=self.up)
        edges = {"crease_angle": p.crease_angle, "depth_jump": p.depth_jump, "width": p.width}
        ekey = tuple(edges.values())
        empty2, empty3 = np.zeros((0, 0), np.float32), np.zeros((0, 0, 0), np.float32)
        layer, emap = empty2, empty3
        if p.style in ("enhance", "gooch", "toon"):
            # One edge map for the three styles; its dark lines thinned where they clump, as
            # the style functions do: the profiles only (white inner edges), or with the inner
            # edges where the style draws them dark (toon). The thinning is cached apart, so a
            # style change never recomputes the edge map itself.
            raw = self._layer(("emap", *ekey), lambda: edge_map(gb, **edges))
            inner = FUSED_CONSTANTS["edge_colors"][p.style][0]
            dark = is_dark(inner)
            emap = self._layer(
                ("emap_thin", dark, *ekey),
                lambda: thin_edge_map(raw, p.width, inner_color=inner),
            )
        elif p.style == "fig7":
            emap = self._layer(("fig7", *ekey), lambda: fig7_edge_map(gb, **edges))
        elif p.style == "lines":
            layer = self._layer(("lines", *ekey), lambda: line_ink(gb, **edges))
        else:
            layer = self._layer(("hatch", p.width), lambda: profile_ink(gb, width=p.width))
        lo, hi = self.height_range
        tint = empty3
        if p.bands > 0:
            # The kernel applies the tint on the surface only: no white-paper copy here.
            tint = self._layer(
                ("bands", p.bands), lambda: _band_rgba(gb, p.bands, lo, hi, self._up)
            )
        ink = empty2
        if p.contour_interval > 0:
            ink = self._layer(
                ("contours", p.contour_interval, p.contour_width),
                lambda: contour_lines(
                    gb.world[..., self._up],
                    interval=p.contour_interval,
                    width=p.contour_width,
                    mask=gb.mask,
                ),
            )
        out = np.empty((*gb.output_shape, 3), dtype=np.uint8)
        fused_style(
            p.style,
            gb.normal,
            gb.mask,
            p.light(),
            layer=layer if layer.size else None,
            emap=emap if emap.size else None,
            tint=tint if tint.size else None,
            ink=ink if ink.size else None,
            ink_color=_CONTOUR_COLOR,
            out=out,
        )
        return out

    def _map_image(self, p: Params) -> np.ndarray:
        """The plan-view map of the DEM: :func:`~sciviz_gbuf.recipes.terrain.map_layers` split
        into three cached layers (contour ink, relief shade, band tables), each re-run only
        when one of its own parameters changes, then the fused composite on white paper."""
        if self.dem is None:
            raise InputError("view: 'map' needs a DEM (open a DEM file); this scene is a "
                             f"{self.kind}")  # fmt: skip
        d, kw = self.dem, p.map_kwargs(self.map_range)
        cache = self._map_layers
        common = {
            "dx": d.pixel_size[0],
            "dy": d.pixel_size[1],
            "interval": kw["interval"],
            "major_interval": kw["major_interval"],
            "width": kw["width"],
            "major_width": kw["major_width"],
            "dense_spacing": 4.0,
            "generalize": True,  # topographic_map's default: the explorer shows that map
            "cmap": None,
            "sea_level": None,
            "azimuth": kw["azimuth"],
            "altitude": kw["altitude"],
            "z_factor": kw["z_factor"],
            "variant": kw["variant"],
            "shadows": False,
            "sky_view": False,
        }
        off = {"contours": False, "bands": False, "relief": False}

        def part(**on) -> dict:
            return map_layers(d.heights, **{**common, **off, **on})

        layers: dict[str, object] = {"relief": True, "ink": None, "tables": None}
        if kw["contours"]:
            key = ("map_contours", kw["interval"], kw["major_interval"], kw["width"])
            layers["ink"] = self._layer(key, lambda: part(contours=True)["ink"], cache)
        if kw["bands"] is not False:
            b = kw["bands"]
            # the band islands filled are the rings the lines drop
            ring = map_min_ring(kw["width"], kw["major_width"], kw["major_interval"])
            key = ("map_bands", b if isinstance(b, str) else tuple(b), ring)
            bl = self._layer(key, lambda: part(bands=b), cache)
            layers["tables"] = bl["tables"]
            if bl.get("band_z") is not None:
                layers["band_z"] = bl["band_z"]
        key = ("map_relief", kw["azimuth"], kw["altitude"], kw["z_factor"], kw["variant"])
        rel = self._layer(key, lambda: part(relief=True), cache)
        layers["sh"], layers["flat"] = rel["sh"], rel["flat"]
        rgba = composite(layers, d.heights, np.asarray(CONTOUR_COLOR, np.float32))
        out = np.empty((*rgba.shape[:2], 3), dtype=np.uint8)
        rgba_on_paper(rgba, out)  # nodata (transparent in the map): white paper
        return out

    def _capture(self) -> None:
        # supersample=1: the per-update filters must stay near 50 ms at 1024².
        gb = capture(
            self.scene, window_size=self.window_size, camera=self.camera_tuple(), supersample=1
        )
        self._gbuffer = gb
        self.captures += 1
        self._layers = {}
        z = gb.world[..., self._up][gb.mask]
        self.height_range = (float(z.min()), float(z.max())) if z.size else (0.0, 1.0)

    def set_camera(
        self,
        azimuth: float | None = None,
        elevation: float | None = None,
        zoom: float | None = None,
    ) -> None:
        """Move the orbit camera (degrees around the up axis, degrees above the plane across
        it, zoom factor) and capture again."""
        new = replace(self.camera)
        # Bounded like every parameter the browser can set (CAMERA_BOUNDS): an extreme zoom
        # puts the camera at a distance no float32 depth buffer resolves.
        for name, value in (("azimuth", azimuth), ("elevation", elevation), ("zoom", zoom)):
            if value is not None:
                low, high, strict = CAMERA_BOUNDS[name]
                v = _bounded(value, name, low, high, strict=strict, integer=False)
                setattr(new, name, v)
        if new != self.camera:
            self.camera = new
            if self._gbuffer is not None:  # else the 3-D view captures when first shown
                self._capture()

    def update_params(self, values: Mapping[str, object]) -> Params:
        """The current parameters with ``values`` replaced (unknown names are an error)."""
        names = {f.name for f in fields(Params)}
        bad = sorted(set(values) - names)
        if bad:
            raise InputError(
                f"params: unknown parameter(s) {bad}; expected some of {sorted(names)}"
            )
        # The browser sends numbers as floats: a whole float is a valid band count.
        ints = ("bands", "major_every", "map_bands")
        conv = {
            k: int(v) if k in ints and isinstance(v, float) and v.is_integer() else v
            for k, v in values.items()
        }
        return replace(self.params, **conv).checked()

    def _check_levels(self, p: Params) -> None:
        """Refuse an interval that draws more than ``LIMITS["levels"]`` lines over the height
        range it is drawn on (the bound of the Python API's ``interval=``)."""
        if p.view == "map":
            name, q, (lo, hi) = "map_interval", p.map_interval, self.map_range
        else:
            name, q, (lo, hi) = "contour_interval", p.contour_interval, self.height_range
        if q > 0:
            n = (hi - lo) / q
            if not n <= LIMITS["levels"]:
                raise InputError(
                    f"{name}: expected an interval drawing at most {LIMITS['levels']:g} lines "
                    f"over the heights {lo:.6g}..{hi:.6g}, got {q!r} ({n:.3g} lines)"
                )

    def render_image(self, params: Params | Mapping[str, object] | None = None) -> np.ndarray:
        """The picture of the cached G-buffer with these parameters (no capture).

        Parameters
        ----------
        params : Params or mapping, optional
            All parameters, or the ones to change from the current ones.

        Returns
        -------
        (H, W, 3) uint8 RGB.
        """
        t0 = time.perf_counter()
        if params is None:
            p = self.params.checked()
        elif isinstance(params, Params):
            p = params.checked()
        else:
            p = self.update_params(params)
        self._check_levels(p)
        rgb = self._map_image(p) if p.view == "map" else self._layered_image(p)
        self.params = p
        self.last_ms = (time.perf_counter() - t0) * 1e3
        return rgb


def _style_rgb(gb: GBuffer, p: Params) -> np.ndarray:
    """The style of ``p`` alone, float32 RGB at the output size."""
    light = p.light()
    edges = {"crease_angle": p.crease_angle, "depth_jump": p.depth_jump, "width": p.width}
    if p.style in ("enhance", "lines", "fig7"):
        rgb = illustrate(gb, style=p.style, light=light, **edges)
    elif p.style == "gooch":
        rgb = gooch(gb, light=light, **edges)
    elif p.style == "toon":
        rgb = toon(gb, light=light, **edges)
    else:
        rgb = hatch(gb, light=light, profile_width=p.width)
    return np.asarray(rgb, dtype=np.float32)[..., :3]


def _band_rgba(gb: GBuffer, bands: int, lo: float, hi: float, axis: int = 2) -> np.ndarray:
    """Colour bands of the height (world coordinate ``axis``) at the buffer size (RGBA, only
    valid on the surface)."""
    step = max(hi - lo, 1e-12) / bands
    height = gb.world[..., axis]
    return color_bands(height, interval=step, base=lo, vmin=lo, vmax=hi, mask=gb.mask)


def _band_tint(gb: GBuffer, bands: int, lo: float, hi: float, axis: int = 2) -> np.ndarray:
    """Colour bands of the height as a multiplicative tint (white off the surface)."""
    tint = _band_rgba(gb, bands, lo, hi, axis)
    tint = np.where(gb.mask[..., None], tint[..., :3], np.float32(1.0))
    return gb.downsample(tint.astype(np.float32))


def _contour_ink(gb: GBuffer, interval: float, width: float, axis: int = 2) -> np.ndarray:
    """Contour-line ink of the height (world coordinate ``axis``), (H, W, 1) at the output
    size."""
    ink = contour_lines(gb.world[..., axis], interval=interval, width=width, mask=gb.mask)
    return gb.downsample(ink)[..., None]


def style_image(
    gb: GBuffer,
    p: Params,
    *,
    height_range: tuple[float, float] | None = None,
    up: str = "z",
) -> np.ndarray:
    """The picture of ``gb`` with parameters ``p``, straight from the package's functions: a
    style, then optional colour bands and contour lines of the height, the world coordinate
    along ``up`` (the reference that :meth:`Explorer.render_image` reproduces with cached
    layers).

    Returns
    -------
    (H, W, 3) uint8 RGB.
    """
    axis = "xyz".index(check_up(up))
    rgb = _style_rgb(gb, p)
    lo, hi = height_range if height_range is not None else (0.0, 1.0)
    if p.bands > 0:
        rgb = rgb * _band_tint(gb, p.bands, lo, hi, axis)
    if p.contour_interval > 0:
        ink = _contour_ink(gb, p.contour_interval, p.contour_width, axis)
        rgb = rgb * (1.0 - ink) + _CONTOUR_COLOR * ink
    return to_uint8(np.clip(rgb, 0.0, 1.0))
