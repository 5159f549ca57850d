"""Terrain lighting beyond ``gdaldem``: cast shadows and sky-view factor of a height grid.

The counterparts of R rayshader's ``ray_shade`` and ``ambient_shade`` for plan-view DEMs, with the
conventions of :func:`~sciviz_gbuf.filters.hillshade.hillshade` (row 0 = north, column 0 = west,
azimuth clockwise from north, NaN = nodata). Both march rays over the grid with one shared
scheme: a step of exactly one pixel along the ray's dominant axis, the height linearly
interpolated between the two cells that straddle the ray along the other axis. Along the axes
and the pixel diagonals (with ``dx == dy``) every sample falls on a cell centre.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from . import _terrain_light_kernels as _k
from .hillshade import check_grid, float32_heights

__all__ = ["cast_shadows", "openness", "sky_view"]

# sin/cos of multiples of 90 degrees are off by ~1e-16, and a sun 1e-10 degrees off north drifts
# 3e-12 px a step: snap such components to 0 or +-1. A drift below 1e-9 px a step stays under
# 1e-4 px over the longest ray, so the ray is cardinal; left unsnapped, it would step off a
# one-cell-wide grid at once (the column "between" 0 and 1 does not exist) and see no horizon.
_SNAP = 1e-9


def line_max(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Largest height of every row and every column, float64 (-inf where all nodata):
    numpy's NaN-skipping maximum, two passes at memory speed (a serial loop took twice as
    long at 8192²)."""
    with np.errstate(invalid="ignore"):
        rows, cols = (np.fmax.reduce(z, axis=a).astype(np.float64) for a in (1, 0))
    for line in (rows, cols):
        line[np.isnan(line)] = -np.inf
    return rows, cols


def _bounds(line: np.ndarray) -> np.ndarray:
    """(3, n) upper bounds of the heights a ray meets from line k on: moving to higher indices,
    to lower indices (interpolation also reads k + 1), and not moving along this axis."""
    up = np.maximum.accumulate(line[::-1])[::-1]
    down = np.maximum.accumulate(line)
    down = np.concatenate([down[1:], down[-1:]])
    return np.stack([up, down, line])


def _local_max(z: np.ndarray, radius: float, dx: float, dy: float) -> np.ndarray:
    """Highest cell within ``radius`` metres of each cell (a box, plus the interpolation
    neighbour): where the rays' march is limited, a far tighter bound than the row/column maxima
    on rough terrain."""
    from scipy import ndimage  # the per-cell references only: not imported by a map

    h, w = z.shape
    half_r = min(math.ceil(radius / dy) + 1, h)
    half_c = min(math.ceil(radius / dx) + 1, w)
    filled = np.where(np.isnan(z), np.float32(-np.inf), z)
    return ndimage.maximum_filter(
        filled, size=(2 * half_r + 1, 2 * half_c + 1), mode="constant", cval=-np.inf
    )


def default_sky_radius(dx: float, dy: float) -> float:
    """:func:`sky_view`'s search distance when none is given: 50 cells of the coarser axis,
    in metres (one definition for the filter and the chunk halo of the maps that call it)."""
    return 50.0 * max(float(dx), float(dy))


def sky_view_reach(radius: float, dx: float, dy: float) -> int:
    """Cells :func:`sky_view` reads around a cell (its stencil radius, for chunked evaluation):
    the most steps the ray march takes, ``radius`` metres in cells of the finer axis (a
    sample's interpolation neighbour lies across the other axis, which the ray crosses more
    slowly). The :func:`_local_max` box is wider, but it only bounds the cells the march reads,
    and a box cut at a chunk's halo still does."""
    r = _check_radius(radius, dx, dy)
    return max(1, math.floor(r / min(float(dx), float(dy)) * (1.0 + 1e-12)))


def _check_radius(radius: object, dx: float, dy: float) -> float:
    """``radius`` in metres, finite, > 0 and at most ``LIMITS["reach"]`` cells of the finer
    axis (the march, the chunk halo and the local-maximum box all grow with it)."""
    r = _validate.finite(radius, "radius")
    if not r > 0.0:
        raise InputError(f"radius: expected a finite distance > 0 (metres), got {radius!r}")
    cells = r / min(float(dx), float(dy))
    bound = _validate.LIMITS["reach"]
    if not cells <= bound:
        raise InputError(
            f"radius: expected at most {bound:g} cells (LIMITS['reach']) of "
            f"{min(float(dx), float(dy)):g} m, got {radius!r} m = {cells:.4g} cells"
        )
    return r


def _which(step: float) -> int:
    return 0 if step > 0.0 else (1 if step < 0.0 else 2)


def _snap(v: float) -> float:
    if abs(v) < _SNAP:
        return 0.0
    if abs(abs(v) - 1.0) < _SNAP:
        return math.copysign(1.0, v)
    return v


def _ray_steps(azimuth: float, dx: float, dy: float) -> tuple[float, float, float]:
    """(rows, columns, metres) per step of a ray towards ``azimuth`` (degrees clockwise from north),
    one pixel along its dominant axis."""
    az = math.radians(azimuth)
    per_m_col = _snap(math.sin(az)) / dx  # east is +column
    per_m_row = -_snap(math.cos(az)) / dy  # north is -row
    m = max(abs(per_m_col), abs(per_m_row))
    return _snap(per_m_row / m), _snap(per_m_col / m), 1.0 / m


def _sky_rays(
    z: np.ndarray, dx: float, dy: float, directions: int, radius: float, local: bool = True
) -> tuple:
    """The ray arguments of the sky kernels (:func:`sky_view`, :func:`openness`) after ``z``:
    per direction the steps (rows, columns, metres) and which bounds apply, the row and column
    height bounds, the local maximum within ``radius`` (None without ``local``: the row
    march does not use it), and ``radius``."""
    steps = [
        _ray_steps(360.0 * k / int(directions), float(dx), float(dy)) for k in range(directions)
    ]
    d_rows, d_cols, step_lens = (np.array(s, dtype=np.float64) for s in zip(*steps, strict=True))
    rows, cols = line_max(z)
    row_which = np.array([_which(v) for v in d_rows], dtype=np.int64)
    col_which = np.array([_which(v) for v in d_cols], dtype=np.int64)
    return (
        d_rows,
        d_cols,
        step_lens,
        _bounds(rows),
        _bounds(cols),
        row_which,
        col_which,
        _local_max(z, float(radius), float(dx), float(dy)) if local else None,
        float(radius),
    )


def _prepare(
    heights: np.ndarray, dx: float, dy: float, z_factor: float, mask: np.ndarray | None,
    writable: bool = False,
) -> np.ndarray:  # fmt: skip
    """Checked float32 ``heights * z_factor`` with NaN at nodata (inputs untouched): a copy
    if ``writable``, else float32 heights without nodata to blank or scale are read as they
    are (a 256 MB copy at 8192² is a tenth of a short-radius sky view)."""
    z = check_grid(heights, dx, dy, z_factor)
    scaled = float(z_factor) != 1.0
    z32 = float32_heights(z, mask, writable=writable or scaled)
    if scaled:
        z32 *= np.float32(z_factor)
    return z32


def cast_shadows(
    heights: np.ndarray,
    *,
    dx: float = 1.0,
    dy: float = 1.0,
    azimuth: float = 315.0,
    altitude: float = 45.0,
    z_factor: float = 1.0,
    sun_radius: float = 0.0,
    mask: np.ndarray | None = None,
    method: str = "sweep",
) -> np.ndarray:
    """Shadows cast by the terrain on itself under a directional sun (rayshader's ``ray_shade``).

    A ray from every cell towards the sun, one pixel per step along its dominant axis with the
    terrain linearly interpolated across the other axis: the cell is in shadow if a sample
    rises above the ray. Beyond the grid edge nothing blocks. Hard shadows (``sun_radius=0``)
    are found by one sweep away from the sun (``method="sweep"``, the default): for a family
    of parallel lines towards the sun through the grid, the *shadow surface* (the highest
    sample so far less ``tan(altitude)`` times its distance) is carried row by row (or column
    by column), O(1) per cell whatever the shadows' length. Along the grid's axes and (square
    cells) its diagonals the lines pass through the cells and the sweep marks exactly the
    march's shadows; at other azimuths a cell between two lines gets the interpolation of
    their surfaces, which keeps shadows' lengths and moves their sides by up to about a cell
    (on a real SRTM DEM up to 1 % of the cells differ, nearly all at shadow edges; tested against
    ``method="march"``, which marches every cell's ray and stops once the ray is above every
    cell it could still meet). Soft shadows always march.

    Parameters
    ----------
    heights : (H, W) array
        Heights; row 0 is the north edge, column 0 the west edge. NaN and +-inf are nodata.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south, in the units of the heights (metres).
    azimuth : float, default: 315
        Direction the light comes from, degrees clockwise from north.
    altitude : float in (0, 90], default: 45
        Elevation of the sun's centre above the horizon, degrees; 90 casts no shadows.
    z_factor : float, default: 1
        Vertical exaggeration; shadow lengths scale with it.
    sun_radius : float, default: 0
        Angular radius of the sun disc, degrees, in ``[0, min(altitude, 90 - altitude)]``. 0 gives
        hard shadows (0 or 1). Otherwise the result is the share of the disc above the terrain
        horizon in the sun's azimuth, a penumbra that widens with distance from the occluder (the
        true sun is ~0.27 degrees). The horizon is taken as straight across the disc.
    mask : (H, W) bool, optional
        False marks nodata cells, like NaN heights.
    method : {"sweep", "march"}, default: "sweep"
        How hard shadows are found (above); ``sun_radius > 0`` marches either way.

    Returns
    -------
    (H, W) float32 in [0, 1]
        1 = lit, 0 = in shadow; NaN at nodata. Nodata cells never block the sun.

    Notes
    -----
    "Shadow" means the sun is hidden by terrain along the ray, whichever terrain that is. So a
    slope facing away from the sun and steeper than its altitude is shadowed by its own upslope
    cells (as in rayshader), except for the cells at the grid edge towards the sun, which have no
    terrain beyond them. A discrete grid cannot tell such self-shadow from a cast shadow on curved
    ground; multiply with :func:`~sciviz_gbuf.filters.hillshade.hillshade`, which is 0 on those
    slopes anyway. The march costs about (shadow length in pixels) per cell, so low suns are
    slower; the sweep costs the same at any sun.

    Raises
    ------
    InputError
        ``heights`` not 2-D or ``mask`` of another shape; ``dx``/``dy`` not finite and positive;
        ``altitude`` outside (0, 90]; non-finite ``azimuth``/``z_factor``; ``sun_radius`` out of
        range; ``method`` not one of the two.
    """
    method = _validate.choice(method, "method", ("sweep", "march"))
    for name, value in (("azimuth", azimuth), ("altitude", altitude), ("sun_radius", sun_radius)):
        _validate.finite(value, name)
    if not 0.0 < float(altitude) <= 90.0:
        raise InputError(f"altitude: expected degrees in (0, 90], got {altitude!r}")
    limit = min(float(altitude), 90.0 - float(altitude))
    if not 0.0 <= float(sun_radius) <= limit:
        raise InputError(
            f"sun_radius: expected degrees in [0, {limit:g}] (disc between horizon and zenith), "
            f"got {sun_radius!r}"
        )
    if _chunks.any_dask(heights, mask):
        raise InputError(
            "cast_shadows: a shadow may be cast from anywhere along the sun's ray across the "
            "whole grid, so it cannot be computed chunk by chunk (dask); compute it on an "
            "in-memory array, or use sky_view (bounded reach) out of core"
        )
    z = _prepare(heights, dx, dy, z_factor, mask)
    if float(altitude) == 90.0 or z.size == 0:
        return np.where(np.isnan(z), np.float32(np.nan), np.float32(1.0))
    d_row, d_col, step_len = _ray_steps(float(azimuth), float(dx), float(dy))
    if method == "sweep" and float(sun_radius) == 0.0:
        return _k.shadow_sweep_kernel(z, d_row, d_col, step_len, float(altitude))
    rows, cols = line_max(z)
    return _k.shadow_kernel(
        z,
        d_row,
        d_col,
        step_len,
        _bounds(rows),
        _which(d_row),
        _bounds(cols),
        _which(d_col),
        float(altitude),
        float(sun_radius),
    )


def sky_view(
    heights: np.ndarray,
    *,
    dx: float = 1.0,
    dy: float = 1.0,
    directions: int = 16,
    radius: float | None = None,
    z_factor: float = 1.0,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """Sky-view factor: the share of the sky hemisphere a cell sees (rayshader's
    ``ambient_shade``, Zakšek et al. 2011).

    ``SVF = 1 - mean_d sin(max(0, horizon_d))`` over ``directions`` azimuths ``360 k / n``
    (k = 0..n-1, from north clockwise), where ``horizon_d`` is the largest elevation angle of the
    terrain seen from the cell within ``radius`` in direction d. Rays are marched as in
    :func:`cast_shadows`.

    Parameters
    ----------
    heights : (H, W) array
        Heights; row 0 is the north edge, column 0 the west edge. NaN and +-inf are nodata.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south, in the units of the heights (metres).
    directions : int in [1, 360], default: 16
        Number of horizon directions; at most ``LIMITS["directions"]`` = 360.
    radius : float > 0, optional
        Search distance in metres. Default: ``50 * max(dx, dy)``. Larger is more faithful in
        broad valleys and slower; the march also stops where no cell could raise the horizon.
        At most ``LIMITS["reach"]`` = 4096 cells of the finer axis (``radius / min(dx, dy)``).
    z_factor : float, default: 1
        Vertical exaggeration.
    mask : (H, W) bool, optional
        False marks nodata cells, like NaN heights.

    Returns
    -------
    (H, W) float32 in [0, 1]
        1 on open flat ground, peaks and ridges; less in valleys and pits. NaN at nodata; nodata
        cells never block the sky. Beyond the grid edge nothing blocks, so cells near the edge
        see more sky than they would in a larger DEM.

    Raises
    ------
    InputError
        ``heights`` not 2-D or ``mask`` of another shape; ``dx``/``dy``/``radius`` not finite and
        positive; ``directions`` not an integer in [1, 360]; ``radius`` beyond 4096 cells;
        non-finite ``z_factor``.

    Notes
    -----
    Every cell's ray takes every step within ``radius`` (``directions * radius / cell``
    samples a cell), marched for a whole row of cells at once: a step puts every cell's sample
    at the same offset with the same interpolation weight, so it is one vectorised float32
    loop over shifted rows of the grid, and four steps share one loop (each cell's running
    maximum kept in a register). The values are those of the per-cell march of the same
    samples within float32 rounding (1e-6), and those of the one-step row march bit for bit.
    The march stops early only where no row or column ahead could raise any cell's horizon.
    A cell reads the cells within ``radius`` of it along the finer axis (plus an interpolation
    neighbour across), the halo of the chunked (dask) evaluation
    (:func:`sky_view_reach`), whose chunks give the whole grid's values.

    References
    ----------
    .. [1] Zakšek, K., Oštir, K. & Kokalj, Ž. (2011). Sky-view factor as a relief visualization
       technique. Remote Sensing 3(2), 398-415.
    .. [2] Morgan-Wall, T. rayshader: ``ambient_shade``. https://www.rayshader.com
    """
    directions = _validate.count(directions, "directions", "directions")
    _prepare(np.zeros((3, 3), np.float32), dx, dy, z_factor, None)  # checks dx, dy first
    if radius is None:
        radius = default_sky_radius(dx, dy)
    radius = _check_radius(radius, dx, dy)
    if _chunks.any_dask(heights, mask):
        reach = radius
        return _chunks.map_stencil(
            sky_view,
            {"heights": heights, "mask": mask},
            halo=sky_view_reach(reach, dx, dy),
            dx=dx,
            dy=dy,
            directions=directions,
            radius=reach,
            z_factor=z_factor,
        )
    z = _prepare(heights, dx, dy, z_factor, mask)
    if z.size == 0:
        return z.copy()  # not the caller's array
    return _k.sky_view_kernel(z, *_sky_rays(z, dx, dy, directions, radius, local=False))


def openness(
    heights: np.ndarray,
    *,
    kind: str = "positive",
    dx: float = 1.0,
    dy: float = 1.0,
    directions: int = 16,
    radius: float | None = None,
    z_factor: float = 1.0,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """Topographic openness in degrees (Yokoyama, Shirasawa & Pike 2002).

    Positive openness ``Phi_L = mean_d (90 - beta_d)``, where ``beta_d`` is the largest
    elevation angle of the terrain seen from the cell within ``radius`` (``L``) in direction d
    (negative where all of it lies below the cell); negative openness ``Psi_L = mean_d
    (90 + delta_d)`` with ``delta_d`` the smallest one, i.e. the positive openness of the
    inverted terrain. Over ``directions`` azimuths ``360 k / n`` (k = 0..n-1, from north
    clockwise), rays marched as in :func:`sky_view` (which is ``1 - mean_d sin(max(0,
    beta_d))``). Positive openness is high on ridges and peaks, negative openness in valleys.

    Parameters
    ----------
    heights : (H, W) array
        Heights; row 0 is the north edge, column 0 the west edge. NaN and +-inf are nodata.
    kind : {"positive", "negative"}, default: "positive"
        Which openness.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south, in the units of the heights (metres).
    directions : int in [1, 360], default: 16
        Number of directions (Yokoyama et al. use 8); at most ``LIMITS["directions"]``.
    radius : float > 0, optional
        The distance ``L`` in metres. Default: ``50 * max(dx, dy)``, as :func:`sky_view`; at
        most ``LIMITS["reach"]`` = 4096 cells of the finer axis.
    z_factor : float, default: 1
        Vertical exaggeration.
    mask : (H, W) bool, optional
        False marks nodata cells, like NaN heights.

    Returns
    -------
    (H, W) float32 in [0, 180]
        Degrees: 90 on any plane (every ray reaching ``radius`` inside the grid), more on a
        peak (``90 + atan(slope)`` at a cone's apex), less in a pit. NaN at nodata; nodata
        samples are skipped, and a ray with no sample (it leaves the grid at once, or meets
        only nodata) counts as a horizontal horizon (90). Near the grid edge the rays are
        shorter, so the values there describe less terrain.

    Raises
    ------
    InputError
        ``heights`` not 2-D or ``mask`` of another shape; ``kind`` not one of the two;
        ``dx``/``dy``/``radius`` not finite and positive; ``directions`` not an integer in
        [1, 360]; ``radius`` beyond 4096 cells; non-finite ``z_factor``.

    References
    ----------
    .. [1] Yokoyama, R., Shirasawa, M. & Pike, R. J. (2002). Visualizing topography by
       openness: a new application of image processing to digital elevation models.
       Photogrammetric Engineering & Remote Sensing 68(3), 257-265.
    .. [2] Kokalj, Ž. & Somrak, M. (2019). Why not a single image? Combining visualizations to
       facilitate fieldwork and on-screen mapping. Remote Sensing 11(7), 747 (RVT).
    """
    kind = _validate.choice(kind, "kind", ("positive", "negative"))
    directions = _validate.count(directions, "directions", "directions")
    _prepare(np.zeros((3, 3), np.float32), dx, dy, z_factor, None)  # checks dx, dy first
    if radius is None:
        radius = default_sky_radius(dx, dy)
    radius = _check_radius(radius, dx, dy)
    if _chunks.any_dask(heights, mask):
        return _chunks.map_stencil(
            openness,
            {"heights": heights, "mask": mask},
            halo=sky_view_reach(radius, dx, dy),
            kind=kind,
            dx=dx,
            dy=dy,
            directions=directions,
            radius=radius,
            z_factor=z_factor,
        )
    z = _prepare(heights, dx, dy, z_factor, mask, writable=kind == "negative")
    if z.size == 0:
        return z.copy()  # not the caller's array
    if kind == "negative":
        np.negative(z, out=z)  # a private copy: the openness of the inverted terrain
    return _k.openness_kernel(z, *_sky_rays(z, dx, dy, directions, radius, local=False))
