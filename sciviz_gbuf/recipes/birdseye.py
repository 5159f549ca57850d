"""Bird's-eye maps and the sumi-e of a DEM (Saito & Takahashi 1990 §4.3, Figs. 12 and 13).

The terrain surface is rendered once with :func:`~sciviz_gbuf.capture` (G-buffers ``sz``,
normals, world x/y/z and the true height ``elevation``); every picture after that is image
processing on the kept G-buffer: contour lines of the height (``cn``, constant width in pixels
however far the ground), relief from the normals (``sh``), profile lines from ``sz`` (``pr``,
ridges against what lies behind them) and colour bands, combined as ``mx2`` (pr + sh) and
``mx4`` (pr + cn + sh + bands). Pass the G-buffer back in to try other parameters without
rendering again.

With ``labels=True`` the index contours carry their heights, placed as on a plan-view map
(:mod:`.labels`) but on the picture's own height image, ``wz``: the text follows the line as
drawn in perspective, its top towards higher ground as seen (the image-space gradient of
``wz``), and the contour ink is knocked out under it.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from .. import _validate
from .._progress import progress
from ..core.capture import capture, check_capture_size
from ..core.framing import terrain_birdseye_camera
from ..core.gbuffer import GBuffer
from ..errors import InputError
from ..filters import band_heights, color_bands, contour_lines, lambert, profile_edges
from ..readers import DEM
from ._intervals import contour_intervals
from ._map import (
    CONTOUR_COLOR,
    as_dem,
    check_bands,
    check_line_sizes,
    check_z_factor,
    lit,
    map_min_ring,
    relief_light,
    relief_z_factor,
    rgba,
)
from ._resample import view_size
from .labels import ContourLabel, draw_labels, label_boxes, label_options, place_labels

__all__ = [
    "PAPER",
    "birdseye_gbuffer",
    "birdseye_label_heights",
    "birdseye_layers",
    "birdseye_map",
    "birdseye_panels",
    "exaggerated_normals",
    "rendered_ground_slope",
    "sumi_e",
]

#: Warm rice-paper white of the sumi-e.
PAPER = (0.96, 0.94, 0.88)
# mx4: share of white mixed into the lit colour bands, the contour colour's brightness ...
_MX4_WASH = 0.4
_MX4_LINE_SHADE = 0.5
# ... and the contours' opacity there: the profiles stay the strongest lines.
_MX4_LINE_INK = 0.75
# A surface of at most about this many points is rendered (every step-th DEM cell): finer than
# the pixels of any usual window, and VTK renders it in well under a second.
_MAX_POINTS = 2_000_000


def _sun(azimuth: float, altitude: float) -> tuple[float, float, float]:
    """Unit vector towards the sun, x east, y north, z up (GDAL's azimuth and altitude)."""
    az, alt = np.radians(azimuth), np.radians(altitude)
    return (np.sin(az) * np.cos(alt), np.cos(az) * np.cos(alt), np.sin(alt))


def birdseye_gbuffer(
    dem: DEM | str | os.PathLike | np.ndarray,
    *,
    view_azimuth: float = 135.0,
    elevation_angle: float = 35.0,
    view_angle: float = 30.0,
    window_size: Sequence[int] | None = None,
    vert_exag: float = 1.0,
    supersample: int = 2,
    step: int | None = None,
    size: int | Sequence[int] | None = None,
    scale: float | None = None,
    progress_bar: bool = False,
) -> GBuffer:
    """Render a DEM's surface from above at an angle and keep its G-buffers.

    Parameters
    ----------
    dem : DEM, path, array or xarray.DataArray
        Anything :func:`~sciviz_gbuf.readers.read_dem` reads.
    view_azimuth : float, default: 135
        Compass direction of the eye seen from the terrain's centre (degrees clockwise from
        north; 135: looking north-west from the south-east).
    elevation_angle : float, default: 35
        Angle of the line of sight above the horizon, in (0, 90) degrees.
    view_angle : float, default: 30
        Vertical view angle of the perspective camera.
    window_size : (int, int), optional
        Default (1024, 768). Each side at most ``LIMITS["image_side"]`` = 16384 (see
        :func:`~sciviz_gbuf.capture`).
    vert_exag : float, default: 1
        Vertical exaggeration of the surface (matplotlib's ``vert_exag``).
    supersample : int, default: 2
        Render at this many times the size (antialiasing of every layer); at most
        ``LIMITS["supersample"]`` = 8.
    step : int, optional
        Render every ``step``-th cell; default the smallest step giving at most about two
        million points.
    size : int or (int, int), optional
        Instead of ``window_size``: ``N`` the long side (the aspect of ``window_size``'s default,
        4:3), ``(W, H)``, or ``(W, 0)``/``(0, H)`` keeping that aspect.
    scale : float, optional
        Instead of ``window_size``/``size``: about this many pixels per DEM cell across the
        terrain, i.e. a long side of ``scale`` times the DEM's long side in cells (4:3). A
        perspective view has no map scale: ``"1:N"`` and ``dpi`` are for plan-view maps.
    progress_bar : bool, default: False

    Returns
    -------
    GBuffer
        With scalar ``"elevation"`` (the true heights, not exaggerated).
    """
    # the capture's size is checked before the DEM is read (with scale=, once more after)
    w, h, _ = check_capture_size(view_size(window_size, size, scale), supersample)
    vert_exag = _validate.positive(vert_exag, "vert_exag")
    if step is not None and not (
        isinstance(step, (int, np.integer)) and not isinstance(step, bool) and step >= 1
    ):
        raise InputError(f"step: expected an integer >= 1, got {_validate.brief(step)}")
    d = as_dem(dem)
    if scale is not None:
        w, h, _ = check_capture_size(view_size(None, None, scale, d.shape), supersample)
    if not d.mask.any():
        raise InputError(f"{d.source or 'DEM'}: no valid heights to render")
    if step is None:
        step = max(1, int(np.ceil(np.sqrt(d.heights.size / _MAX_POINTS))))
    surface = d.to_pyvista(z_factor=vert_exag, step=step)
    # Frame the valid ground only: hidden nodata points keep their place in the grid.
    pts = np.asarray(surface.points)[np.isfinite(surface.point_data["elevation"])]
    bounds = np.column_stack([pts.min(axis=0), pts.max(axis=0)]).ravel()
    camera = terrain_birdseye_camera(
        tuple(float(v) for v in bounds),
        azimuth=view_azimuth,
        elevation=elevation_angle,
        view_angle=view_angle,
        aspect=w / max(h, 1),
        points=pts,
    )
    return capture(
        surface,
        window_size=(w, h),
        camera=camera,
        scalars=["elevation"],
        supersample=supersample,
        progress_bar=progress_bar,
    )


def _gbuffer_of(dem_or_gbuffer, **capture_opts) -> GBuffer:
    if isinstance(dem_or_gbuffer, GBuffer):
        for key in ("size", "scale"):
            if capture_opts.get(key) is not None:
                h, w = dem_or_gbuffer.mask.shape[:2]
                raise InputError(
                    f"{key}: the G-buffer is already rendered ({w}x{h} buffer pixels): render "
                    "another with birdseye_gbuffer(size=/scale=)"
                )
        if "elevation" not in dem_or_gbuffer.scalars:
            raise InputError(
                "gbuffer: expected a G-buffer with the 'elevation' scalar (birdseye_gbuffer)"
            )
        return dem_or_gbuffer
    return birdseye_gbuffer(dem_or_gbuffer, **capture_opts)


def rendered_ground_slope(normal: np.ndarray, valid: np.ndarray) -> float:
    """Median slope (rise over run) of the rendered terrain from its world normals (z up):
    ``hypot(nx, ny) / |nz|`` over the valid pixels that are not flat (as
    :func:`~._intervals.median_ground_slope` of a DEM); NaN without such a pixel."""
    n = normal[valid].astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.hypot(n[:, 0], n[:, 1]) / np.abs(n[:, 2])
    t = t[np.isfinite(t) & (t > 1e-6)]
    return float(np.median(t)) if t.size else float("nan")


def exaggerated_normals(normal: np.ndarray, z_factor: float) -> np.ndarray:
    """Unit normals of the surface whose heights are ``z_factor`` times those of the surface
    with unit ``normal`` (z up): a surface ``z = f`` has normals along ``(-f_x, -f_y, 1)``,
    ``k f`` along ``(-k f_x, -k f_y, 1)``, i.e. ``(k n_x, k n_y, n_z)``."""
    n = normal.astype(np.float32, copy=True)
    n[..., :2] *= np.float32(z_factor)
    with np.errstate(invalid="ignore", divide="ignore"):
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return n


def birdseye_layers(
    gb: GBuffer,
    *,
    interval: float | None = None,
    major_interval: float | None = None,
    contours: bool = True,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    profile_width: float = 1.5,
    generalize: bool = True,
    bands: bool | str | float | Sequence[float] = True,
    cmap: str | object | None = None,
    sea_level: float | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float | None = None,
    labels: bool = False,
    label_size: float | None = None,
    label_spacing: float | None = None,
) -> dict[str, Any]:
    """The enhanced images of a bird's-eye G-buffer, at its output size (1990 Fig. 12).

    ``z_factor``: exaggeration of the relief shade ``sh`` (not of the geometry, which is
    ``vert_exag`` of the capture), as in :func:`~sciviz_gbuf.recipes.terrain.topographic_map`:
    the normals are lit as those of the surface with its heights times ``z_factor``. Default
    automatic, the maps' rule on the rendered surface: ``clip(tan(10 deg) / m, 1, 20)`` for
    ``m`` the median slope of the rendered ground (from the captured normals, flat pixels
    left out), so the relief of a plain is not washed out and hilly ground keeps 1.

    Returns
    -------
    dict
        ``cn`` contour ink, ``pr`` profile ink, ``sh`` relief shade (1 = lit by the sun at
        ``azimuth``/``altitude``), ``bands`` RGB colour bands (float32 (H, W, 3)), ``alpha``
        coverage, ``wz`` true height (NaN on the background), ``depth`` the eye distance
        normalised to [0, 1] over the terrain (near 0), all float32. Line sizes in output
        pixels: ``width``, ``major_width``, ``profile_width`` at most ``LIMITS["line_width"]``
        = 64, ``dense_spacing`` at most ``LIMITS["spacing"]`` = 1024. ``generalize``: the
        cartographic generalisation of the ``cn`` contours (as in
        :func:`~sciviz_gbuf.recipes.terrain.topographic_map`; rings up to 3 widths of the
        widest line dropped), False for the exact lines.

        With ``labels=True`` also ``labels``, a list of
        :class:`~sciviz_gbuf.recipes.labels.ContourLabel` (``x``, ``y``, ``angle`` in output
        pixels of the picture; its ``map_*`` fields are not georeferenced in a perspective
        view), and ``cn`` is knocked out under their boxes (``pr`` is not: labels keep clear
        of the profile lines). The labelled levels are the multiples of the major interval the
        contours use (of ``interval`` with one family of lines), placed by
        :func:`~sciviz_gbuf.recipes.labels.place_labels` on :func:`birdseye_label_heights`;
        ``label_size``/``label_spacing`` as in
        :func:`~sciviz_gbuf.recipes.terrain.topographic_map`. Without ``contours`` nothing
        is labelled.
    """
    labels = _validate.boolean(labels, "labels")
    font_px, spacing_px = label_options(label_size, label_spacing)
    check_line_sizes(
        width=width,
        major_width=major_width,
        dense_spacing=dense_spacing,
        profile_width=profile_width,
    )
    k = gb.supersample
    mask = gb.mask
    elev = np.where(mask, gb.scalars["elevation"], np.float32(np.nan))
    valid = np.isfinite(elev)
    lo, hi, interval, major_interval = contour_intervals(
        elev, interval, major_interval, pixels_per_sample=1.0 / k
    )
    cn = np.zeros_like(elev)
    if contours:
        cn = contour_lines(
            elev,
            interval=interval,
            major_interval=major_interval,
            width=width * k,
            major_width=major_width * k,
            dense_spacing=dense_spacing * k,
            generalize=generalize,
        )
    normal = gb.world_normal()
    zf = relief_z_factor(check_z_factor(z_factor), rendered_ground_slope(normal, valid))
    if zf != 1.0:
        normal = exaggerated_normals(normal, zf)
    sh = lambert(normal, light=_sun(azimuth, altitude), mask=valid)
    opts = check_bands(bands, major_interval if major_interval is not None else 5 * interval)
    if opts is None:
        rgb = np.ones((*elev.shape, 3), dtype=np.float32)
    else:
        band_z = elev
        if generalize and opts:
            # no island of band colour where the generalised lines dropped a ring
            band_z = band_heights(
                elev, band_interval=opts.get("interval"), band_levels=opts.get("levels"),
                min_ring=map_min_ring(width, major_width, major_interval) * k,
            )  # fmt: skip
        rgb = color_bands(
            band_z,
            cmap=cmap,
            sea_level=sea_level,
            vmin=lo if vmin is None else vmin,
            vmax=hi if vmax is None else vmax,
            **opts,
        )[..., :3]
    depth = np.where(valid, gb.depth, np.nan)
    if valid.any():
        dlo, dhi = float(np.nanmin(depth)), float(np.nanmax(depth))
        depth = (depth - dlo) / max(dhi - dlo, 1e-12)
    rgb = np.where(valid[..., None], rgb, np.nan)
    out: dict[str, Any] = {
        "cn": np.nan_to_num(gb.downsample(np.where(valid, cn, np.nan))),
        "pr": profile_edges(gb, width=profile_width),
        "sh": np.nan_to_num(gb.downsample(sh), nan=1.0),
        "bands": np.nan_to_num(gb.downsample(rgb), nan=1.0),
        "alpha": gb.downsample(valid.astype(np.float32)),
        "wz": gb.downsample(elev),
        "depth": gb.downsample(depth.astype(np.float32)),
    }
    if labels:
        placed: list[ContourLabel] = []
        if contours:
            # the index contours drawn: the multiples of the major interval (of the interval
            # when there is one family of lines), as the plan-view map labels them
            step = float(major_interval if major_interval is not None else interval)
            placed = place_labels(
                birdseye_label_heights(out), step=step, band=step, font_px=font_px,
                spacing_px=spacing_px,
            )  # fmt: skip
            # the line is broken under the number (the contour ink only: no box meets a
            # profile line, see birdseye_label_heights)
            out["cn"] = out["cn"] * (1.0 - label_boxes(placed, out["cn"].shape))
        out["labels"] = placed
    return out


def birdseye_label_heights(layers: dict[str, Any]) -> np.ndarray:
    """The image-space height raster the labels of a bird's-eye picture are placed on: ``wz``
    of :func:`birdseye_layers` (float64), NaN where the pixel is not wholly terrain (the sky,
    nodata, the antialiased outline) and under the profile lines ``pr``.

    On a profile line the ground seen jumps from a ridge to the ground behind it: the
    heights there are neither surface's (an output pixel averages both), and a contour traced
    through the jump would follow the ridge, not a line of the picture. Masked, the jumps
    break the traced lines, and no label box (which must lie over heights) reaches across a
    ridge or the outline.
    """
    wz = np.asarray(layers["wz"], dtype=np.float64)
    whole = (layers["alpha"] >= 1.0) & (layers["pr"] <= 0.0)
    return np.where(whole, wz, np.nan)


def birdseye_panels(
    dem_or_gbuffer: DEM | GBuffer | str | os.PathLike | np.ndarray,
    *,
    contour_color: Sequence[float] = CONTOUR_COLOR,
    background: Sequence[float] | None = None,
    label_color: Sequence[float] | None = None,
    capture_options: dict | None = None,
    **layer_options,
) -> dict[str, np.ndarray]:
    """The four pictures of the 1990 Fig. 12 as RGBA uint8: ``cn``, ``pr``, ``mx2``, ``mx4``,
    plus ``sh`` (see :func:`birdseye_map` for the parameters). With ``labels=True`` the
    pictures with contour lines, ``cn`` and ``mx4``, carry the labels."""
    colour = _validate.rgb(contour_color, "contour_color")
    text_colour = None if label_color is None else _validate.rgb(label_color, "label_color")
    # the label options are checked before anything is rendered
    _validate.boolean(layer_options.get("labels", False), "labels")
    font_px, _ = label_options(layer_options.get("label_size"), layer_options.get("label_spacing"))
    gb = _gbuffer_of(dem_or_gbuffer, **(capture_options or {}))
    lay = birdseye_layers(gb, **layer_options)
    alt = float(layer_options.get("altitude", 45.0))
    flat = np.float32(max(np.sin(np.radians(alt)), 1e-3))
    coloured = lit(lay["bands"], relief_light(lay["sh"] / flat))
    white = np.ones_like(lay["bands"])
    # mx4 carries four layers: the bands and relief are washed towards white and the contours
    # drawn darker (and a little translucent), so the lines read on dark brown slopes too
    washed = coloured + np.float32(_MX4_WASH) * (white - coloured)
    dark = colour * np.float32(_MX4_LINE_SHADE)
    cn, pr = lay["cn"][..., None], lay["pr"][..., None]
    cn4 = cn * np.float32(_MX4_LINE_INK)
    grey = np.clip(0.2 + 0.8 * lay["sh"], 0.0, 1.0)[..., None] * white
    images = {
        "cn": white * (1.0 - cn) + colour * cn,
        "pr": white * (1.0 - pr),
        "sh": grey,
        "mx2": grey * (1.0 - pr),
        "mx4": (washed * (1.0 - cn4) + dark * cn4) * (1.0 - pr),
    }
    out = {key: rgba(img, lay["alpha"], background) for key, img in images.items()}
    placed = lay.get("labels")
    if placed:
        # the text in the colour of the lines as drawn (darker in mx4), unless told
        for key, ink in (("cn", colour), ("mx4", dark)):
            out[key] = draw_labels(out[key], placed, font_px, ink if text_colour is None
                                   else text_colour)  # fmt: skip
    return out


def birdseye_map(
    dem: DEM | GBuffer | str | os.PathLike | np.ndarray,
    *,
    view_azimuth: float = 135.0,
    elevation_angle: float = 35.0,
    window_size: Sequence[int] | None = None,
    vert_exag: float = 1.0,
    supersample: int = 2,
    size: int | Sequence[int] | None = None,
    scale: float | None = None,
    interval: float | None = None,
    major_interval: float | None = None,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    profile_width: float = 1.5,
    contour_color: Sequence[float] = CONTOUR_COLOR,
    bands: bool | str | float | Sequence[float] = True,
    cmap: str | object | None = None,
    sea_level: float | None = None,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float | None = None,
    labels: bool = False,
    label_size: float | None = None,
    label_spacing: float | None = None,
    label_color: Sequence[float] | None = None,
    background: Sequence[float] | None = None,
    progress_bar: bool = False,
) -> np.ndarray:
    """A bird's-eye map (1990 Fig. 12 ``mx4``): profiles, contour lines, relief and colour bands
    of a rendered DEM surface.

    Parameters
    ----------
    dem : DEM, GBuffer, path, array or xarray.DataArray
        A DEM to render (see :func:`birdseye_gbuffer`), or a G-buffer it made: then nothing
        is rendered and the view options are ignored.
    view_azimuth, elevation_angle, window_size, vert_exag, supersample
        The view, as in :func:`birdseye_gbuffer`.
    size, scale
        The output size instead of ``window_size``, as in :func:`birdseye_gbuffer`: ``N`` (the
        long side), ``(W, H)``, or about ``scale`` pixels per DEM cell. Refused with a
        G-buffer (already rendered).
    interval, major_interval, width, major_width, dense_spacing, contour_color
        Contour lines of the true height, as in
        :func:`~sciviz_gbuf.recipes.terrain.topographic_map`; widths in output pixels.
    profile_width : float, default: 1.5
        Width of the profile lines (ridges seen against the ground behind them, and the
        outline).
    bands, cmap, sea_level
        Colour bands, as in :func:`~sciviz_gbuf.recipes.terrain.topographic_map`.
    azimuth, altitude : float, default: 315, 45
        The sun of the relief (GDAL's convention), lighting the surface's normals.
    z_factor : float, optional
        Exaggeration of the relief shade only (the geometry's is ``vert_exag``). Default
        automatic, as in :func:`~sciviz_gbuf.recipes.terrain.topographic_map`:
        ``clip(tan(10 deg) / m, 1, 20)`` for ``m`` the median slope of the rendered ground
        (:func:`birdseye_layers`); a number is used as it is.
    labels : bool, default: False
        Write the heights of the index (major) contours into the lines, as
        :func:`~sciviz_gbuf.recipes.terrain.topographic_map` ``labels=True`` does on a plan
        view, but in the picture: the text follows the line as seen, its top towards higher
        ground as seen (the image-space gradient of the rendered height), the contour ink is
        knocked out under it; labels keep ``label_spacing`` apart along a line and clear of
        each other, of the outline, of the profile lines and of the other index contours.
        :func:`birdseye_layers` ``labels=True`` gives the placements.
    label_size, label_spacing : float, optional
        Font height in output pixels (default 11 px, at most ``LIMITS["font_size"]`` = 512)
        and the least distance between labels along a line (default 25 font sizes).
    label_color : RGB, optional
        Colour of the label text (default that of the lines as drawn: ``contour_color``
        darkened as in ``mx4``).
    background : RGB, optional
        Opaque background colour; default transparent.
    progress_bar : bool, default: False

    Returns
    -------
    (H, W, 4) uint8 RGBA
        At ``window_size`` (or ``size``/``scale``); transparent where no valid terrain was
        rendered (the sky, nodata holes), antialiased at the outline.
    """
    # the label options are checked before anything is rendered
    labels = _validate.boolean(labels, "labels")
    label_options(label_size, label_spacing)
    if label_color is not None:
        _validate.rgb(label_color, "label_color")
    with progress(progress_bar, 3, "bird's-eye map") as bar:
        gb = _gbuffer_of(
            dem,
            view_azimuth=view_azimuth,
            elevation_angle=elevation_angle,
            window_size=window_size,
            vert_exag=vert_exag,
            supersample=supersample,
            size=size,
            scale=scale,
        )
        bar.step("enhance")
        panels = birdseye_panels(
            gb,
            contour_color=contour_color,
            background=background,
            interval=interval,
            major_interval=major_interval,
            width=width,
            major_width=major_width,
            dense_spacing=dense_spacing,
            profile_width=profile_width,
            bands=bands,
            cmap=cmap,
            sea_level=sea_level,
            azimuth=azimuth,
            altitude=altitude,
            z_factor=z_factor,
            labels=labels,
            label_size=label_size,
            label_spacing=label_spacing,
            label_color=label_color,
        )
        bar.step("done")
    return panels["mx4"]


def sumi_e(
    dem: DEM | GBuffer | str | os.PathLike | np.ndarray,
    *,
    view_azimuth: float = 135.0,
    elevation_angle: float = 20.0,
    window_size: Sequence[int] | None = None,
    vert_exag: float = 1.5,
    supersample: int = 2,
    size: int | Sequence[int] | None = None,
    scale: float | None = None,
    interval: float | None = None,
    profile_width: float = 2.0,
    wash: float = 12.0,
    mist: float = 0.4,
    paper: Sequence[float] | None = PAPER,
    progress_bar: bool = False,
) -> np.ndarray:
    """A sumi-e (Indian-ink painting) of a DEM from its contour lines and ``sz`` (1990 Fig. 13).

    Ink for the profiles (ridge lines from ``sz``), thin strokes along the contour lines, and a
    wash that is darkest just below each ridge line and fades downhill over ``wash`` pixels.
    All ink fades with distance (aerial perspective) and towards the valleys (``mist``).

    Parameters
    ----------
    dem : DEM, GBuffer, path, array or xarray.DataArray
        As in :func:`birdseye_map` (a low ``elevation_angle`` suits the style).
    size, scale
        The output size instead of ``window_size``, as in :func:`birdseye_map`.
    interval : float, optional
        Contour interval of the strokes; default a fifth of the automatic major interval.
    profile_width : float, default: 2
        Width of the ridge lines in output pixels.
    wash : float, default: 12
        Pixels over which the wash below a ridge line fades (0: no wash).
    mist : float in [0, 1], default: 0.4
        How much the ink fades in the lowest ground (0: none).
    paper : RGB or None, default: :data:`PAPER`
        Paper colour; it fills the sky opaquely. None: a transparent sky.

    Returns
    -------
    (H, W, 4) uint8 RGBA
    """
    if not (np.isfinite(wash) and wash >= 0):
        raise InputError(f"wash: expected a number of pixels >= 0, got {wash!r}")
    if not 0.0 <= float(mist) <= 1.0:
        raise InputError(f"mist: expected a value in [0, 1], got {mist!r}")
    with progress(progress_bar, 3, "sumi-e") as bar:
        gb = _gbuffer_of(
            dem,
            view_azimuth=view_azimuth,
            elevation_angle=elevation_angle,
            window_size=window_size,
            vert_exag=vert_exag,
            supersample=supersample,
            size=size,
            scale=scale,
        )
        bar.step("ink")
        lay = birdseye_layers(
            gb,
            interval=interval,
            major_interval=None if interval is None else 5.0 * interval,
            width=0.7,
            major_width=0.7,
            dense_spacing=6.0,
            profile_width=profile_width,
            bands=False,
        )
        alpha = lay["alpha"]
        # ink strong enough to read at the far edge and in the valleys too
        near = 1.0 - 0.5 * np.nan_to_num(lay["depth"], nan=1.0)
        wz = lay["wz"]
        fin = np.isfinite(wz)
        if fin.any():
            lo, hi = float(np.nanmin(wz)), float(np.nanmax(wz))
            high = np.where(fin, (wz - lo) / max(hi - lo, 1e-12), 0.0)
        else:
            high = np.zeros_like(wz)
        fade = near * (1.0 - mist + mist * np.sqrt(np.clip(high, 0.0, 1.0)))
        ink = np.maximum(lay["pr"], 0.5 * lay["cn"])
        if wash > 0:
            ink = np.maximum(ink, 0.35 * _wash_below(lay["pr"], wash))
        ink = np.clip(ink * fade, 0.0, 1.0) * np.minimum(alpha * 4.0, 1.0)
        # Sumi ink is a warm black; the paper shows through in proportion.
        sumi = np.float32([0.08, 0.07, 0.06])
        base = np.asarray(PAPER if paper is None else paper, dtype=np.float32)
        rgb = base * (1.0 - ink[..., None]) + sumi * ink[..., None]
        out = rgba(rgb, np.maximum(alpha, ink), None if paper is None else paper)
        bar.step("done")
    return out


def _wash_below(profile: np.ndarray, length: float) -> np.ndarray:
    """A wash that is darkest just below the profile lines and fades downwards over ``length``
    pixels: per column ``exp(-d / length)`` of the distance ``d`` down from the nearest line
    above, with the lines first widened and the result softened sideways, so that broken
    lines do not leave vertical streaks."""
    from scipy import ndimage

    h = profile.shape[0]
    lines = ndimage.maximum_filter1d(profile, size=5, axis=1) > 0.5
    rows = np.arange(h, dtype=np.float32)[:, None]
    last = np.maximum.accumulate(np.where(lines, rows, np.float32(-np.inf)), axis=0)
    with np.errstate(over="ignore"):
        wash = np.exp(-(rows - last) / np.float32(length)).astype(np.float32)
    return ndimage.gaussian_filter1d(wash, sigma=max(length / 3.0, 1.0), axis=1)
