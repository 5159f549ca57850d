"""The contour figures of Saito & Takahashi (1990): Fig. 5 (contour lines), Fig. 6 (curved
hatching) and Fig. 11 (a topographic map).

:func:`fig5_panels` and :func:`fig6_panels` draw the paper's test field ``s = x y`` (Eq. 16) on
``[-1, 1]²``: its gradient vanishes at the centre and grows towards the corners, so regular
contours go from far apart to crowded in one picture. Fig. 5 handles both ends with ``f_g``
(Eq. 10, 15): flat centre faded to white (``c_sparse``), crowded corners filled with
``c_dense``, black or grey. Fig. 6 avoids the crowding with curved hatching (Eq. 17-21): lines
at a near-constant on-screen spacing. :func:`fig11_panels` makes the plan-view map of Fig. 11
from the bundled Jacksboro DEM, whose grid *is* the G-buffer: height ``wz``, major and minor
contours with the minors thinned out where they crowd (``cn``), a relief shade (``sh``) and
their combination with colour bands (``mx3``).

All return ``(key, title, image)`` triples, ready for :func:`~sciviz_gbuf.compose.write_png`
and :func:`~sciviz_gbuf.compose.montage`: line pictures are grey paper ``1 - ink`` (float32
(H, W), 1 white), colour pictures float32 (H, W, 3). Each key has a one-sentence caption in
:data:`CONTOUR_CAPTIONS`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.colors import LinearSegmentedColormap

from ..compose import colorize, montage, write_png
from ..datasets import load_jacksboro_terrain
from ..errors import InputError
from ..filters import contour_lines, hatching, lambert

__all__ = [
    "CONTOUR_CAPTIONS",
    "HYPSOMETRIC_TINTS",
    "fig5_panels",
    "fig6_panels",
    "fig11_panels",
    "jacksboro_plan",
    "relief",
    "write_panels",
    "xy_field",
]

Panel = tuple[str, str, np.ndarray]

#: One-sentence caption of each panel, by key.
CONTOUR_CAPTIONS = {
    "a_black": "(a) contours of s = xy (Eq. 10, 15): the flat centre fades to white "
    "(c_sparse = 0), the crowded corners fill with black (c_dense = 1)",
    "b_grey": "(b) the same with c_dense = 0.5: where lines crowd closer than twice their "
    "width they blend into an even grey",
    "f1_bilevel": "Fig. 4(a) bilevel f1 (Eq. 8), zoomed: aliased, stair-stepped lines",
    "f1_linear": "Fig. 4(b) linear f1, zoomed: the exact coverage of each pixel by the line, "
    "antialiased",
    "f1_smooth": "Fig. 4(c) higher-order (smoothstep) f1, zoomed: softer edges",
    "contours": "contours of s = xy at a regular interval: far apart at the flat centre, "
    "crowded in the corners",
    "hatching": "curved hatching of s = xy (Eq. 17-21, binary thinning out): lines at a "
    "near-constant spacing everywhere; in-between lines start crisply (default transition)",
    "hatching_exact": "curved hatching with Eq. 18 exactly (transition 1): constant mean ink, "
    "but faint in-between lines where the spacing grows",
    "wz": "(wz) original height data: the Jacksboro DEM resampled to square pixels, "
    "north up, darker low",
    "cn": "(cn) contour image: thick major and thin minor contours; the minors are thinned out "
    "(c_dense = white) where they crowd, the majors never",
    "cn_unthinned": "contours without thinning: on steep slopes the minor lines crowd and "
    "merge with the majors",
    "majors": "the major contours alone, for comparison with (cn)",
    "sh": "(sh) relief: Lambert shade of the normals of the height grid, sun in the north-west",
    "bands": "colour bands: one hypsometric tint per major interval of height",
    "mx3": "(mx3) combination of the contours (cn), the relief (sh) and the colour bands",
}

#: Hypsometric tints of the colour bands, from low (green) to high (brown).
HYPSOMETRIC_TINTS = (
    (0.55, 0.74, 0.47),
    (0.78, 0.86, 0.56),
    (0.96, 0.93, 0.66),
    (0.93, 0.80, 0.56),
    (0.82, 0.65, 0.47),
    (0.72, 0.56, 0.46),
)

# Fig. 5: the lines reach one line width apart (solid c_dense) at this distance from the centre
# (the middle of each edge), so the corners are well inside the dense regime; the flat centre
# fades to c_sparse within FLAT_RADIUS.
DENSE_RADIUS = 1.0
FLAT_RADIUS = 0.3
# Fig. 4 crops: lines 4x sparser than in Fig. 5, zoomed 8x around (0.3, 0.3).
CROP_ZOOM = 8
CROP_CENTRE = (0.3, 0.3)
CROP_SPARSER = 4.0
# Fig. 11: the part of the DEM shown (metres from its south-west sample), where the fault's
# straight ridges meet a flat valley and a dissected plateau.
JACKSBORO_CENTRE = (15000.0, 16000.0)
# The DEM holds whole metres: a Gaussian of this many samples removes the 1 m steps before the
# bicubic resampling, which would otherwise give the flat valleys spurious little loops.
DEM_SMOOTH = 0.7


def write_panels(
    outdir: str | os.PathLike, name: str, panels: Sequence[Panel], *, columns: int = 4
) -> list[Path]:
    """Write ``(key, title, image)`` panels (of any figure) as ``<name>_<key>.png`` into
    ``outdir``, then their titled montage as ``<name>_montage.png``; return the paths in that
    order."""
    out = Path(outdir)
    written = [write_png(out / f"{name}_{key}.png", image) for key, _, image in panels]
    tiles = [(title, image) for _, title, image in panels]
    written.append(write_png(out / f"{name}_montage.png", montage(tiles, columns=columns)))
    return written


def _size(size: int) -> int:
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 16:
        raise InputError(f"size: expected an integer number of pixels >= 16, got {size!r}")
    return int(size)


def xy_field(size: int) -> tuple[np.ndarray, float]:
    """The test field ``s = x y`` of Eq. 16 on ``[-1, 1]²``, ``size`` x ``size`` pixels,
    ``y`` upwards (row 0 is ``y = 1``); and the pixel size in field units."""
    n = _size(size)
    y, x = np.mgrid[1 : -1 : n * 1j, -1 : 1 : n * 1j]
    return (x * y).astype(np.float32), 2.0 / (n - 1)


def _paper(ink: np.ndarray) -> np.ndarray:
    return (1.0 - ink).astype(np.float32)


def _zoom(image: np.ndarray, centre: tuple[float, float], zoom: int) -> np.ndarray:
    """The part of ``image`` (of ``[-1, 1]²``) around ``centre`` magnified ``zoom`` times with
    nearest-neighbour pixels, at the same size."""
    n = image.shape[0]
    c = -(-n // zoom)
    col = round((centre[0] + 1) / 2 * (n - 1)) - c // 2
    row = round((1 - centre[1]) / 2 * (n - 1)) - c // 2
    col, row = min(max(col, 0), n - c), min(max(row, 0), n - c)
    crop = image[row : row + c, col : col + c]
    return np.repeat(np.repeat(crop, zoom, axis=0), zoom, axis=1)[:n, :n]


def fig5_panels(
    size: int = 384,
    *,
    width: float = 1.5,
    interval: float | None = None,
    g_eps: float | None = None,
    profiles: bool = True,
) -> list[Panel]:
    """The 1990 Fig. 5: contour lines of ``s = x y`` with Eq. 10 and 15, and the Fig. 4 profiles.

    Parameters
    ----------
    size : int, default: 384
        Pixels across the square images.
    width : float, default: 1.5
        Line width ``d`` in pixels.
    interval : float, optional
        ``q`` of Eq. 12. Default: lines one line width apart at distance 1 from the centre,
        ``width * 2 / (size - 1)``, so the corners are solid ``c_dense`` and the lines read as
        lines within about half of that distance.
    g_eps : float, optional
        Eq. 11: ink fades to ``c_sparse = 0`` (white) where the Eq. 9 gradient is below it.
        Default: the gradient at distance 0.3 from the centre, so the flat centre visibly
        fades to white.
    profiles : bool, default: True
        Also return three 8x zoomed crops with the bilevel, linear and smooth line profiles
        ``f1`` (Fig. 4), drawn with a 4x larger interval so that the lines stand apart.

    Returns
    -------
    list of (key, title, image)
        ``a_black`` (``c_dense = 1``), ``b_grey`` (``c_dense = 0.5``), then if ``profiles``
        ``f1_bilevel``, ``f1_linear``, ``f1_smooth``; grey paper ``1 - ink`` of shape
        ``(size, size)``.
    """
    s, px = xy_field(size)
    q = width * DENSE_RADIUS * px if interval is None else interval
    eps = FLAT_RADIUS * px if g_eps is None else g_eps
    opts = {"interval": q, "width": width, "g_eps": eps, "c_sparse": 0.0}
    panels: list[Panel] = [
        ("a_black", "(a) c_dense = 1 (black)", _paper(contour_lines(s, c_dense=1.0, **opts))),
        ("b_grey", "(b) c_dense = 0.5 (grey)", _paper(contour_lines(s, c_dense=0.5, **opts))),
    ]
    if profiles:
        for tag, profile in (("a", "bilevel"), ("b", "linear"), ("c", "smooth")):
            ink = contour_lines(s, interval=CROP_SPARSER * q, width=width, profile=profile)
            panels.append(
                (
                    f"f1_{profile}",
                    f"Fig. 4({tag}) {profile} f1, {CROP_ZOOM}x zoom",
                    _zoom(_paper(ink), CROP_CENTRE, CROP_ZOOM),
                )
            )
    return panels


def fig6_panels(
    size: int = 384,
    *,
    spacing: float = 6.0,
    width: float = 1.0,
    exact: bool = True,
) -> list[Panel]:
    """The 1990 Fig. 6: curved hatching of ``s = x y``, next to regular contours.

    Parameters
    ----------
    size : int, default: 384
        Pixels across the square images.
    spacing : float, default: 6
        ``d_i`` of Eq. 18: the on-screen spacing of the hatch lines in pixels. The regular
        contours use the interval that puts their lines this far apart at distance 0.5 from
        the centre (``spacing / 2 * 2 / (size - 1)``): about 3x closer in the corners, much
        further apart near the centre. The hatching's standard interval ``p_d`` is the same,
        so its lines are a subset and refinement of the contours.
    width : float, default: 1
        Line width in pixels.
    exact : bool, default: True
        Also return the hatching with Eq. 18 exactly (``transition=1``).

    Returns
    -------
    list of (key, title, image)
        ``contours``, ``hatching`` (the filter's default ``transition``) and if ``exact``
        ``hatching_exact``; grey paper ``1 - ink`` of shape ``(size, size)``.
    """
    s, px = xy_field(size)
    q = spacing * 0.5 * px
    panels: list[Panel] = [
        (
            "contours",
            "contour lines, regular interval",
            _paper(contour_lines(s, interval=q, width=width)),
        ),
        (
            "hatching",
            f"curved hatching, spacing {spacing:g} px",
            _paper(hatching(s, spacing=spacing, width=width, interval=q)),
        ),
    ]
    if exact:
        ink = hatching(s, spacing=spacing, width=width, interval=q, transition=1.0)
        panels.append(("hatching_exact", "curved hatching, Eq. 18 exactly", _paper(ink)))
    return panels


def jacksboro_plan(
    size: int = 512,
    *,
    pixel_size: float = 20.0,
    centre: Sequence[float] = JACKSBORO_CENTRE,
    smooth: float = DEM_SMOOTH,
) -> np.ndarray:
    """A square plan-view height image (``wz``) of the Jacksboro DEM, north up, in metres.

    The DEM (:func:`~sciviz_gbuf.datasets.load_jacksboro_terrain`: whole metres on a grid of
    about 74.6 m east by 92.5 m north) is smoothed with a Gaussian of ``smooth`` samples and
    resampled bicubically to square pixels of ``pixel_size`` metres, ``size`` x ``size`` of
    them centred on ``centre`` (metres east and north of the south-west sample).

    Returns
    -------
    (size, size) float32
        Elevation in metres; row 0 is the north edge.

    Raises
    ------
    InputError
        If the square does not lie within the DEM, or a parameter is out of range.
    """
    from scipy import ndimage

    n = _size(size)
    if not (np.isfinite(pixel_size) and pixel_size > 0):
        raise InputError(f"pixel_size: expected metres > 0, got {pixel_size!r}")
    if not (np.isfinite(smooth) and smooth >= 0):
        raise InputError(f"smooth: expected a number of samples >= 0, got {smooth!r}")
    grid = load_jacksboro_terrain()
    nx, ny, _ = grid.dimensions
    elev = np.asarray(grid.point_data["elevation"], dtype=np.float64).reshape(ny, nx)
    pts = np.asarray(grid.points)
    dx, dy = pts[1, 0] - pts[0, 0], pts[nx, 1] - pts[0, 1]
    cx, cy = (float(c) for c in centre)
    half = (n - 1) / 2 * pixel_size
    if not (half <= cx <= dx * (nx - 1) - half and half <= cy <= dy * (ny - 1) - half):
        raise InputError(
            f"centre, size, pixel_size: a square of {2 * half:.0f} m about ({cx:g}, {cy:g}) m "
            f"does not fit in the DEM ({dx * (nx - 1):.0f} x {dy * (ny - 1):.0f} m)"
        )
    if smooth > 0:
        elev = ndimage.gaussian_filter(elev, smooth)
    off = (np.arange(n) - (n - 1) / 2) * pixel_size
    rows = np.broadcast_to((cy - off)[:, None] / dy, (n, n))  # row 0 of the DEM is south
    cols = np.broadcast_to((cx + off)[None, :] / dx, (n, n))
    return ndimage.map_coordinates(elev, [rows, cols], order=3).astype(np.float32)


def relief(
    height: np.ndarray,
    pixel_size: float,
    *,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float = 1.0,
) -> np.ndarray:
    """Relief shade of a north-up height image: Lambert shade of the normals of its gradient,
    sun at ``azimuth`` (degrees clockwise from north) and ``altitude`` (GDAL's convention).

    Returns (H, W) float32 in [0, 1], 1 fully lit; flat ground is ``sin(altitude)``.
    """
    dz_row, dz_col = np.gradient(height.astype(np.float64) * z_factor, pixel_size)
    # east = +column, north = -row
    normal = np.dstack([-dz_col, dz_row, np.ones_like(dz_col)])
    normal /= np.linalg.norm(normal, axis=2, keepdims=True)
    az, alt = np.radians(azimuth), np.radians(altitude)
    sun = (np.sin(az) * np.cos(alt), np.cos(az) * np.cos(alt), np.sin(alt))
    return lambert(normal.astype(np.float32), light=sun)


def fig11_panels(
    size: int = 512,
    *,
    pixel_size: float = 20.0,
    centre: Sequence[float] = JACKSBORO_CENTRE,
    interval: float = 20.0,
    major_interval: float = 100.0,
    width: float = 1.0,
    major_width: float = 2.0,
    dense_spacing: float = 4.0,
    azimuth: float = 315.0,
    altitude: float = 45.0,
) -> list[Panel]:
    """The 1990 Fig. 11 process on the Jacksboro DEM: a plan-view topographic map.

    No rendering: the resampled DEM grid (:func:`jacksboro_plan`) is the G-buffer ``wz``.

    Parameters
    ----------
    size : int, default: 512
        Pixels across the square map.
    pixel_size : float, default: 20
        Metres per pixel (the DEM's own samples are 75-92 m apart). The paper's 20 m / 5 m
        contours suit a gentler, finer map; this terrain's slopes (median 24 %) would bury
        5 m contours at any useful scale, so the defaults are 100 m majors and 20 m minors.
    centre : (float, float)
        Of the map, in metres east and north of the DEM's south-west sample.
    interval, major_interval : float, default: 20, 100
        Minor and major contour intervals in metres.
    width, major_width : float, default: 1, 2
        Their line widths in pixels.
    dense_spacing : float, default: 4
        Minor lines fade out (``c_dense`` = white, Eq. 15) where they come closer than this
        many pixels, and are gone one line width closer: on slopes steeper than about
        ``interval / (dense_spacing * pixel_size)`` (25 % by default) only the majors remain.
    azimuth, altitude : float, default: 315, 45
        The sun of the relief, GDAL's convention.

    Returns
    -------
    list of (key, title, image)
        ``wz`` (grey height), ``cn`` (the contour image), ``cn_unthinned`` (the same without
        thinning), ``majors`` (majors alone), ``sh`` (relief), ``bands`` (colour bands, RGB)
        and ``mx3`` (their combination, RGB); ``(size, size)``.
    """
    z = jacksboro_plan(size, pixel_size=pixel_size, centre=centre)
    cn = contour_lines(
        z,
        interval=interval,
        major_interval=major_interval,
        width=width,
        major_width=major_width,
        dense_spacing=dense_spacing,
    )
    majors = contour_lines(z, interval=major_interval, width=major_width)
    unthinned = np.maximum(contour_lines(z, interval=interval, width=width), majors)
    sh = relief(z, pixel_size, azimuth=azimuth, altitude=altitude)
    lo = np.floor(float(z.min()) / major_interval) * major_interval
    hi = np.ceil(float(z.max()) / major_interval) * major_interval
    band = (np.floor((z - lo) / major_interval) + 0.5) * major_interval + lo
    tints = LinearSegmentedColormap.from_list("hypsometric", HYPSOMETRIC_TINTS)
    bands = colorize(band, cmap=tints, vmin=lo, vmax=hi)
    # Relief relative to flat ground (sin(altitude)): slopes facing the sun lighter.
    light = np.clip(0.35 + 0.65 * sh / np.sin(np.radians(altitude)), 0.0, 1.2)
    mx3 = np.clip(bands * light[..., None], 0.0, 1.0) * (1.0 - cn)[..., None]
    m = f"{major_interval:g} m"
    return [
        ("wz", "(wz) original height data", (z - z.min()) / max(float(np.ptp(z)), 1e-6)),
        ("cn", f"(cn) contour image, {m} and {interval:g} m", _paper(cn)),
        ("cn_unthinned", "contours without thinning", _paper(unthinned)),
        ("majors", f"{m} contours only", _paper(majors)),
        ("sh", "(sh) shaded image (relief)", sh),
        ("bands", f"colour bands every {m}", bands),
        ("mx3", "(mx3) combination of (cn), (sh) and bands", mx3.astype(np.float32)),
    ]
