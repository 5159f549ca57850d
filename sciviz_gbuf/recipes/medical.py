"""Enhanced CT surfaces (Saito & Takahashi 1990 §4.4, Fig. 14).

A CT series is read (:func:`~sciviz_gbuf.readers.read_dicom_series`), cut at a bone or skin
threshold (:func:`~sciviz_gbuf.core.isosurface`) and rendered once into G-buffers from a
patient-anatomical view. The enhanced image (b) of Fig. 14 combines four image operations on
them: profiles (from ``sz``), shading (from the normals), contour lines of one world coordinate
(heights along the body axis: ``wz``) and colour bands of another (front to back: ``wy``); the
conventional shaded image (a) is shown beside it. Pass the G-buffer back in to try other
parameters without reading or rendering again.

Views are named in the DICOM patient frame (LPS: x to the patient's left, y to the back, z to
the head): ``anterior`` looks at the face, ``superior`` down onto the head, and names join with
``-`` for oblique views (``anterior-left``).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
import pyvista as pv
from matplotlib.colors import LinearSegmentedColormap

from .. import _validate
from ..core.capture import capture, check_capture_size
from ..core.framing import FILL, check_up, framed_camera
from ..core.gbuffer import GBuffer
from ..core.isosurface import isosurface
from ..errors import InputError
from ..filters import color_bands, contour_lines, lambert, profile_edges
from ..readers import kind_of, read_volume
from ..readers.dicom import read_dicom_series
from ..styles import LIGHT
from ._intervals import round_up
from ._map import rgba

__all__ = [
    "BONE",
    "SKIN",
    "SKIN_OPACITY",
    "TRANSLUCENT_LAYERS",
    "VIEWS",
    "ct_enhance",
    "ct_gbuffer",
    "ct_layers",
    "ct_panels",
    "ct_surface",
    "ct_translucent",
    "read_ct_volume",
    "view_camera",
]

#: Colours of the bands, near to far: light enough for lines and shading to read on them.
DEPTH_BANDS = LinearSegmentedColormap.from_list(
    "sciviz_depth_bands",
    [
        (0.97, 0.62, 0.50),
        (0.99, 0.84, 0.58),
        (0.96, 0.95, 0.78),
        (0.66, 0.85, 0.86),
        (0.55, 0.66, 0.88),
    ],
)
#: Dark sepia of the contour lines.
CT_CONTOUR_COLOR = (0.22, 0.11, 0.04)
#: Colour of bone in the conventional shaded image.
BONE = (0.93, 0.87, 0.76)
#: Colour and opacity of a translucent skin (:func:`ct_translucent`).
SKIN = (0.92, 0.56, 0.46)
SKIN_OPACITY = 0.35
#: Layers a translucent figure keeps: the skin's front, the bone's front and back, the
#: skin's back (and one more for folds).
TRANSLUCENT_LAYERS = 5
#: Anatomical views: direction from the patient towards the eye, and the view-up, in LPS.
VIEWS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "anterior": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "posterior": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    "left": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "right": ((-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "superior": ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
    "inferior": ((0.0, 0.0, -1.0), (0.0, -1.0, 0.0)),
}
_AXES = {"x": 0, "y": 1, "z": 2}
LAYOUTS = ("pair", "enhanced", "shaded")
#: The pictures of :func:`ct_panels`.
PANELS = ("shaded", "enhanced", "pr", "cn", "sh", "bands")


def view_camera(
    points: np.ndarray,
    view: str | Sequence[float] = "anterior",
    *,
    view_angle: float = 20.0,
    aspect: float = 1.0,
    margin: float = 1.0 - FILL,
    up: str | None = None,
):
    """A camera framing ``points`` from an anatomical view, by the one framing rule (their
    projected box centred, filling :data:`~sciviz_gbuf.core.framing.FILL` of the image).

    Parameters
    ----------
    points : (N, 3) array
        What must be in view (a surface's points), in patient coordinates (LPS, mm).
    view : str or 3 floats, default: "anterior"
        One of :data:`VIEWS`, several joined by ``-`` (``"anterior-left"``: halfway), or a
        direction from the object towards the eye (then the head, +z, is up unless the view is
        along z, when the face, -y, is).
    view_angle, aspect, margin
        As in :func:`~sciviz_gbuf.core.framing.framed_camera`.
    up : {"x", "y", "z"}, optional
        World axis upright in the picture, for views not along it; default the anatomical
        rule (DICOM is z-up: the head, +z, is up; looking along z, the face, -y).
    """
    up_axis = None if up is None else check_up(up)
    if isinstance(view, str):
        names = [v.strip().lower() for v in view.split("-")]
        bad = [n for n in names if n not in VIEWS]
        if bad or not names:
            raise InputError(
                f"view: expected one of {sorted(VIEWS)} (or several joined by '-', or a "
                f"3-vector), got {view!r}"
            )
        direction = np.sum([VIEWS[n][0] for n in names], axis=0)
        if not np.linalg.norm(direction) > 0:
            raise InputError(f"view: {view!r} names opposite directions")
        up = np.sum([VIEWS[n][1] for n in names], axis=0)
    else:
        try:
            direction = np.asarray(view, dtype=np.float64).reshape(3)
        except (TypeError, ValueError):
            raise InputError(f"view: expected a view name or a 3-vector, got {view!r}") from None
        if not (np.isfinite(direction).all() and np.linalg.norm(direction) > 0):
            raise InputError(f"view: expected a finite non-zero 3-vector, got {view!r}")
        up = np.array([0.0, 0.0, 1.0])
    d = direction / np.linalg.norm(direction)
    if up_axis is not None:
        wanted = np.eye(3)[_AXES[up_axis]]
        if np.linalg.norm(wanted - (wanted @ d) * d) > 1e-6:
            up = wanted
    up = up - (up @ d) * d
    if np.linalg.norm(up) < 1e-6:
        up = np.array([0.0, -1.0, 0.0]) - (-d[1]) * d
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return framed_camera((), d, up, view_angle=view_angle, aspect=aspect, margin=margin, points=pts)


def ct_surface(
    source: str | os.PathLike | Sequence[str | os.PathLike] | pv.DataSet,
    *,
    iso: str | float = "bone",
    scalars: str | None = None,
    smooth: int = 60,
    decimate: float = 0.0,
    largest: bool = False,
    refine: bool = True,
    series_uid: str | None = None,
    resample: bool = False,
    progress_bar: bool = False,
) -> pv.PolyData:
    """The isosurface of a DICOM folder / file list or of a volume; a surface passes through.

    ``series_uid`` and ``resample`` go to :func:`~sciviz_gbuf.readers.read_dicom_series`; the
    other options to :func:`~sciviz_gbuf.core.isosurface`. ``refine`` (default True) resamples
    thick slices by cubic convolution before the surface is cut, so a bone surface seen along
    the slices has no terrace (and no crease or speck of ink) at every slice; ``smooth`` is the
    windowed-sinc smoothing after it (0 with ``refine=False``: the raw marching-cubes surface).
    """
    if isinstance(source, pv.PolyData) and source.n_cells > 0 and source.n_lines == 0:
        return source
    if isinstance(source, pv.DataSet):
        volume = source
    elif isinstance(source, (str, os.PathLike, list, tuple)):
        volume = read_ct_volume(
            source, series_uid=series_uid, resample=resample, progress_bar=progress_bar
        )
    else:
        raise InputError(
            "source: expected a DICOM folder or file list, a volume file (NRRD, MetaImage, "
            f"NIfTI), a PyVista volume or a surface, got {type(source).__name__}"
        )
    return isosurface(
        volume,
        iso=iso,
        scalars=scalars,
        smooth=smooth,
        decimate=decimate,
        largest=largest,
        refine=refine,
        progress_bar=progress_bar,
    )


def read_ct_volume(
    source: str | os.PathLike | Sequence[str | os.PathLike],
    *,
    series_uid: str | None = None,
    resample: bool = False,
    progress_bar: bool = False,
) -> pv.DataSet:
    """The CT volume of ``source``: one volume file (``.nrrd``, ``.nhdr``, ``.mha``, ``.mhd``,
    ``.nii``, ``.nii.gz``: :func:`~sciviz_gbuf.readers.read_volume`), else a DICOM folder,
    file or file list (:func:`~sciviz_gbuf.readers.read_dicom_series`, which takes
    ``series_uid`` and ``resample``). Both give point array ``"HU"`` in LPS millimetres."""
    single = source if isinstance(source, (str, os.PathLike)) else None
    if isinstance(source, (list, tuple)) and len(source) == 1:
        single = source[0]
    if single is not None and kind_of(single) == "volume":
        return read_volume(single)
    return read_dicom_series(
        source, series_uid=series_uid, resample=resample, progress_bar=progress_bar
    )


def ct_gbuffer(
    source,
    *,
    iso: str | float = "bone",
    view: str | Sequence[float] = "anterior",
    camera=None,
    window_size: Sequence[int] = (1024, 1024),
    supersample: int = 2,
    view_angle: float = 20.0,
    progress_bar: bool = False,
    up: str | None = None,
    **surface_options,
) -> GBuffer:
    """Render the CT surface once from ``view`` and keep its G-buffers (1990 §4.4: wx, wy, wz,
    sz and the normals are what Fig. 14 needs).

    Parameters
    ----------
    source : DICOM folder, file list, volume or surface
        See :func:`ct_surface` (``**surface_options`` go there).
    iso : float or {"bone", "skin"}, default: "bone"
    view : str or 3 floats, default: "anterior"
        See :func:`view_camera`.
    camera : optional
        Anything :func:`~sciviz_gbuf.capture` accepts, instead of ``view``.
    window_size : (int, int), default: (1024, 1024)
    supersample : int, default: 2
        Render at this many times the size: antialiased lines and silhouettes.
    view_angle : float, default: 20
    progress_bar : bool, default: False
    up : {"x", "y", "z"}, optional
        World axis upright in the picture (see :func:`view_camera`); default the anatomical
        rule (head up).
    """
    # the capture's size is checked before the volume is read and its surface extracted
    w, h, _ = check_capture_size(window_size, supersample)
    surface = ct_surface(source, iso=iso, progress_bar=progress_bar, **surface_options)
    if camera is None:
        position, focal, view_up = view_camera(
            surface.points, view, view_angle=view_angle, aspect=w / max(h, 1), up=up
        )
        camera = pv.Camera()
        camera.position, camera.focal_point, camera.up = position, focal, view_up
        camera.view_angle = view_angle
    return capture(
        surface,
        window_size=(w, h),
        camera=camera,
        supersample=supersample,
        progress_bar=progress_bar,
    )


def ct_translucent(
    source,
    *,
    translucent: str | float | pv.PolyData = "skin",
    inner: str | float | pv.PolyData = "bone",
    opacity: float = SKIN_OPACITY,
    view: str | Sequence[float] = "anterior",
    camera=None,
    window_size: Sequence[int] = (1024, 1024),
    supersample: int = 2,
    view_angle: float = 20.0,
    layers: int = TRANSLUCENT_LAYERS,
    colors: tuple[Sequence[float], Sequence[float]] = (SKIN, BONE),
    profile_width: float = 1.5,
    background: Sequence[float] | None = None,
    progress_bar: bool = False,
    up: str | None = None,
    **surface_options,
) -> np.ndarray:
    """A translucent outer surface (the skin) with an inner one (the bone) seen through it:
    both surfaces shaded and outlined by their own profiles, the outer one with ``opacity``
    (:func:`~sciviz_gbuf.compose.layered` of a multi-layer G-buffer; the "extended"
    G-buffer 1990 §5.1 names as the way to transparency).

    Parameters
    ----------
    source : DICOM folder, file list, volume or None
        The CT (:func:`read_ct_volume`); None when both surfaces are given as meshes.
    translucent, inner : float, {"skin", "bone"} or pyvista.PolyData
        The two isosurfaces (thresholds in HU for the presets, or the value of a volume's
        scalars), or the surfaces themselves (e.g. two labels of a segmentation).
    opacity : float in [0, 1], default: 0.35
        Of the translucent surface; the inner one is opaque.
    view, camera, window_size, supersample, view_angle, up
        As :func:`ct_gbuffer`; the view is framed on the translucent surface.
    layers : int in [2, 8], default: 5
        Surfaces kept along each ray (``capture(layers=...)``).
    colors : (RGB, RGB), default: (:data:`SKIN`, :data:`BONE`)
    profile_width : float, default: 1.5
    background : RGB, optional
        Opaque background; default transparent.
    **surface_options
        :func:`ct_surface` options (``smooth``, ``refine``, ``largest``, ...).

    Returns
    -------
    (H, W, 4) uint8 RGBA.
    """
    from ..compose import layered
    from ..writers.png import to_uint8

    w, h, _ = check_capture_size(window_size, supersample)
    volume = None
    surfaces = []
    for name, spec in (("translucent", translucent), ("inner", inner)):
        if isinstance(spec, pv.PolyData):
            surfaces.append(spec)
            continue
        if volume is None:
            if source is None:
                raise InputError(f"{name}: a threshold needs a CT source (or give a surface)")
            volume = source if isinstance(source, pv.DataSet) else read_ct_volume(
                source, progress_bar=progress_bar)  # fmt: skip
        surfaces.append(ct_surface(volume, iso=spec, progress_bar=progress_bar, **surface_options))
    outer = surfaces[0]
    if camera is None:
        position, focal, view_up = view_camera(
            outer.points, view, view_angle=view_angle, aspect=w / max(h, 1), up=up
        )
        camera = pv.Camera()
        camera.position, camera.focal_point, camera.up = position, focal, view_up
        camera.view_angle = view_angle
    if _validate.count(layers, "layers", "layers") < 2:
        raise InputError(f"layers: expected at least 2 to see through a surface, got {layers!r}")
    gb = capture(surfaces, window_size=(w, h), camera=camera, supersample=supersample,
                 progress_bar=progress_bar, layers=layers)  # fmt: skip
    alpha = _validate.unit_interval(opacity, "opacity")
    if np.ndim(colors) != 2 or len(colors) != 2:
        raise InputError(f"colors: expected two RGB colours, got {_validate.brief(colors)}")
    rgba = layered(gb, opacity=(alpha, 1.0), colors=tuple(colors),
                   profile_width=profile_width, background=background)  # fmt: skip
    return to_uint8(rgba)


def _axis(axis: str | None, default: int, name: str) -> int:
    if axis is None:
        return default
    if axis not in _AXES:
        raise InputError(f"{name}: expected 'x', 'y' or 'z', got {axis!r}")
    return _AXES[axis]


def _interval(values: np.ndarray, count: float) -> float:
    """A round step (1, 2, 2.5, 5 x 10^k) giving about ``count`` steps over the values."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    return round_up(max(hi - lo, 1e-6) / count) if hi > lo else 1.0


def ct_layers(
    gb: GBuffer,
    *,
    contour_axis: str | None = None,
    contour_interval: float | None = None,
    contour_width: float = 1.0,
    band_axis: str | None = None,
    bands: int | float | Sequence[float] | None = 6,
    profile_width: float = 1.5,
    light: Sequence[float] = LIGHT,
) -> dict[str, np.ndarray]:
    """The image layers of Fig. 14 from a G-buffer, at its output size.

    Parameters
    ----------
    gb : GBuffer
        From :func:`ct_gbuffer` (or any capture).
    contour_axis : {"x", "y", "z"}, optional
        World coordinate whose contour lines are drawn; default ``"z"``, the body axis (and the
        slice axis of an axial CT): each line is where one axial level meets the surface.
    contour_interval : float, optional
        In world units (mm); default a round value giving about 24 lines over the surface.
    contour_width : float, default: 1
        Line width in output pixels; lines fade out where they crowd closer than three widths
        (surfaces seen edge-on), which the profiles and shading show instead. At most
        ``LIMITS["line_width"]`` = 64.
    band_axis : {"x", "y", "z"}, optional
        World coordinate coloured in bands, near warm to far cool; default the horizontal axis
        (x or y) closest to the line of sight (``wy`` for the anterior view), or for views along
        z the one most upright in the picture.
    bands : int, float, sequence of float or None, default: 6
        About this many bands (int), bands of this width (float), explicit band edges, or None
        for no bands (bone colour). A count or edges: at most ``LIMITS["bands"]`` = 4096.
    profile_width : float, default: 1.5
        Width of the profile lines in output pixels, in [1, 64] (``LIMITS["line_width"]``).
    light : 3 floats
        Eye-space direction towards the light.

    Returns
    -------
    dict
        ``sh`` shade (1 = lit), ``cn`` contour ink, ``pr`` profile ink, ``bands`` RGB
        (H, W, 3), ``shaded`` the conventional image (a) as RGB, ``alpha`` coverage; float32.
    """
    contour_width = _validate.size(contour_width, "contour_width", "line_width")
    _validate.size(profile_width, "profile_width", "line_width", low=1.0, closed=True)
    k = gb.supersample
    mask = gb.mask
    cam = gb.camera
    ci = _axis(contour_axis, 2, "contour_axis")
    # Bands default to the horizontal axis most along the line of sight (front to back in an
    # anterior view); looking along z, to the one most upright in the picture.
    sight = np.abs(np.asarray(cam.direction, dtype=np.float64))
    across = sight if max(sight[0], sight[1]) > sight[2] else np.abs(cam.view_up)
    bi = _axis(band_axis, int(np.argmax(across[:2])), "band_axis")
    field = np.where(mask, gb.world[..., ci], np.float32(np.nan))
    valid = mask & np.isfinite(field)
    if not valid.any():
        raise InputError("gb: the G-buffer covers no pixel")
    interval = _interval(field[valid], 24)
    if contour_interval is not None:
        if not (np.isfinite(contour_interval) and contour_interval > 0):
            raise InputError(
                f"contour_interval: expected a number > 0 (mm), got {contour_interval!r}"
            )
        interval = float(contour_interval)
    cn = contour_lines(
        field,
        interval=interval,
        width=contour_width * k,
        mask=valid,
        c_dense=0.0,
        dense_spacing=3.0 * contour_width * k,
    )
    n = gb.normal
    sh = lambert(n, light=light, mask=valid)
    # Near to far ramps warm to cool, whichever way the axis points.
    sign = np.float32(1.0 if np.asarray(cam.direction)[bi] >= 0 else -1.0)
    depthwise = np.where(valid, sign * gb.world[..., bi], np.float32(np.nan))
    if bands is None:
        rgb = np.broadcast_to(np.asarray(BONE, np.float32), (*field.shape, 3))
    else:
        rgb = color_bands(
            depthwise, cmap=DEPTH_BANDS, mask=valid, **_band_options(bands, depthwise)
        )
        rgb = rgb[..., :3]
    # The conventional image (a): bone colour, diffuse + Blinn-Phong highlight.
    lv = np.asarray(light, np.float64) / np.linalg.norm(light)
    half = lv + np.array([0.0, 0.0, 1.0])
    half /= max(np.linalg.norm(half), 1e-12)
    spec = np.maximum(n @ half.astype(np.float32), 0.0) ** np.float32(40.0)
    shaded = np.asarray(BONE, np.float32) * (0.15 + 0.85 * sh)[..., None]
    shaded = np.clip(shaded + (0.35 * spec)[..., None], 0.0, 1.0)
    nan_rgb = np.float32(np.nan)
    return {
        "sh": np.nan_to_num(gb.downsample(sh), nan=1.0),
        "cn": np.nan_to_num(gb.downsample(np.where(valid, cn, np.nan))),
        "pr": profile_edges(gb, width=profile_width),
        "bands": np.nan_to_num(gb.downsample(np.where(valid[..., None], rgb, nan_rgb)), nan=1.0),
        "shaded": np.nan_to_num(
            gb.downsample(np.where(valid[..., None], shaded, nan_rgb)), nan=1.0
        ),
        "alpha": gb.downsample(valid.astype(np.float32)),
    }


def _band_options(bands, values: np.ndarray) -> dict:
    if isinstance(bands, (bool, np.bool_)):
        raise InputError(f"bands: expected a count, a width, band edges or None, got {bands!r}")
    if isinstance(bands, (int, np.integer)):
        n = _validate.count(bands, "bands", "bands")
        return {"interval": _interval(values[np.isfinite(values)], n)}
    if isinstance(bands, (float, np.floating)):
        if not (np.isfinite(bands) and bands > 0):
            raise InputError(f"bands: expected a band width > 0, got {bands!r}")
        return {"interval": float(bands)}
    return {"levels": _validate.levels(bands, "bands", limit="bands")}


def ct_panels(
    source,
    *,
    contour_color: Sequence[float] = CT_CONTOUR_COLOR,
    background: Sequence[float] | None = None,
    layer_options: dict | None = None,
    keys: Sequence[str] | None = None,
    **gbuffer_options,
) -> dict[str, np.ndarray]:
    """Fig. 14's pictures as RGBA uint8: ``shaded`` (a), ``enhanced`` (b) and its parts ``pr``,
    ``cn``, ``sh`` and ``bands`` (each multiplied by the shade).

    ``source`` is a G-buffer (nothing is read or rendered) or anything :func:`ct_gbuffer`
    takes, with ``**gbuffer_options``; ``layer_options`` go to :func:`ct_layers`; ``keys``
    limits the pictures made (default all).
    """
    wanted = PANELS if keys is None else tuple(keys)
    if not set(wanted) <= set(PANELS):
        raise InputError(f"keys: expected some of {PANELS}, got {keys!r}")
    gb = source if isinstance(source, GBuffer) else ct_gbuffer(source, **gbuffer_options)
    lay = ct_layers(gb, **(layer_options or {}))
    colour = _validate.rgb(contour_color, "contour_color")
    sh = lay["sh"][..., None]
    cn, pr = lay["cn"][..., None], lay["pr"][..., None]
    lit_bands = lay["bands"] * (0.3 + 0.7 * sh)
    white = np.ones_like(lay["bands"])
    images = {
        "shaded": lambda: lay["shaded"],
        "enhanced": lambda: (lit_bands * (1.0 - cn) + colour * cn) * (1.0 - pr),
        "pr": lambda: white * (1.0 - pr),
        "cn": lambda: white * (1.0 - cn) + colour * cn,
        "sh": lambda: np.clip(0.15 + 0.85 * sh, 0.0, 1.0) * white,
        "bands": lambda: lit_bands,
    }
    return {key: rgba(images[key](), lay["alpha"], background) for key in wanted}


def ct_enhance(
    source,
    *,
    iso: str | float = "bone",
    view: str | Sequence[float] = "anterior",
    layout: str = "pair",
    window_size: Sequence[int] = (1024, 1024),
    supersample: int = 2,
    contour_axis: str | None = None,
    contour_interval: float | None = None,
    contour_width: float = 1.0,
    band_axis: str | None = None,
    bands: int | float | Sequence[float] | None = 6,
    profile_width: float = 1.5,
    contour_color: Sequence[float] = CT_CONTOUR_COLOR,
    background: Sequence[float] | None = None,
    series_uid: str | None = None,
    resample: bool = False,
    smooth: int = 60,
    refine: bool = True,
    progress_bar: bool = False,
    translucent: str | float | pv.PolyData | None = None,
    inner: str | float | pv.PolyData = "bone",
    opacity: float = SKIN_OPACITY,
) -> np.ndarray:
    """The enhanced CT image of Saito & Takahashi 1990 Fig. 14 (b), beside the conventional (a).

    Parameters
    ----------
    source : str, path, list of paths, pyvista.DataSet or GBuffer
        A DICOM series folder or file list (:func:`~sciviz_gbuf.readers.read_dicom_series`),
        a volume with point scalars (``"HU"``), a surface, or a G-buffer from
        :func:`ct_gbuffer` (then nothing is read or rendered and the view options are ignored).
    iso : float or {"bone", "skin"}, default: "bone"
        Threshold of the surface (HU for the presets).
    view : str or 3 floats, default: "anterior"
        Anatomical view in the patient frame (see :func:`view_camera`).
    layout : {"pair", "enhanced", "shaded"}, default: "pair"
        (a) and (b) side by side, or one of them.
    window_size : (int, int), default: (1024, 1024)
        Size of each picture.
    supersample : int, default: 2
    contour_axis, contour_interval, contour_width, band_axis, bands, profile_width
        See :func:`ct_layers`.
    contour_color : RGB, default: :data:`CT_CONTOUR_COLOR` (dark sepia)
    background : RGB, optional
        Opaque background; default transparent.
    series_uid, resample, smooth, refine
        Reading and surface options (:func:`ct_surface`): ``refine=False, smooth=0`` draws the
        raw marching-cubes surface, slice terraces and all.
    progress_bar : bool, default: False
    translucent, inner, opacity
        With ``translucent`` (e.g. ``"skin"``): the translucent-skin view instead,
        :func:`ct_translucent` of ``source`` (``inner`` seen through ``translucent`` at
        ``opacity``; one picture, ``layout`` and the Fig. 14 options do not apply).

    Returns
    -------
    (H, W, 4) uint8 RGBA; for ``"pair"`` W is twice the window width plus a gap of 1/32 of it.
    """
    if translucent is not None:
        if isinstance(source, GBuffer):
            raise InputError(
                "source: a translucent view captures its two surfaces itself: give the CT "
                "(or the surfaces), not a G-buffer"
            )
        return ct_translucent(
            source, translucent=translucent, inner=inner, opacity=opacity, view=view,
            window_size=window_size, supersample=supersample, profile_width=profile_width,
            background=background, progress_bar=progress_bar, smooth=smooth, refine=refine,
        )  # fmt: skip
    if layout not in LAYOUTS:
        raise InputError(f"layout: expected one of {LAYOUTS}, got {layout!r}")
    layer_options = {
        "contour_axis": contour_axis,
        "contour_interval": contour_interval,
        "contour_width": contour_width,
        "band_axis": band_axis,
        "bands": bands,
        "profile_width": profile_width,
    }
    gbuffer_options = (
        {}
        if isinstance(source, GBuffer)
        else {
            "iso": iso,
            "view": view,
            "window_size": window_size,
            "supersample": supersample,
            "series_uid": series_uid,
            "resample": resample,
            "smooth": smooth,
            "refine": refine,
            "progress_bar": progress_bar,
        }
    )
    panels = ct_panels(
        source,
        contour_color=contour_color,
        background=background,
        layer_options=layer_options,
        keys=("shaded", "enhanced") if layout == "pair" else (layout,),
        **gbuffer_options,
    )
    if layout != "pair":
        return panels[layout]
    a, b = panels["shaded"], panels["enhanced"]
    gap = np.zeros((a.shape[0], max(1, a.shape[1] // 32), 4), dtype=np.uint8)
    if background is not None:
        gap[..., :3] = np.rint(_validate.rgb(background, "background") * 255.0)
        gap[..., 3] = 255
    return np.concatenate([a, gap, b], axis=1)
