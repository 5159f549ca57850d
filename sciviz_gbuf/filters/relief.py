"""Relief filters beyond ``gdaldem``: texture shading and the local relief model.

Both take a height grid with the conventions of :func:`~sciviz_gbuf.filters.hillshade.hillshade`
(row 0 = north, column 0 = west, NaN and +-inf = nodata, ``dx``/``dy`` the cell size in the
heights' units) and work on numpy and dask arrays alike.

- :func:`texture_shade` is Leland Brown's texture shading (2010): the fractional Laplacian
  ``(-Laplacian)^(alpha/2)`` of the heights, which keeps the drainage network and ridge lines
  of any scale at once (the mountains' "texture") where a hillshade shows the slopes facing
  one sun.
- :func:`local_relief` is the simple local relief model (SLRM; Hesse 2010, RVT's ``slrm``):
  the heights minus their mean over a square window, the small landforms with the large-scale
  trend taken away.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as _fft
from scipy import ndimage

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from .hillshade import check_grid, float32_heights

__all__ = ["default_texture_reach", "local_relief", "texture_shade"]

#: Default texture detail alpha (Brown's "detail" of 0.5: halfway between the heights, 0,
#: and their Laplacian, 2).
TEXTURE_DETAIL = 0.5
#: Default halo of texture shading on a dask array, in cells.
TEXTURE_REACH = 256
#: Default local relief radius, in cells (RVT's ``slrm`` default of 20).
LOCAL_RELIEF_CELLS = 20


def default_texture_reach() -> int:
    """The default ``reach`` of :func:`texture_shade` on a dask array, in cells."""
    return TEXTURE_REACH


def _filled(z: np.ndarray) -> np.ndarray:
    """``z`` with each NaN replaced by the nearest valid cell's height (a float32 copy): the
    spectral filter needs a value everywhere, and a nearest value adds no slope."""
    bad = np.isnan(z)
    if not bad.any():
        return z
    if bad.all():
        return np.zeros_like(z)
    idx = ndimage.distance_transform_edt(bad, return_distances=False, return_indices=True)
    return z[tuple(idx)]


def _plane(f: np.ndarray) -> np.ndarray:
    """The least-squares plane ``a + b col + c row`` through ``f`` (float64), from the nine
    sums of its normal equations (no (cells, 3) design matrix is made)."""
    h, w = f.shape
    r = np.arange(h, dtype=np.float64) - (h - 1) / 2
    c = np.arange(w, dtype=np.float64) - (w - 1) / 2
    # centred coordinates: the normal equations are diagonal
    mean = f.mean()
    sc, sr = (c * c).sum() * h, (r * r).sum() * w
    b = float((f.sum(axis=0) * c).sum() / sc) if sc else 0.0
    a = float((f.sum(axis=1) * r).sum() / sr) if sr else 0.0
    return mean + b * c[None, :] + a * r[:, None]


def texture_shade(
    heights: np.ndarray,
    *,
    detail: float = TEXTURE_DETAIL,
    dx: float = 1.0,
    dy: float = 1.0,
    z_factor: float = 1.0,
    mask: np.ndarray | None = None,
    reach: int | None = None,
) -> np.ndarray:
    """Texture shading (Brown 2010): the fractional Laplacian of the heights.

    ``T = (-Laplacian)^(alpha/2) z``: in the frequency domain every wave
    ``cos(kx x) cos(ky y)`` of the heights is multiplied by ``|k|^alpha =
    (kx^2 + ky^2)^(alpha/2)`` (``k`` in radians per unit of ``dx``). ``alpha = 0`` returns the
    heights, ``alpha = 2`` the negative Laplacian; in between, small valleys and ridges are
    weighted like big ones, so a whole drainage network shows at once, dark in valleys
    (negative) and bright on ridges (positive). This is the filter of Brown's texture shading
    and of its Python reference implementation (Fasih's ``texshade``, ``H = |f|^alpha`` with
    ``f`` in cycles per sample), which it equals up to the constant factor ``(2 pi /
    dx)^alpha`` (``|k| = 2 pi |f| / dx``) away from the grid edge.

    The best-fitting plane is taken away first (the fractional Laplacian of a plane is zero),
    and the rest is extended by mirroring it at the grid's edges (a discrete cosine transform,
    DCT-II, in place of the reference's zero padding): the edges get neither a cliff nor, from
    the terrain's overall tilt, a crease, and ``cos(pi m (row + 1/2) / H) cos(pi n (col + 1/2)
    / W)`` (``m, n >= 1``) is an exact eigenfunction.

    Parameters
    ----------
    heights : (H, W) array or dask array
        Heights; NaN and +-inf are nodata (filled with the nearest height for the filter, NaN
        in the result).
    detail : float in [0, 2], default: 0.5
        ``alpha``, Brown's detail.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south.
    z_factor : float, default: 1
        Vertical exaggeration (the result scales with it).
    mask : (H, W) bool, optional
        False marks nodata cells.
    reach : int, optional
        Dask arrays only: each chunk is filtered with ``reach`` cells of its neighbours around
        it (default :func:`default_texture_reach`, 256; at most ``LIMITS["reach"]``), the
        plane taken away per chunk. Landforms wider than about ``reach`` cells come out a
        little differently from the whole-grid filter: on hilly test terrain in 512-cell
        chunks (``alpha`` = 0.5) within 6 % of its 99th percentile away from the grid's edge,
        12 % in the chunks along it (whose halo the edge cuts off).

    Returns
    -------
    (H, W) float32
        In height units per (unit of ``dx``)^alpha; NaN at nodata. Mean zero over the grid
        for ``alpha > 0``.

    Raises
    ------
    InputError
        ``heights`` not a 2-D real array, ``mask`` of another shape, ``detail`` outside
        [0, 2], a bad cell size, ``z_factor`` or ``reach``.

    References
    ----------
    .. [1] Brown, L. (2010). A new technique for depicting terrain relief. NACIS Annual
       Meeting, St. Petersburg, Florida (texture shading).
    """
    detail = _validate.finite(detail, "detail")
    if not 0.0 <= detail <= 2.0:
        raise InputError(f"detail: expected a texture detail alpha in [0, 2], got {detail!r}")
    if reach is None:
        reach = TEXTURE_REACH
    reach = _validate.count(reach, "reach", "reach")
    if _chunks.any_dask(heights, mask):
        return _chunks.map_stencil(
            texture_shade,
            {"heights": heights, "mask": mask},
            halo=reach,
            detail=detail,
            dx=dx,
            dy=dy,
            z_factor=z_factor,
            reach=reach,
        )
    z = check_grid(heights, dx, dy, z_factor)
    z = float32_heights(z, mask)
    if z.size == 0:
        return z.copy()
    nodata = np.isnan(z)
    # float64 through the transforms: a float32 DCT of heights of thousands of metres loses
    # the small waves the filter is for.
    f = _filled(z).astype(np.float64) * float(z_factor)
    if detail > 0:
        f -= _plane(f)  # its gain is 0^alpha: zero, except for the identity alpha = 0
    h, w = f.shape
    ky = np.pi * np.arange(h) / (h * float(dy))
    kx = np.pi * np.arange(w) / (w * float(dx))
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    # |k|^alpha with 0^0 = 1 (alpha = 0 is the identity) and 0^alpha = 0 otherwise
    gain = k2 ** (detail / 2.0) if detail > 0 else np.ones_like(k2)
    spectrum = _fft.dctn(f, type=2, norm="ortho", workers=-1)
    spectrum *= gain
    out = _fft.idctn(spectrum, type=2, norm="ortho", workers=-1).astype(np.float32)
    out[nodata] = np.nan
    return out


def _window(radius: float | None, dx: float, dy: float) -> tuple[int, int]:
    """Half-sizes (rows, columns) of the local relief window for ``radius`` in metres."""
    if radius is None:
        return LOCAL_RELIEF_CELLS, LOCAL_RELIEF_CELLS
    r = _validate.finite(radius, "radius")
    if not r > 0:
        raise InputError(f"radius: expected a window radius > 0, got {radius!r}")
    rows, cols = round(r / float(dy)), round(r / float(dx))
    limit = int(_validate.LIMITS["reach"])
    if max(rows, cols) > limit:
        raise InputError(
            f"radius: {r:g} is {max(rows, cols)} cells; expected at most {limit} (LIMITS['reach'])"
        )
    return max(rows, 1), max(cols, 1)


def _window_sums(a: np.ndarray, r: int, axis: int) -> np.ndarray:
    """Sums of ``a`` over the windows ``[i - r, i + r]`` along ``axis``, cut off at the
    grid's edge: differences of a running sum, padded with its first and last value so that
    every window is one slice (no gather). The sums of float32 values in float64 are exact
    (29 spare bits), so they do not depend on where the grid starts (dask chunks agree)."""
    n = a.shape[axis]
    run = np.cumsum(a, axis=axis, dtype=np.float64)
    shape = list(a.shape)
    shape[axis] = r + 1
    start = np.zeros(shape, np.float64)
    end = np.repeat(np.take(run, [n - 1], axis=axis), r, axis=axis)
    # padded[k + r] is the sum before index k, for k in [-r, n + r] (clipped to [0, n])
    padded = np.concatenate([start, run, end], axis=axis)
    hi = [slice(None)] * a.ndim
    lo = [slice(None)] * a.ndim
    hi[axis], lo[axis] = slice(2 * r + 1, 2 * r + 1 + n), slice(0, n)
    return padded[tuple(hi)] - padded[tuple(lo)]


def _window_counts(n: int, r: int) -> np.ndarray:
    """How many of ``0..n-1`` lie in ``[i - r, i + r]``, for each ``i``."""
    i = np.arange(n)
    return (np.minimum(i + r, n - 1) - np.maximum(i - r, 0) + 1).astype(np.float64)


def _box_sum(a: np.ndarray, ry: int, rx: int) -> np.ndarray:
    """Sums of ``a`` over the (2 ry + 1) x (2 rx + 1) windows centred on each cell, the
    window cut off at the grid edge."""
    return _window_sums(_window_sums(a, ry, 0), rx, 1)


def local_relief(
    heights: np.ndarray,
    *,
    radius: float | None = None,
    dx: float = 1.0,
    dy: float = 1.0,
    z_factor: float = 1.0,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """Simple local relief model (SLRM): the heights minus their local mean.

    ``L(p) = z(p) - mean{ z(q) : |q_row - p_row| <= ry, |q_col - p_col| <= rx }`` over the
    data cells of a square window (RVT's ``slrm``, the first step of Hesse's local relief
    model): the trend of the landscape is taken away, and what is left are the landforms
    smaller than the window, positive on mounds and banks, negative in hollows and ditches.
    It is zero on any plane (where the window is whole), and ``-a (r (r + 1) / 3) (dx^2 +
    dy^2)`` on the paraboloid ``a (x^2 + y^2)`` for a window of ``r`` cells a side.

    Parameters
    ----------
    heights : (H, W) array or dask array
        Heights; NaN and +-inf are nodata (left out of the means, NaN in the result).
    radius : float > 0, optional
        Half the window's side in the units of ``dx``/``dy`` (rounded to whole cells per axis,
        at least one). Default: 20 cells (RVT's default) whatever the cell size; at most
        ``LIMITS["reach"]`` = 4096 cells.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south.
    z_factor : float, default: 1
        Vertical exaggeration (the result scales with it).
    mask : (H, W) bool, optional
        False marks nodata cells.

    Returns
    -------
    (H, W) float32
        In height units; NaN at nodata. Near the grid edge the window is cut off by it, so
        the trend there is that of the cells on one side.

    Raises
    ------
    InputError
        ``heights`` not a 2-D real array, ``mask`` of another shape, a bad cell size,
        ``z_factor`` or ``radius``.

    References
    ----------
    .. [1] Hesse, R. (2010). LiDAR-derived Local Relief Models - a new tool for archaeological
       prospection. Archaeological Prospection 17(2), 67-72.
    .. [2] Kokalj, Ž. & Hesse, R. (2017). Airborne laser scanning raster data visualization:
       a guide to good practice. Založba ZRC (RVT's SLRM).
    """
    check_grid(np.zeros((1, 1), np.float32), dx, dy, z_factor)
    ry, rx = _window(radius, dx, dy)
    if _chunks.any_dask(heights, mask):
        return _chunks.map_stencil(
            local_relief,
            {"heights": heights, "mask": mask},
            halo=max(ry, rx),
            radius=radius,
            dx=dx,
            dy=dy,
            z_factor=z_factor,
        )
    z = float32_heights(check_grid(heights, dx, dy, z_factor), mask)
    if z.size == 0:
        return z.copy()
    valid = ~np.isnan(z)
    zero = np.where(valid, z, np.float32(0))
    # the mean over the window's data cells: their sum over their count
    if valid.all():  # the count of a window is that of its rows times that of its columns
        count = np.outer(_window_counts(z.shape[0], ry), _window_counts(z.shape[1], rx))
    else:
        count = _box_sum(valid.astype(np.float32), ry, rx)
    with np.errstate(invalid="ignore", divide="ignore"):
        trend = _box_sum(zero, ry, rx) / count
    out = ((z - trend) * float(z_factor)).astype(np.float32)
    out[~valid] = np.nan
    return out
