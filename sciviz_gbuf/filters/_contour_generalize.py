"""Cartographic generalisation of contour lines: a height-aware smoothing of the field before
the lines are drawn, and the removal of small rings after (used by :mod:`.contours`).

Smoothing. A level's position is steady where the ground is steep (the line moves
``noise / g`` px for a height noise ``noise``, small when the gradient ``g`` is large) and
wanders where it is flat: there integer-metre terraces and sensor noise make the level cross
the ground many times, which draws specks and dashes. So the field is smoothed by a Gaussian
whose width follows the local line spacing ``s = interval / g`` (in pixels, Eq. 9 units):
``sigma = clip(SIGMA_PER_PX * (s - STEEP_SPACING), 0, SIGMA_MAX)``. Where lines are at most
``STEEP_SPACING`` px apart nothing changes; on flat ground the field is averaged over up to
``SIGMA_MAX`` px, but the smoothed value is kept within ``DISPLACE_MAX * g`` of the height
(a tolerance band, as in line simplification), so no line moves more than ``DISPLACE_MAX``
= 0.6 px from the exact one (about the exact lines' own agreement with ``gdal_contour``):
the smoothing straightens the wiggles of a level that crosses gentle ground and the ring
opening below removes the specks. The per-pixel sigma blends the field smoothed at the fixed
widths ``SIGMAS`` (linearly between the two around it), so the work is a few separable
filters. ``g`` is taken
from the field smoothed at ``SIGMA_SLOPE``, so noise does not pass for slope.

Each smoothed value is a local linear (not constant) weighted fit over the valid cells
(Gaussian-weighted least squares of ``z ~ a + b x + c y``, the value ``a``), so a plane stays
the same plane up to nodata holes and the grid edge: holes and borders neither bend nor
shift a line. Inside the data it is the ordinary Gaussian smoothing.

Rings. After drawing, rings too small to read and the specks of a level grazing flat ground
are removed by an attribute opening of the ink (Vincent 1993): a pixel keeps its ink only up
to the highest level ``T`` at which its 8-connected component of ``ink >= T`` is large, a
bounding box more than ``min_ring`` px on its longer side; a component that touches the
grid's edge or a nodata cell is an open line cut short, not a ring, and is large unless it is
at most one widest line width long (a stub). At the lowest ink this is Canny's hysteresis (a
line whose ink dips where the level is noisy stays one line instead of breaking into short
dashes that the size rule would remove); at every higher level it is the same rule, so no
threshold of the ink shows short dashes either: a minor line that fades where lines crowd
(Eq. 15) keeps the ink of its faintest link along the whole piece instead of breaking into
dark fragments, and isolated specks go whatever their ink. Real summits and pits whose rings
are wider than ``min_ring`` stay.

Both steps are local: the smoothing reads ``SMOOTH_RADIUS`` cells, and whether a component
is at most ``min_ring`` px wide is decided within ``min_ring`` cells of it (a component seen
through a window ``min_ring`` cells wider than the part it keeps is either whole, or reaches
the window's edge and so is wider than ``min_ring``). Chunked evaluation with a halo of
``RADIUS + SMOOTH_RADIUS + min_ring`` gives the same pixels as in memory.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np

from ..core.bands import run_bands, threads
from . import _contour_kernels as _k
from . import _smooth_kernels as _sk

#: Line spacing (px) up to which the field is left as it is: steep ground keeps exact lines.
STEEP_SPACING = 3.0
#: Growth of the smoothing width with the line spacing beyond that (px of sigma per px).
SIGMA_PER_PX = 0.25
#: The fixed smoothing widths (px) blended per pixel; 0 is the field itself.
SIGMAS = (0.0, 1.0, 2.0, 4.0)
SIGMA_MAX = SIGMAS[-1]
#: The most a smoothed line may move from the exact line (px): a tolerance band, as in line
#: simplification (:func:`tolerance_band`).
DISPLACE_MAX = 0.6
#: Smoothing of the field whose gradient decides the local spacing.
SIGMA_SLOPE = 1.0
#: The least smoothing of the gradient that sets line widths and the crowding fade.
SIGMA_GRADIENT = 1.0
#: Gaussians are cut at this many sigmas.
TRUNCATE = 3.0
#: Cells read by the smoothing around each output cell.
SMOOTH_RADIUS = math.ceil(TRUNCATE * SIGMA_MAX)
#: Ink above which pixels take part in the opening (the low threshold of the hysteresis): any.
LOW_INK = 0.0


def _kernels(sigma: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gaussian weights ``G(d)``, ``G(d) d`` and ``G(d) d^2`` for offsets ``d`` in cells."""
    r = math.ceil(TRUNCATE * sigma)
    d = np.arange(-r, r + 1, dtype=np.float64)
    g = np.exp(-0.5 * (d / sigma) ** 2)
    g /= g.sum()
    return g, g * d, g * d * d


def _pass(a: np.ndarray, w: np.ndarray, axis: int) -> np.ndarray:
    # Outside the grid counts as no data (weight 0), like a nodata cell: the same rule at the
    # grid's edge as at a chunk cut by the grid's edge.
    from scipy import ndimage  # the references only: not imported by a map

    return ndimage.correlate1d(a, w, axis=axis, mode="constant", cval=0.0)


def local_linear(z: np.ndarray, valid: np.ndarray, sigma: float):
    """``(a, b, c)``: at each cell the Gaussian-weighted least-squares plane
    ``a + b dx + c dy`` of the valid cells around it (offsets in cells, x = column, y = row);
    where fewer than three cells span a plane, the weighted mean and no slope. The numba
    kernel (:func:`._smooth_kernels.local_linear_kernel`); :func:`local_linear_reference`
    is the same with scipy's passes."""
    g, gd, gdd = _kernels(sigma)
    return _sk.local_linear_kernel(z, valid, g, gd, gdd, sigma)


def local_linear_reference(z: np.ndarray, valid: np.ndarray, sigma: float):
    """:func:`local_linear` by fourteen ``scipy.ndimage.correlate1d`` passes over the grid
    (the plain statement the kernel is tested against)."""
    v = valid.astype(np.float64)
    vz = np.where(valid, z, 0.0).astype(np.float64)
    g, gd, gdd = _kernels(sigma)
    # x passes, then y passes of the moments of v and v z.
    v0, v1, v2 = (_pass(v, k, 1) for k in (g, gd, gdd))
    z0, z1 = (_pass(vz, k, 1) for k in (g, gd))
    m0, my, myy = (_pass(v0, k, 0) for k in (g, gd, gdd))
    mx, mxy = (_pass(v1, k, 0) for k in (g, gd))
    mxx = _pass(v2, g, 0)
    mz, myz = (_pass(z0, k, 0) for k in (g, gd))
    mxz = _pass(z1, g, 0)
    # Solve [[m0 mx my] [mx mxx mxy] [my mxy myy]] (a b c) = (mz mxz myz) by Cramer's rule.
    c00 = mxx * myy - mxy * mxy
    c01 = mxy * my - mx * myy
    c02 = mx * mxy - mxx * my
    det = m0 * c00 + mx * c01 + my * c02
    c11 = m0 * myy - my * my
    c12 = mx * my - m0 * mxy
    c22 = m0 * mxx - mx * mx
    with np.errstate(divide="ignore", invalid="ignore"):
        # a plane needs a spread of cells: det relative to m0^3 sigma^4 (a full window ~ 1)
        ok = det > 1e-3 * m0**3 * sigma**4
        inv = np.where(ok, 1.0 / det, 0.0)
        a = np.where(ok, (c00 * mz + c01 * mxz + c02 * myz) * inv, mz / m0)
        b = (c01 * mz + c11 * mxz + c12 * myz) * inv
        c = (c02 * mz + c12 * mxz + c22 * myz) * inv
    return a, b, c


#: Rows and columns smoothed at a time (a tile, read with ``SMOOTH_RADIUS`` cells around
#: it): the fits keep ~25 float64 arrays of a tile, and the y-passes of one of its rows read
#: ``2 SMOOTH_RADIUS + 1`` rows of the x-passes, 0.4 MB that stay in a core's cache.
STRIP_ROWS = 256
TILE_COLS = 512
#: Columns of a tile of the ring opening (its rows: ``STRIP_ROWS``).
RING_TILE_COLS = 256


def smooth_field(
    z: np.ndarray, valid: np.ndarray, interval: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`smooth_strip` tile by tile of ``STRIP_ROWS`` x ``TILE_COLS`` cells, each read
    with ``SMOOTH_RADIUS`` cells around it (the same values as in one piece: a cell's fits
    depend on its window alone), the tiles shared out to the cores as they finish (each core
    with one working memory; fresh memory costs more to touch than the sums)."""
    h, w = z.shape
    r = SMOOTH_RADIUS
    if h <= STRIP_ROWS + 2 * r and w <= TILE_COLS + 2 * r:
        return smooth_strip(z, valid, interval)
    out = np.empty(z.shape, np.float32)
    grad = np.empty(z.shape, np.float32)
    # the cells within r of the grid's sides in tiles of their own, so that every other tile
    # can have full windows (the fused route)
    tiles = [(a, b, c, d) for a, b in _cuts(h, r, STRIP_ROWS) for c, d in _cuts(w, r, TILE_COLS)]
    following = itertools.count()  # next() is atomic: each tile is taken once
    size = 14 * min(h, STRIP_ROWS + 2 * r) * min(w, TILE_COLS + 2 * r)

    def smooth_tiles(_k0: int, _k1: int) -> None:
        work = np.empty(size, np.float64)
        while (k := next(following)) < len(tiles):
            a, b, c, d = tiles[k]
            lo, hi = max(0, a - r), min(h, b + r)
            cl, ch = max(0, c - r), min(w, d + r)
            inner = (a - lo, b - lo, c - cl, d - cl)
            into = (out[a:b, c:d], grad[a:b, c:d])
            smooth_strip(z[lo:hi, cl:ch], valid[lo:hi, cl:ch], interval, work=work,
                         serial=True, inner=inner, into=into)  # fmt: skip

    # one band per core, each taking the next tile (the kernels release the GIL)
    run_bands(smooth_tiles, threads(), min_items=1)
    return out, grad


def _cuts(n: int, r: int, step: int) -> list[tuple[int, int]]:
    """``[lo, hi)`` pieces of ``range(n)``: the first and last ``r`` on their own, the rest
    in pieces of at most ``step`` (a grid too short for that: pieces of ``step``)."""
    if n <= 2 * r + 1:
        return [(a, min(a + step, n)) for a in range(0, n, step)]
    inner = [(a, min(a + step, n - r)) for a in range(r, n - r, step)]
    return [(0, r), *inner, (n - r, n)]


def smooth_strip(
    z: np.ndarray, valid: np.ndarray, interval: float, work: np.ndarray | None = None,
    serial: bool = False, inner: tuple[int, int, int, int] | None = None,
    into: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The field smoothed as the local line spacing ``interval / g`` asks (module docstring)
    and its gradient magnitude (per cell), both float32 and NaN where not ``valid``.

    The gradient is that of the same blend of fits but at least ``SIGMA_GRADIENT`` wide: it
    sets the lines' widths and where minors fade for crowding (Eq. 15), and a gradient that
    flickers with the height noise of steep ground would make the fade flicker into dashes
    (positions are those of the field alone, so they do not move).

    The fits by :func:`local_linear`, then the blend, the tolerance band and the flat test in
    one pass per cell (:func:`._smooth_kernels.blend_kernel`); the same values as
    :func:`smooth_strip_reference`, the array statement (tested bit for bit). ``work``: an
    optional flat float64 buffer of at least ``14 H W`` to compute in; ``serial``: on the
    calling thread only; ``inner``: with ``serial``, only the cells ``(r0, r1, c0, c1)``
    (rows, columns; the others are read), written into the arrays ``into`` if given."""
    z64 = np.ascontiguousarray(z, dtype=np.float64)
    if serial and inner is not None and FUSED_ROUTE and _fused_ok(valid, inner):
        return _smooth_fused(z64, inner, interval, into)
    n = z.size
    nfit = 3 * (len(SIGMAS) - 1)
    if work is None:
        work = np.empty((nfit + 5) * n, np.float64)
    fits = work[: nfit * n].reshape(nfit, *z.shape)
    h, w = z.shape
    r0, r1, c0, c1 = (0, h, 0, w) if inner is None else inner
    rows = (r0, r1) if serial and inner is not None else None
    cols = (c0, c1) if serial and inner is not None else None
    widest = SIGMA_MAX
    for k, s in enumerate(SIGMAS[1:]):
        if s > SIGMA_SLOPE and SIGMAS[k] >= widest:
            break  # no cell of the strip asks for this width (its fit would not be read)
        g, gd, gdd = _kernels(s)
        _sk.local_linear_kernel(z64, valid, g, gd, gdd, s, out=fits[3 * k : 3 * k + 3],
                                work=work[nfit * n :], serial=serial, rows=rows,
                                cols=cols)  # fmt: skip
        if s == SIGMA_SLOPE:
            widest = _widest_sigma(fits[3 * k + 1, r0:r1, c0:c1], fits[3 * k + 2, r0:r1, c0:c1],
                                   valid[r0:r1, c0:c1], interval)  # fmt: skip
    # the kernel blends the fits at the widths of SIGMAS = (0, 1, 2, 4), SIGMA_SLOPE = 1
    out, grad = (None, None) if into is None else into
    return _sk.blend_kernel(
        z64, valid, fits, interval, per_px=SIGMA_PER_PX, steep=STEEP_SPACING,
        sigma_max=SIGMA_MAX, sigma_grad=SIGMA_GRADIENT, displace=DISPLACE_MAX, serial=serial,
        inner=(r0, r1, c0, c1), out=out, grad=grad,
    )  # fmt: skip


#: Columns the fused route fits at a time: its rings of x-moments (8 + 16 + 32 rows of two
#: float64 moments) then take 230 KB, within a core's second-level cache.
FUSED_COLS = 256
#: Whether tiles of full windows take the fused route (benchmarks set it False to time the
#: separate kernels, the route of every other tile, in the same run).
FUSED_ROUTE = True


def _fused_ok(valid: np.ndarray, inner: tuple[int, int, int, int]) -> bool:
    """Whether every cell of ``inner`` has its widest window (``SMOOTH_RADIUS`` cells around
    it, which holds the blend's 3 x 3) inside the array and without nodata: then the fits'
    mask moments are those of a full window everywhere (:func:`_smooth_fused`)."""
    r0, r1, c0, c1 = inner
    r = SMOOTH_RADIUS
    h, w = valid.shape
    if r0 - r < 0 or c0 - r < 0 or r1 + r > h or c1 + r > w or r0 >= r1 or c0 >= c1:
        return False
    return bool(valid[r0 - r : r1 + r, c0 - r : c1 + r].all())


@functools.cache
def _fused_constants() -> tuple[list, np.ndarray, np.ndarray]:
    """The fused route's taps of widths 1, 2, 4, their full-window mask moments and
    ``1e-3 sigma^4``: the same for every tile, so taken once (the kernel only reads them; they
    stay writable arrays so that it keeps one compiled signature)."""
    taps = [_kernels(s) for s in SIGMAS[1:]]
    full = np.stack([_sk.full_moments(*k) for k in taps])
    s4 = np.array([1e-3 * s**4 for s in SIGMAS[1:]])
    return taps, full, s4


def _smooth_fused(
    z64: np.ndarray, inner: tuple[int, int, int, int], interval: float,
    into: tuple[np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`smooth_strip` of a tile whose cells all have full windows (:func:`_fused_ok`),
    by :func:`._smooth_kernels.fused_rows` (the same operations, so the same bits, without
    the moment and fit planes), ``FUSED_COLS`` columns at a time."""
    assert SIGMAS == (0.0, 1.0, 2.0, 4.0) and SIGMA_SLOPE == 1.0  # the kernel's widths
    r0, r1, c0, c1 = inner
    out, grad = (
        (np.empty((r1 - r0, c1 - c0), np.float32), np.empty((r1 - r0, c1 - c0), np.float32))
        if into is None
        else into
    )
    taps, full, s4 = _fused_constants()
    n = min(FUSED_COLS, c1 - c0)
    for a in range(c0, c1, n):
        b = min(a + n, c1)
        k = b - a
        if a == c0 or k != n:  # contiguous rows, for the vector loops
            rings = [np.empty((m, 2, k)) for m in (8, 16, 32)]  # >= 2 r + 1 rows of each
            acc, fit = np.empty((3, k)), np.empty((9, k))
        _sk.fused_rows(z64, r0, r1, a, b, taps[0][0], taps[0][1], taps[1][0], taps[1][1],
                       taps[2][0], taps[2][1], full, s4, float(interval), SIGMA_PER_PX,
                       STEEP_SPACING, SIGMA_MAX, SIGMA_GRADIENT, DISPLACE_MAX,
                       DISPLACE_MAX / math.sqrt(2.0), out[:, a - c0 : b - c0],
                       grad[:, a - c0 : b - c0], rings[0], rings[1], rings[2], acc,
                       fit)  # fmt: skip
    return out, grad


def _widest_sigma(b: np.ndarray, c: np.ndarray, valid: np.ndarray, interval: float) -> float:
    """The widest smoothing any valid cell asks for, from the slope fit ``(b, c)``: the
    width grows as the gradient falls, so it is that of the least gradient (as the blend
    kernel computes it)."""
    g = float(_sk.least_gradient(b, c, np.ascontiguousarray(valid, np.bool_)))
    if g == math.inf:  # no valid cell
        return 0.0
    g *= 1.0 - 1e-12  # a hair low: at worst a fit too many is computed, never too few
    spacing = interval / g if g > 0.0 else math.inf
    return min(max(SIGMA_PER_PX * (spacing - STEEP_SPACING), 0.0), SIGMA_MAX)


def smooth_strip_reference(
    z: np.ndarray, valid: np.ndarray, interval: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`smooth_strip` by numpy expressions over the strip (the plain statement of the
    blend, the tolerance band and the flat test that the kernel is tested against)."""
    z64 = z.astype(np.float64)
    fits = {s: local_linear(z64, valid, s) for s in SIGMAS[1:]}
    _, b, c = fits[SIGMA_SLOPE]  # one of SIGMAS
    g = np.sqrt(b * b + c * c)
    with np.errstate(divide="ignore", invalid="ignore"):
        spacing = np.where(g > 0, interval / g, np.inf)
    sigma = np.clip(SIGMA_PER_PX * (spacing - STEEP_SPACING), 0.0, SIGMA_MAX)
    sigma_g = np.maximum(sigma, SIGMA_GRADIENT)
    out = np.where(valid, z64, np.nan)
    gx = gy = np.zeros_like(out)
    lower = (out, gx, gy)
    for s0, s1 in itertools.pairwise(SIGMAS):
        upper = fits[s1]
        t = np.clip((sigma - s0) / (s1 - s0), 0.0, 1.0)
        out = np.where((sigma > s0) & (sigma <= s1), (1.0 - t) * lower[0] + t * upper[0], out)
        t = np.clip((sigma_g - s0) / (s1 - s0), 0.0, 1.0)
        here = (sigma_g > s0) & (sigma_g <= s1)
        gx = np.where(here, (1.0 - t) * lower[1] + t * upper[1], gx)
        gy = np.where(here, (1.0 - t) * lower[2] + t * upper[2], gy)
        lower = upper
    gm = np.sqrt(gx * gx + gy * gy)
    out = np.clip(out, *tolerance_band(z64, valid, DISPLACE_MAX))
    # Where the heights are exactly flat around a cell (a sea of exact zeros beside an island)
    # the exact field's gradient is 0, so no line is drawn there (a value equal to a level
    # counts as above it); the smoothed gradient would still reach there from the slope and
    # make a wide line flood the flat ground at its level: zero it, as for the exact field.
    from scipy import ndimage

    flat = ndimage.maximum_filter(np.where(valid, z64, -np.inf), 3) == ndimage.minimum_filter(
        np.where(valid, z64, np.inf), 3
    )
    gm = np.where(flat, 0.0, gm)
    out = np.where(valid, out, np.nan).astype(np.float32)
    return out, np.where(valid, gm, np.nan).astype(np.float32)


def tolerance_band(z: np.ndarray, valid: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)``: the range of the bilinear interpolant of ``z`` within ``r`` (< 1) cells
    of each cell centre, over the valid cells. A smoothed value in that range is a height the
    exact surface takes within ``r`` px, so the smoothed line through that cell lies within
    ``r`` px of the exact one. Along an axis the interpolant moves ``r (z_k - z)`` towards
    neighbour ``k``; towards a diagonal neighbour at most ``r / sqrt 2`` of the way (the
    bilinear patch's largest change along the diagonal at that distance)."""
    lo = z.copy()
    hi = z.copy()
    h, w = z.shape
    pad = np.pad(np.where(valid, z, np.nan), 1, constant_values=np.nan)
    for dr, dc in itertools.product((-1, 0, 1), repeat=2):
        if dr == dc == 0:
            continue
        k = r if dr == 0 or dc == 0 else r / math.sqrt(2.0)
        step = pad[1 + dr : 1 + dr + h, 1 + dc : 1 + dc + w] - z
        step = np.where(np.isfinite(step), k * step, 0.0)
        np.minimum(lo, z + step, out=lo)
        np.maximum(hi, z + step, out=hi)
    return lo, hi


def cut_cells(valid: np.ndarray) -> np.ndarray:
    """Cells where a piece counts as cut short rather than closed: the grid's edge and the
    cells next to one that is not ``valid`` (8-connected)."""
    valid = np.ascontiguousarray(valid, np.bool_)
    cut = np.empty(valid.shape, np.bool_)
    if valid.size:
        run_bands(_k.cut_rows, valid.shape[0], valid, cut)
    return cut


def drop_small_rings(
    ink: np.ndarray, min_ring: float, valid: np.ndarray, min_stub: float
) -> np.ndarray:
    """``ink`` without small rings and specks at any ink level: each pixel is lowered to the
    highest level ``T`` at which its 8-connected component of ``ink >= T`` is large, to 0 if
    it is small even at the lowest ink (an attribute opening, :func:`ring_opening`). Small:
    at most ``min_ring`` px on the longer side of its bounding box, or at most ``min_stub`` px
    if it touches the grid's edge or a cell that is not ``valid`` (a line that nodata or the
    edge cut short). So a speck goes whatever its ink, and a line whose ink fades in and out
    (crowded minors, a level grazing flat ground) keeps the ink it has along its whole length
    instead of breaking into short dark dashes at any visible threshold.

    Tiles of ``STRIP_ROWS`` x ``RING_TILE_COLS`` cells are read with ``ceil(min_ring) + 1``
    cells around them (a small component lies within ``min_ring`` cells of each of its
    pixels, and one cut by the tile's side is wider than that there): the same pixels as in
    one piece, memory for a tile (the union-find's lookups then stay in a core's cache)."""
    if min_ring <= 0:
        return ink
    ink = np.ascontiguousarray(ink, np.float32)
    cut = cut_cells(valid)
    h, w = ink.shape
    margin = math.ceil(min_ring) + 1
    if h <= STRIP_ROWS + 2 * margin and w <= RING_TILE_COLS + 2 * margin:
        return ring_opening(ink, cut, min_ring, min_stub)
    out = np.empty_like(ink)
    tiles = [(a, c) for a in range(0, h, STRIP_ROWS) for c in range(0, w, RING_TILE_COLS)]
    following = itertools.count()  # next() is atomic: each tile is taken once

    def open_tiles(_k0: int, _k1: int) -> None:
        while (k := next(following)) < len(tiles):
            a, c = tiles[k]
            b, d = min(a + STRIP_ROWS, h), min(c + RING_TILE_COLS, w)
            lo, hi = max(0, a - margin), min(h, b + margin)
            cl, ch = max(0, c - margin), min(w, d + margin)
            part = ring_opening(ink[lo:hi, cl:ch], cut[lo:hi, cl:ch], min_ring, min_stub)
            out[a:b, c:d] = part[a - lo : b - lo, c - cl : d - cl]

    # one band per core, each taking the next tile (the kernels release the GIL)
    run_bands(open_tiles, threads(), min_items=1)
    return out


def ring_opening(ink: np.ndarray, cut: np.ndarray, min_ring: float, min_stub: float) -> np.ndarray:
    """:func:`drop_small_rings` of one piece, ``cut`` the cells where a line counts as cut
    short (the kernel :func:`~._contour_kernels.ring_opening`)."""
    # by decreasing ink; ties in raster order (any order of ties gives the same opening); ink
    # above LOW_INK = 0 is inked (the kernel's rule). The arrays are as long as the image:
    # only the m entries used are touched.
    ink = np.ascontiguousarray(ink, np.float32)
    node = np.empty(ink.shape, np.int32)
    order = np.empty(ink.size, np.int32)
    m = _k.ink_order(ink.ravel().view(np.uint32), node.ravel(), order, np.empty(ink.size, np.int32),
                     np.empty((4, 257), np.int64))  # fmt: skip
    if m == 0:
        return np.zeros_like(ink)
    order = order[:m]
    out = np.empty(ink.shape, np.float32)
    _k.ring_opening(ink, node, order, np.ascontiguousarray(cut), np.float32(min_ring),
                    np.float32(min_stub), np.empty(m, np.int32), np.empty(m, np.int32),
                    np.empty(m, np.float32), np.empty(m, np.float32), np.empty((4, m), np.int32),
                    np.empty(m, np.bool_), np.empty(m, np.float32), out, np.empty(m, np.int32),
                    np.empty(m, np.int32))  # fmt: skip
    return out


def band_heights(
    z: np.ndarray, valid: np.ndarray, min_ring: float, *, base: float = 0.0, step: float = 1.0,
    edges: np.ndarray | None = None,
) -> np.ndarray:  # fmt: skip
    """Heights for colour bands that agree with generalised contour lines: ``z`` where every
    band island, an 8-connected piece of one band (``floor((z - base) / step)`` in float32,
    or with ``edges`` the number of edges <= ``z``) whose
    bounding box is at most ``min_ring`` px on its longer side and which touches neither the
    grid's edge nor a cell that is not ``valid``, takes the height of the nearest valid cell
    outside the islands, so the islands whose rings the lines drop (:func:`drop_small_rings`)
    are not left as specks of colour. Elsewhere the heights are kept: their band edges are
    the exact lines, which the generalised lines follow within ``DISPLACE_MAX`` px, under a
    line's width. Float32, NaN where not ``valid``.

    The islands by run-length labelling, the nearest cells by a search within
    ``m = ceil(min_ring) + 1`` cells (:func:`~._contour_kernels.small_islands`,
    :func:`~._contour_kernels.fill_from_nearest`; :func:`band_heights_reference` is the
    statement with ``scipy.ndimage``). An island lies within ``min_ring`` cells of each of its
    cells, so a cell's island and the cells it is filled from are decided within ``2 m``
    cells: row strips (bounded memory) and chunks read with that halo give the same cells
    as one piece. (A chain of touching islands of several bands wider than ``m`` keeps the
    heights of cells farther than ``m`` from the cells around it.)"""
    s = np.where(valid, z, np.nan).astype(np.float32)
    if min_ring <= 0 or not valid.any():
        return s
    h = s.shape[0]
    m = math.ceil(min_ring) + 1
    halo = 2 * m
    spec = (
        np.float32(base),
        np.float32(step),
        np.empty(0) if edges is None else np.ascontiguousarray(edges, np.float64),
    )
    valid = np.ascontiguousarray(valid, bool)
    if h <= STRIP_ROWS + 2 * halo:
        return _band_strip(s, valid, spec, min_ring, m, 0, h)
    out = np.empty_like(s)

    def strips(k0: int, k1: int) -> None:
        small = np.zeros((STRIP_ROWS + 2 * halo, s.shape[1]), bool)
        for a in range(k0 * STRIP_ROWS, min(k1 * STRIP_ROWS, h), STRIP_ROWS):
            b = min(a + STRIP_ROWS, h)
            lo, hi = max(0, a - halo), min(h, b + halo)
            _band_strip(s[lo:hi], valid[lo:hi], spec, min_ring, m, a - lo, b - lo,
                        small=small[: hi - lo], out=out[a:b])  # fmt: skip

    # strips at once on every core (the kernels release the GIL; each writes its own rows)
    run_bands(strips, -(-h // STRIP_ROWS), min_items=1)
    return out


def _band_strip(
    s: np.ndarray, valid: np.ndarray, spec: tuple, min_ring: float, m: int, r0: int, r1: int,
    small: np.ndarray | None = None, out: np.ndarray | None = None,
) -> np.ndarray:  # fmt: skip
    """Rows ``r0 .. r1`` of :func:`band_heights` of a strip (its first and last rows count
    as cut, like the grid's edge); ``small`` and ``out`` optional working and output arrays."""
    if small is None:
        small = np.zeros(s.shape, bool)
    else:
        small[...] = False
    small_islands(s, valid, spec, min_ring, small)
    if out is None:
        out = np.empty((r1 - r0, s.shape[1]), np.float32)
    _k.fill_from_nearest(s, small, valid, m, r0, r1, out)
    return out


def small_islands(
    s: np.ndarray, valid: np.ndarray, spec: tuple, min_ring: float, small: np.ndarray
) -> None:
    """Mark the band islands of ``s`` in ``small`` (:func:`~._contour_kernels.small_islands`
    over the runs of :func:`~._contour_kernels.band_runs`); ``spec``: ``(base, step, edges)``
    as float32, float32 and float64 (no edges: bands every ``step`` from ``base``)."""
    h = s.shape[0]
    none = np.empty(0, np.int32)
    n = _k.band_runs(s, valid, *spec, False, none, none, none, np.empty(0, np.int64), none)
    rrow, rc0, rc1 = (np.empty(n, np.int32) for _ in range(3))
    rband = np.empty(n, np.int64)
    first = np.empty(h + 1, np.int32)
    _k.band_runs(s, valid, *spec, True, rrow, rc0, rc1, rband, first)
    _k.small_islands(valid, rrow, rc0, rc1, rband, first, np.float32(min_ring), small,
                     np.empty(n, np.int32), np.empty((4, n), np.int32),
                     np.empty(n, np.bool_))  # fmt: skip


def band_heights_reference(
    z: np.ndarray, valid: np.ndarray, band_index, min_ring: float
) -> np.ndarray:
    """:func:`band_heights` with ``scipy.ndimage``: a labelling of the whole grid per band and
    the nearest cell by the Euclidean distance transform (ties and chains of islands aside,
    the same cells; the tests compare them)."""
    from scipy import ndimage

    s = np.where(valid, z, np.nan).astype(np.float32)
    if min_ring <= 0 or not valid.any():
        return s
    band = np.where(valid, band_index(np.where(valid, s, 0.0)), np.iinfo(np.int64).min)
    eight = np.ones((3, 3), bool)
    cut = cut_cells(valid)
    small = np.zeros(s.shape, bool)
    for v in np.unique(band[valid]):
        labels, _ = ndimage.label(band == v, structure=eight)
        boxes = ndimage.find_objects(labels)
        extent = np.array([max(b[0].stop - b[0].start, b[1].stop - b[1].start) for b in boxes])
        island = np.concatenate([[False], extent <= min_ring])
        island[np.unique(labels[cut])] = False
        if island.any():
            small |= island[labels]
    if small.any():
        _, (ri, ci) = ndimage.distance_transform_edt(small, return_indices=True)
        s[small] = s[ri[small], ci[small]]
    return s
