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

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from .hillshade import check_grid, float32_heights

__all__ = ["local_relief", "texture_shade"]

#: Default texture detail alpha (Brown's "detail" of 0.5: halfway between the heights, 0,
#: and their Laplacian, 2).
TEXTURE_DETAIL = 0.5
#: Default local relief radius, in cells (RVT's ``slrm`` default of 20).
LOCAL_RELIEF_CELLS = 20


def _row_sums(z: np.ndarray) -> np.ndarray:
    """(H, 5) float64 sums along each row of whole rows ``z`` (NaN nodata): data cells, and
    their ``c``, ``c^2``, ``z``, ``z c`` with ``c`` the column from the grid's centre. Each
    row is summed on its own (numpy's pairwise sum of one contiguous row), so a block of
    whole rows gives the same sums as the whole grid, bit for bit."""
    w = z.shape[1]
    c = np.arange(w, dtype=np.float64) - (w - 1) / 2
    v = np.isfinite(z)
    vv = v.astype(np.float64)
    zz = np.where(v, z, 0.0).astype(np.float64)
    return np.stack(
        [vv.sum(axis=1), (vv * c).sum(axis=1), (vv * c * c).sum(axis=1), zz.sum(axis=1),
         (zz * c).sum(axis=1)], axis=1,
    )  # fmt: skip


def _plane_coefficients(sums: np.ndarray) -> tuple[float, float, float]:
    """``(a, b, c)`` of the least-squares plane ``a + b col + c row`` (coordinates from the
    grid's centre) through the data cells, from the (H, 5) row sums of :func:`_row_sums`."""
    h = sums.shape[0]
    r = np.arange(h, dtype=np.float64) - (h - 1) / 2
    n, sx, sxx, sz, sxz = sums.T
    m = np.array([[n.sum(), sx.sum(), (n * r).sum()],
                  [sx.sum(), sxx.sum(), (sx * r).sum()],
                  [(n * r).sum(), (sx * r).sum(), (n * r * r).sum()]])  # fmt: skip
    rhs = np.array([sz.sum(), sxz.sum(), (sz * r).sum()])
    if not n.sum():
        return 0.0, 0.0, 0.0
    coef = np.linalg.lstsq(m, rhs, rcond=None)[0]  # one row or column: the least norm
    return float(coef[0]), float(coef[1]), float(coef[2])


def _plane(shape: tuple[int, int], coef: tuple[float, float, float], chunks=None):
    """The plane ``a + b col + c row`` on the grid (numpy, or dask with ``chunks``): the same
    float64 expression either way, so the same values."""
    h, w = shape
    a, b, c = coef
    if chunks is None:
        cols = np.arange(w, dtype=np.float64) - (w - 1) / 2
        rows = np.arange(h, dtype=np.float64) - (h - 1) / 2
    else:
        import dask.array as da

        cols = da.arange(w, dtype=np.float64, chunks=(chunks[1],)) - (w - 1) / 2
        rows = da.arange(h, dtype=np.float64, chunks=(chunks[0],)) - (h - 1) / 2
    return a + b * cols[None, :] + c * rows[:, None]


#: Gaussian of the nodata fill (cells) and its reach (4 sigma).
_FILL_SIGMA = 4.0
FILL_RADIUS = 16


def _fill_residual(r: np.ndarray) -> np.ndarray:
    """The detrended heights ``r`` (float64, NaN nodata) with each nodata cell within
    :data:`FILL_RADIUS` cells of data set to the Gaussian-weighted mean of the data around it
    and the others to 0 (the plane): a value everywhere for the transform, without a step at
    a nodata border. Each value reads ``FILL_RADIUS`` cells around it only."""
    valid = np.isfinite(r)
    if valid.all():
        return r
    from scipy import ndimage  # imported by the relief styles that use it, not by every map

    opts = {"sigma": _FILL_SIGMA, "truncate": FILL_RADIUS / _FILL_SIGMA, "mode": "constant"}
    num = ndimage.gaussian_filter(np.where(valid, r, 0.0), **opts)
    den = ndimage.gaussian_filter(valid.astype(np.float64), **opts)
    with np.errstate(invalid="ignore", divide="ignore"):
        fill = np.where(den > 1e-6, num / den, 0.0)
    return np.where(valid, r, fill)


def _gain(shape: tuple[int, int], offset: tuple[int, int], full: tuple[int, int], detail: float,
          dx: float, dy: float) -> np.ndarray:  # fmt: skip
    """``|k|^alpha`` of the DCT coefficients of a block at ``offset`` in a ``full`` grid."""
    (h, w), (r0, c0), (fh, fw) = shape, offset, full
    ky = np.pi * np.arange(r0, r0 + h) / (fh * float(dy))
    kx = np.pi * np.arange(c0, c0 + w) / (fw * float(dx))
    return (ky[:, None] ** 2 + kx[None, :] ** 2) ** (detail / 2.0)


def _dct_rows(a: np.ndarray, inverse: bool = False) -> np.ndarray:
    from scipy import fft as _fft

    f = _fft.idct if inverse else _fft.dct
    return f(a, type=2, axis=1, norm="ortho", workers=-1)


def _texture_cols(a: np.ndarray, detail: float, dx: float, dy: float, full, block_info=None):
    """The column transform, the gain and the inverse column transform of a block of whole
    columns (the middle of the separable filter)."""
    from scipy import fft as _fft

    c0 = 0 if block_info is None else block_info[0]["array-location"][1][0]
    spectrum = _fft.dct(a, type=2, axis=0, norm="ortho", workers=-1)
    spectrum *= _gain(a.shape, (0, c0), full, detail, dx, dy)
    return _fft.idct(spectrum, type=2, axis=0, norm="ortho", workers=-1)


def texture_shade(
    heights: np.ndarray,
    *,
    detail: float = TEXTURE_DETAIL,
    dx: float = 1.0,
    dy: float = 1.0,
    z_factor: float = 1.0,
    mask: np.ndarray | None = None,
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

    The least-squares plane through the data is taken away first (the fractional Laplacian of
    a plane is zero), and the rest is extended by mirroring it at the grid's edges (a
    discrete cosine transform, DCT-II, in place of the reference's zero padding): the edges
    get neither a cliff nor, from the terrain's overall tilt, a crease, and ``cos(pi m (row +
    1/2) / H) cos(pi n (col + 1/2) / W)`` (``m, n >= 1``) is an exact eigenfunction. Nodata
    cells are filled for the transform with the Gaussian-weighted mean (sigma 4 cells) of the
    data within 16 cells, and with the plane beyond.

    On a dask array the result is the in-memory one bit for bit and the grid is never in
    memory at once: one pass fits the plane (row by row), the fill runs chunk by chunk with a
    16-cell halo, and the separable transform runs over blocks of whole rows, then of whole
    columns, then of whole rows again (a row or column of the grid must fit in memory).

    Parameters
    ----------
    heights : (H, W) array or dask array
        Heights; NaN and +-inf are nodata (NaN in the result).
    detail : float in [0, 2], default: 0.5
        ``alpha``, Brown's detail.
    dx, dy : float > 0, default: 1
        Cell size east-west and north-south.
    z_factor : float, default: 1
        Vertical exaggeration (the result scales with it).
    mask : (H, W) bool, optional
        False marks nodata cells.

    Returns
    -------
    (H, W) float32
        In height units per (unit of ``dx``)^alpha; NaN at nodata. Mean zero over the grid
        for ``alpha > 0``.

    Raises
    ------
    InputError
        ``heights`` not a 2-D real array, ``mask`` of another shape, ``detail`` outside
        [0, 2], a bad cell size or ``z_factor``.

    References
    ----------
    .. [1] Brown, L. (2010). A new technique for depicting terrain relief. NACIS Annual
       Meeting, St. Petersburg, Florida (texture shading).
    """
    detail = _validate.finite(detail, "detail")
    if not 0.0 <= detail <= 2.0:
        raise InputError(f"detail: expected a texture detail alpha in [0, 2], got {detail!r}")
    if _chunks.any_dask(heights, mask):
        return _lazy_texture(heights, mask, detail, dx, dy, z_factor)
    z = float32_heights(check_grid(heights, dx, dy, z_factor), mask)
    if z.size == 0:
        return z.copy()
    if detail == 0:  # (-Laplacian)^0: the heights themselves
        return (z * np.float32(z_factor)).astype(np.float32)
    # float64 through the transforms: a float32 DCT of heights of thousands of metres loses
    # the small waves the filter is for. The plane's gain is 0^alpha = 0: it is taken away.
    coef = _plane_coefficients(_row_sums(z))
    r = _fill_residual((z - _plane(z.shape, coef)) * float(z_factor))
    out = _dct_rows(_texture_cols(_dct_rows(r), detail, dx, dy, z.shape), inverse=True)
    out = out.astype(np.float32)
    out[np.isnan(z)] = np.nan
    return out


def _lazy_texture(heights, mask, detail: float, dx: float, dy: float, z_factor: float):
    """:func:`texture_shade` of dask heights, bit for bit the in-memory result: one pass for
    the plane (row sums of blocks of whole rows), then the fill chunk by chunk with its halo,
    and the separable transform as passes over blocks of whole rows and whole columns."""
    import dask.array as da

    texture_shade(np.zeros((3, 3), np.float32), detail=detail, dx=dx, dy=dy, z_factor=z_factor)
    z = _chunks.map_stencil(
        lambda heights, mask=None: float32_heights(np.asarray(heights), mask),
        {"heights": heights, "mask": mask}, halo=0,
    )  # fmt: skip
    chunks = z.chunks
    shape = z.shape
    if detail == 0:
        return (z * np.float32(z_factor)).astype(np.float32)
    rows = z.rechunk({1: -1})
    sums = da.map_blocks(_row_sums, rows, dtype=np.float64, chunks=(rows.chunks[0], (5,)))
    coef = _plane_coefficients(np.asarray(sums.compute()))
    plane = _plane(shape, coef, chunks)
    resid = (z.astype(np.float64) - plane) * float(z_factor)
    filled = _chunks.map_stencil(
        lambda r: _fill_residual(np.asarray(r)), {"r": resid}, halo=FILL_RADIUS,
        dtype=np.float64,
    )  # fmt: skip
    step = filled.rechunk({1: -1}).map_blocks(_dct_rows, dtype=np.float64)
    step = step.rechunk({0: -1}).map_blocks(_texture_cols, detail, dx, dy, shape, dtype=np.float64)
    out = step.rechunk({1: -1}).map_blocks(_dct_rows, True, dtype=np.float64)
    out = out.rechunk(chunks).astype(np.float32)
    return da.where(da.isnan(z), np.float32(np.nan), out)


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
