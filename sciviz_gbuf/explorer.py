"""Interactive exploration of one scene: capture once, re-run only the filters per parameter.

:class:`Explorer` owns a surface (a mesh file, a DEM as a height field, or the bone surface of
a DICOM series), a cached :class:`~sciviz_gbuf.GBuffer` and the current parameters.
:meth:`Explorer.render_image` runs only the image-space filters and styles on the cached
buffer; only :meth:`Explorer.set_camera` captures again. The web front end (``sciviz-gbuf
explore``) lives in :mod:`sciviz_gbuf.cli_explore`.
"""

from __future__ import annotations

import base64
import io
import math
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np
import pyvista as pv

from .capture import capture
from .compose import to_uint8
from .errors import InputError
from .filters import (
    color_bands,
    contour_lines,
    crease_edges,
    edge_map,
    enhance,
    profile_edges,
)
from .gbuffer import GBuffer
from .recipes.illustration import fig7_edge_map, illustrate, shade_image
from .styles import gooch, hatch, toon

__all__ = [
    "DEM_SUFFIXES",
    "STYLES",
    "Explorer",
    "Params",
    "encode_jpeg_data_url",
    "load_scene",
    "style_image",
]

#: Style name -> one-line description (the first three are :func:`illustrate`'s).
STYLES = {
    "enhance": "shaded, white inner edges, black profiles (2003 edge map)",
    "lines": "black profile and crease lines on white paper",
    "fig7": "shaded, convex edges white, concave edges and profiles black (1990 Fig. 7)",
    "gooch": "warm-cool technical illustration with the 2003 edge map",
    "toon": "cartoon shading with black edges",
    "hatch": "pen-and-ink hatching",
}
#: File suffixes read as DEMs (everything else but a folder is read as a mesh).
DEM_SUFFIXES = (".tif", ".tiff", ".asc", ".hgt", ".dem", ".npy", ".npz")
_CONTOUR_COLOR = np.array([0.45, 0.22, 0.05], dtype=np.float32)


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
        Contour lines of the height (world z) every ``contour_interval`` data units (0: none),
        ``contour_width`` pixels wide.
    bands : int
        Number of colour bands over the visible height range (0: none).
    light_azimuth, light_elevation : float
        Eye-space light: azimuth in degrees counter-clockwise from the image's right, elevation
        in degrees towards the viewer.
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

    def light(self) -> tuple[float, float, float]:
        """The unit eye-space light direction (x right, y up, z to the viewer)."""
        az, el = math.radians(self.light_azimuth), math.radians(self.light_elevation)
        return (math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el))

    def checked(self) -> Params:
        """These parameters, or an :class:`InputError` naming the first bad one."""
        if self.style not in STYLES:
            raise InputError(f"style: expected one of {sorted(STYLES)}, got {self.style!r}")
        for name, low, strict in (
            ("crease_angle", 0.0, True),
            ("depth_jump", 0.0, True),
            ("width", 1.0, False),
            ("contour_interval", 0.0, False),
            ("contour_width", 0.0, True),
            ("light_azimuth", -math.inf, False),
            ("light_elevation", -90.0, False),
        ):
            v = getattr(self, name)
            ok = (
                isinstance(v, (int, float))
                and math.isfinite(v)
                and (v > low if strict else v >= low)
            )
            if not ok:
                op = ">" if strict else ">="
                raise InputError(f"{name}: expected a finite number {op} {low}, got {v!r}")
        if not -90.0 <= self.light_elevation <= 90.0:
            raise InputError(
                f"light_elevation: expected degrees in [-90, 90], got {self.light_elevation!r}"
            )
        if isinstance(self.bands, bool) or not (isinstance(self.bands, int) and self.bands >= 0):
            raise InputError(f"bands: expected an integer >= 0, got {self.bands!r}")
        return self


@dataclass
class _Camera:
    azimuth: float = 45.0
    elevation: float = 30.0
    zoom: float = 1.0


def load_scene(path: str | os.PathLike | None) -> tuple[pv.DataSet, str]:
    """The surface to explore and its kind (``"mesh"``, ``"dem"`` or ``"dicom"``).

    A folder is a DICOM series (bone surface of :func:`~sciviz_gbuf.recipes.medical.ct_surface`);
    a file with a suffix of :data:`DEM_SUFFIXES` a DEM (its height field in metres); anything
    else a mesh file; ``None`` the bundled machine nut.
    """
    if path is None:
        from .datasets import load_nut

        return load_nut(), "mesh"
    p = Path(path)
    if not p.exists():
        raise InputError(f"FILE: no such file or folder {str(p)!r}")
    if p.is_dir():
        from .readers import read_dicom_series
        from .recipes.medical import ct_surface

        return ct_surface(read_dicom_series(p)), "dicom"
    if p.suffix.lower() in DEM_SUFFIXES:
        from .readers import read_dem

        dem = read_dem(p)
        # A step keeps the height field near one vertex per output pixel: capture stays fast.
        step = max(1, int(max(dem.shape) // 1024))
        return dem.to_pyvista(step=step), "dem"
    from .readers import read_mesh

    return read_mesh(p), "mesh"


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

    Attributes
    ----------
    gbuffer : GBuffer
        The cached capture at the current camera.
    params : Params
        The parameters of the last :meth:`render_image`.
    captures : int
        How many times the scene has been captured (1 after construction).
    last_ms : float
        Milliseconds the last :meth:`render_image` took (filters and styles only).
    """

    scene: pv.DataSet
    window_size: tuple[int, int] = (1024, 768)
    kind: str = "mesh"
    params: Params = field(default_factory=Params)
    captures: int = 0
    last_ms: float = 0.0

    def __post_init__(self) -> None:
        w, h = (int(v) for v in self.window_size)
        if w < 16 or h < 16:
            raise InputError(f"--size: expected at least 16x16 pixels, got {w}x{h}")
        self.window_size = (w, h)
        if not isinstance(self.scene, pv.DataSet) or self.scene.n_points == 0:
            raise InputError("scene: expected a non-empty PyVista dataset")
        b = np.asarray(self.scene.bounds, dtype=np.float64).reshape(3, 2)
        self._centre = b.mean(axis=1)
        self._radius = max(float(np.linalg.norm(b[:, 1] - b[:, 0])) / 2.0, 1e-9)
        self.camera = _Camera(elevation=55.0 if self.kind == "dem" else 30.0)
        self._capture()

    @classmethod
    def from_file(
        cls, path: str | os.PathLike | None, *, window_size: Sequence[int] = (1024, 768)
    ) -> Explorer:
        """An explorer of a mesh file, DEM or DICOM folder (see :func:`load_scene`)."""
        scene, kind = load_scene(path)
        return cls(scene, window_size=tuple(window_size), kind=kind)

    def camera_tuple(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """``(position, focal_point, view_up)`` of the orbit camera (z up, 30° view angle)."""
        az, el = math.radians(self.camera.azimuth), math.radians(self.camera.elevation)
        d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        # The whole bounding sphere fits the 30° view angle at zoom 1.
        dist = self._radius / math.sin(math.radians(15.0)) / self.camera.zoom
        up = (0.0, 0.0, 1.0) if abs(self.camera.elevation) < 89.0 else (0.0, 1.0, 0.0)
        pos = self._centre + dist * d
        return tuple(pos.tolist()), tuple(self._centre.tolist()), up

    def _layer(self, key: tuple, make) -> np.ndarray:
        """A filter result of the cached G-buffer, computed once per parameter ``key``: a slider
        change re-runs only the filters that depend on it."""
        if key not in self._layers:
            # Keep the last few results per layer only: sliders visit many values.
            same = [k for k in self._layers if k[0] == key[0]]
            for k in same[:-3]:
                del self._layers[k]
            self._layers[key] = make()
        return self._layers[key]

    def _layered_image(self, p: Params) -> np.ndarray:
        """:func:`style_image` with cached layers and a float32 composite (within one grey
        level of it; tested)."""
        gb = self.gbuffer
        light = p.light()
        edges = {"crease_angle": p.crease_angle, "depth_jump": p.depth_jump, "width": p.width}
        ekey = tuple(edges.values())
        if p.style in ("enhance", "fig7"):
            shade = self._layer(("shade", light), lambda: shade_image(gb, light=light))
            if p.style == "enhance":
                emap = self._layer(("emap", *ekey), lambda: edge_map(gb, **edges))
            else:
                emap = self._layer(("fig7", *ekey), lambda: fig7_edge_map(gb, **edges))
            rgb = enhance(shade, emap)
        elif p.style == "lines":
            ink = self._layer(
                ("lines", *ekey),
                lambda: np.maximum(
                    profile_edges(gb, depth_jump=p.depth_jump, width=p.width),
                    crease_edges(gb, **edges),
                ),
            )
            rgb = np.repeat((1.0 - ink)[..., None], 3, axis=2)
        else:
            # The other styles fuse shade and edges inside; they run whole.
            rgb = _style_rgb(gb, p)
        lo, hi = self.height_range
        if p.bands > 0:
            tint = self._layer(("bands", p.bands), lambda: _band_tint(gb, p.bands, lo, hi))
            rgb = rgb * tint
        if p.contour_interval > 0:
            ink = self._layer(
                ("contours", p.contour_interval, p.contour_width),
                lambda: _contour_ink(gb, p.contour_interval, p.contour_width),
            )
            rgb = rgb * (1.0 - ink) + _CONTOUR_COLOR * ink
        return to_uint8(rgb)

    def _capture(self) -> None:
        # supersample=1: the per-update filters must stay near 50 ms at 1024².
        self.gbuffer = capture(
            self.scene, window_size=self.window_size, camera=self.camera_tuple(), supersample=1
        )
        self.captures += 1
        self._layers: dict[tuple, np.ndarray] = {}
        z = self.gbuffer.world[..., 2][self.gbuffer.mask]
        self.height_range = (float(z.min()), float(z.max())) if z.size else (0.0, 1.0)

    def set_camera(
        self,
        azimuth: float | None = None,
        elevation: float | None = None,
        zoom: float | None = None,
    ) -> None:
        """Move the orbit camera (degrees around z, degrees above the xy plane, zoom factor)
        and capture again."""
        new = replace(self.camera)
        if azimuth is not None:
            new.azimuth = float(azimuth)
        if elevation is not None:
            if not -90.0 <= float(elevation) <= 90.0:
                raise InputError(f"elevation: expected degrees in [-90, 90], got {elevation!r}")
            new.elevation = float(elevation)
        if zoom is not None:
            if not (math.isfinite(float(zoom)) and float(zoom) > 0):
                raise InputError(f"zoom: expected a number > 0, got {zoom!r}")
            new.zoom = float(zoom)
        if not all(math.isfinite(v) for v in (new.azimuth, new.elevation, new.zoom)):
            raise InputError(f"camera: expected finite numbers, got {new!r}")
        if new != self.camera:
            self.camera = new
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
        conv = {
            k: int(v) if k == "bands" and isinstance(v, float) and v.is_integer() else v
            for k, v in values.items()
        }
        return replace(self.params, **conv).checked()

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
        rgb = self._layered_image(p)
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


def _band_tint(gb: GBuffer, bands: int, lo: float, hi: float) -> np.ndarray:
    """Colour bands of world z as a multiplicative tint (white off the surface)."""
    z = gb.world[..., 2]
    step = max(hi - lo, 1e-12) / bands
    tint = color_bands(z, interval=step, base=lo, vmin=lo, vmax=hi, mask=gb.mask)
    tint = np.where(gb.mask[..., None], tint[..., :3], np.float32(1.0))
    return gb.downsample(tint.astype(np.float32))


def _contour_ink(gb: GBuffer, interval: float, width: float) -> np.ndarray:
    """Contour-line ink of world z, (H, W, 1) at the output size."""
    ink = contour_lines(gb.world[..., 2], interval=interval, width=width, mask=gb.mask)
    return gb.downsample(ink)[..., None]


def style_image(
    gb: GBuffer, p: Params, *, height_range: tuple[float, float] | None = None
) -> np.ndarray:
    """The picture of ``gb`` with parameters ``p``, straight from the package's functions: a
    style, then optional colour bands and contour lines of world z (the reference that
    :meth:`Explorer.render_image` reproduces with cached layers).

    Returns
    -------
    (H, W, 3) uint8 RGB.
    """
    rgb = _style_rgb(gb, p)
    lo, hi = height_range if height_range is not None else (0.0, 1.0)
    if p.bands > 0:
        rgb = rgb * _band_tint(gb, p.bands, lo, hi)
    if p.contour_interval > 0:
        ink = _contour_ink(gb, p.contour_interval, p.contour_width)
        rgb = rgb * (1.0 - ink) + _CONTOUR_COLOR * ink
    return to_uint8(np.clip(rgb, 0.0, 1.0))
