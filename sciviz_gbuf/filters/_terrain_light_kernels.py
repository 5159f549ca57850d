"""Numba kernels of :mod:`sciviz_gbuf.filters.terrain_light`: horizons along sun and sky rays.

Two statements of the sky rays (sky view, openness):

- :func:`_horizon_tan` marches one cell's ray (per-cell, float64, with bounds that end the
  march early): :func:`sky_view_reference_kernel`, :func:`openness_reference_kernel`, and
  the cast shadows.
- :func:`_horizon_row` marches the rays of a whole row of cells at once (in blocks of
  ``MARCH_BLOCK`` cells that stay in cache, each through all its steps). A step ``k`` of
  direction ``d`` puts every cell's sample at the same offset from it, with the same
  interpolation weight (the weight comes from the offset alone, :func:`_sample`), so the step
  is one loop over the block reading one or two shifted rows of the grid: a float32 loop LLVM
  vectorises. Same samples, same bounds; float32 instead of float64, so the sky-view factor
  agrees with the per-cell march within 1e-6 and openness within 1e-4 degrees (tested).
  :func:`sky_view_kernel` and :func:`openness_kernel` take four steps in one loop
  (:func:`_fused4`), the same samples and float32 expressions, so the same values bit for bit
  as the one-step march (:func:`sky_view_march_kernel`, :func:`openness_march_kernel`, kept
  as the reference; tested). The one-step loop's ``best[j] = t if t > best[j] else best[j]``
  stores only where a sample raises the maximum, and the LLVM of llvmlite 0.50 (numba
  0.68) vectorises it with masked stores (``vmaskmovps``), microcoded on AMD Zen: ~1.7 cycles a
  sample in a loop over L1-resident rows, against ~0.3 for the fused loop, which keeps the
  maximum in a register over its four samples and stores it unconditionally. About 3 x the
  one-step march (docs/performance.md).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.bands import run_bands
from ._hillshade_kernels import atan_pos as _atan_pos


@njit(cache=True, inline="always")
def _sample(start: int, offset: float, n: int) -> tuple[int, float]:
    """Cell and interpolation weight of a ray sample ``offset`` cells from cell ``start`` along
    an axis of ``n`` cells. The weight comes from the offset alone, not from ``start + offset``,
    so it is the same wherever the ray starts: a chunk of the grid (out-of-core evaluation)
    samples exactly as the whole grid. The clamps absorb rounding of samples that land on the
    first or last cell."""
    b = math.floor(offset)
    f = offset - b
    c = start + int(b)
    if c < 0:
        return 0, 0.0
    if c >= n - 1:
        return n - 1, 0.0
    return c, f


@njit(cache=True, inline="always")
def _horizon_tan(
    z: np.ndarray,
    i: int,
    j: int,
    d_row: float,
    d_col: float,
    step_len: float,
    row_ub: np.ndarray,
    rw: int,
    col_ub: np.ndarray,
    cw: int,
    cell_ub: float,
    floor_tan: float,
    stop_tan: float,
    max_steps: int,
) -> float:
    """Largest ``(height - z[i, j]) / distance`` over the samples of a ray, at least ``floor_tan``.

    The ray starts at cell (i, j) and moves ``(d_row, d_col)`` cells per step (one of them is
    +-1), ``step_len`` metres per step. It stops at the grid edge, after ``max_steps`` steps, as
    soon as the result reaches ``stop_tan`` or when no cell ahead could raise it: ``row_ub[rw, r]``
    and ``col_ub[cw, c]`` bound the heights of all rows / columns from r / c onwards in the ray's
    direction (see :func:`_bounds`), ``cell_ub`` bounds all the ray's samples. (Rows of 2-D
    arrays rather than 1-D slices: a slice per ray costs atomic reference counting, which
    threads contend for.) Samples that touch a NaN cell are
    skipped: nodata never blocks.
    """
    h, w = z.shape
    z0 = np.float64(z[i, j])
    best = floor_tan
    # the number of steps inside the grid, up front: no bounds checks in the loop. The 1e-9 and
    # the clamps below absorb rounding of positions that land exactly on the last row/column.
    if abs(d_row) == 1.0:
        di = int(d_row)
        n_in = h - 1 - i if di > 0 else i
        if d_col > 0.0:
            n_in = min(n_in, int((w - 1 - j) / d_col + 1e-9))
        elif d_col < 0.0:
            n_in = min(n_in, int(j / -d_col + 1e-9))
        n_k = min(n_in, max_steps)
        far = n_k * step_len
        for k in range(1, n_k + 1):
            dist = k * step_len
            r = i + k * di
            c0, f = _sample(j, k * d_col, w)
            # all later samples are at most this high: once the ray clears it, nothing can
            # block. Below the horizontal (best < 0) a sample further out needs less rise to
            # raise the horizon, so the test takes the farthest one.
            if min(row_ub[rw, r], col_ub[cw, c0], cell_ub) - z0 <= best * (
                dist if best >= 0.0 else far
            ):
                break
            a = z[r, c0]
            v = a + f * (z[r, c0 + 1] - a) if f > 0.0 else a
            rise = v - z0  # NaN (nodata) compares False: not blocking
            if rise > best * dist:
                best = rise / dist
                if best >= stop_tan:
                    break
    else:
        dj = int(d_col)
        n_in = w - 1 - j if dj > 0 else j
        if d_row > 0.0:
            n_in = min(n_in, int((h - 1 - i) / d_row + 1e-9))
        elif d_row < 0.0:
            n_in = min(n_in, int(i / -d_row + 1e-9))
        n_k = min(n_in, max_steps)
        far = n_k * step_len
        for k in range(1, n_k + 1):
            dist = k * step_len
            c = j + k * dj
            r0, f = _sample(i, k * d_row, h)
            if min(row_ub[rw, r0], col_ub[cw, c], cell_ub) - z0 <= best * (
                dist if best >= 0.0 else far
            ):
                break
            a = z[r0, c]
            v = a + f * (z[r0 + 1, c] - a) if f > 0.0 else a
            rise = v - z0
            if rise > best * dist:
                best = rise / dist
                if best >= stop_tan:
                    break
    return best


def shadow_kernel(
    z: np.ndarray,
    d_row: float,
    d_col: float,
    step_len: float,
    row_ub: np.ndarray,
    rw: int,
    col_ub: np.ndarray,
    cw: int,
    altitude: float,
    sun_radius: float,
) -> np.ndarray:
    h, w = z.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    run_bands(
        _shadow_rows, h, z, d_row, d_col, step_len, row_ub, rw, col_ub, cw, altitude, sun_radius,
        out,
    )  # fmt: skip
    return out


# error_model="numpy" in the band kernels, as numba compiled the prange loop bodies they
# replace: a division by zero gives inf / NaN, it does not raise.
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _shadow_rows(
    i0: int,
    i1: int,
    z: np.ndarray,
    d_row: float,
    d_col: float,
    step_len: float,
    row_ub: np.ndarray,
    rw: int,
    col_ub: np.ndarray,
    cw: int,
    altitude: float,
    sun_radius: float,
    out: np.ndarray,
) -> None:
    """Rows ``i0 .. i1`` of :func:`shadow_kernel` into ``out`` (one band of :func:`.run_bands`)."""
    h, w = z.shape
    floor_tan = math.tan(math.radians(altitude - sun_radius))
    stop_tan = math.tan(math.radians(altitude + sun_radius)) if sun_radius > 0.0 else floor_tan
    alt = math.radians(altitude)
    rad = math.radians(sun_radius)
    max_steps = h + w
    for i in range(i0, i1):
        for j in range(w):
            if np.isnan(z[i, j]):
                continue
            t = _horizon_tan(
                z,
                i,
                j,
                d_row,
                d_col,
                step_len,
                row_ub,
                rw,
                col_ub,
                cw,
                np.inf,
                floor_tan,
                stop_tan,
                max_steps,
            )
            if sun_radius == 0.0:
                out[i, j] = 1.0 if t <= floor_tan else 0.0
            else:
                # share of the sun disc above a straight horizon at elevation atan(t)
                s = min(max((math.atan(t) - alt) / rad, -1.0), 1.0)
                out[i, j] = (math.acos(s) - s * math.sqrt(1.0 - s * s)) / math.pi


#: "No terrain" in the sweep's shadow surface: finite, so interpolating it with a height
#: stays far below any terrain instead of giving NaN (-inf + inf).
_NOTHING = -1e300


def shadow_sweep_kernel(
    z: np.ndarray, d_row: float, d_col: float, step_len: float, altitude: float
) -> np.ndarray:
    """Hard shadows of ``z`` by one sweep away from the sun (the rays of
    :func:`shadow_kernel`: ``(d_row, d_col)`` cells a step, one of them +-1).

    Every ray towards the sun lies on a straight line of the grid's family ``column = u +
    row e`` (rows-major rays, ``e`` columns a row; the same with rows and columns swapped).
    The sweep keeps, for the lines at integer ``u``, the *shadow surface* ``S_u``: the
    highest of the heights sampled along the line so far (interpolated across the row, as
    the march samples) less ``tan(altitude)`` times their distance. Row by row from the side
    of the sun, a cell is shadowed where the surface of its own line passes above it; then
    the row's samples join the lines and every surface drops by one step. A cell on an
    integer line (rays along the rows, the columns, or with square cells the diagonals) is
    tested against exactly the march's samples. A cell between two lines gets the
    interpolation of their two surfaces: each carries its line's highest sample undamped to
    any distance, so shadows keep their length; their sides move by up to about a cell
    (tested against the march). O(1) per cell, whatever the shadows' length."""
    h, w = z.shape
    out = np.empty((h, w), dtype=np.float32)
    # float64 surfaces: a ray that grazes a cell (a 45-degree sun over integer heights) must
    # fall on the side the march's float64 comparison puts it
    drop = math.tan(math.radians(altitude)) * step_len
    if abs(d_row) == 1.0:  # lines across rows
        e = float(d_row) * float(d_col)  # columns per row away from row 0
        s = np.empty(_n_lines(h, w, e))
        _shadow_sweep_rows(z, int(d_row), e, drop, out, s)
    else:  # lines across columns, the columns swept in strips copied into row buffers
        e = float(d_col) * float(d_row)
        s = np.empty(_n_lines(w, h, e))
        zt = np.empty((_STRIP, h + _PAD), z.dtype)
        lt = np.empty((_STRIP, h + _PAD), np.float32)
        _shadow_sweep_cols(z, int(d_col), e, drop, out, s, zt, lt)
    return out


def _n_lines(n_steps: int, n: int, e: float) -> int:
    """Lines ``u`` of the family ``x = u + k e`` (k = 0 .. n_steps - 1) that cross a line of
    ``n`` cells, with a margin for interpolation."""
    return n + math.ceil(abs(e) * (n_steps - 1)) + 3


#: Columns copied at a time by the column sweep, into rows padded by a few cells: rows a
#: power of two apart map to the same cache set, and the copy touches all of them at once.
_STRIP, _PAD = 64, 16


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sweep_line(zi: np.ndarray, k: int, e: float, u0: int, s: np.ndarray, oi: np.ndarray,
                drop: float) -> None:  # fmt: skip
    """Line ``k`` of cells (``k = i`` for the grid's row i) of the sweep: the cells tested
    against the surfaces ``s`` of the lines through them (``s[L]`` is line ``u = L + u0``),
    then the cells' heights join the lines, then the surfaces drop one step."""
    n = zi.shape[0]
    p = k * e  # line u crosses this line of cells at x = u + p
    fl = math.floor(p)
    phi = p - fl
    # the cell j lies on line u = j - p: between lines a = j - fl - 1 and a + 1 (weight g)
    if phi > 0.0:
        g = 1.0 - phi
        base = -fl - 1 - u0
        _sweep_query(s[base : base + n], s[base + 1 : base + 1 + n], g, zi, oi)
    else:
        base = -fl - u0
        _sweep_query(s[base : base + n], s[base : base + n], 0.0, zi, oi)
    # lines whose crossing (and its interpolation neighbour) lies inside: x = L + u0 + fl + phi
    c_lo = 0
    c_hi = n - 1 if phi > 0.0 else n  # cells c with c + 1 <= n - 1 when interpolating
    off = u0 + fl  # cell c = L + off
    la = c_lo - off
    lb = c_hi - off
    if phi > 0.0:
        _sweep_join_lerp(zi[c_lo:c_hi], zi[c_lo + 1 : c_hi + 1], phi, s[la:lb])
    else:
        _sweep_join(zi[c_lo:c_hi], s[la:lb])
    _sweep_drop(s, drop)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sweep_query(a: np.ndarray, b: np.ndarray, g: float, zi: np.ndarray, oi: np.ndarray) -> None:
    """Shadow where the surface between lines ``a`` and ``b`` (weight ``g``) passes above
    the cell; NaN at nodata."""
    for j in range(zi.shape[0]):
        v = np.float64(zi[j])
        sj = a[j] + g * (b[j] - a[j])
        lit = np.float32(0.0) if sj > v else np.float32(1.0)
        oi[j] = lit if v == v else np.float32(np.nan)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sweep_join_lerp(a: np.ndarray, b: np.ndarray, f: float, s: np.ndarray) -> None:
    """The heights between cells ``a`` and ``b`` (weight ``f``) join the lines' surfaces
    (a sample touching nodata is skipped: NaN compares False)."""
    for j in range(s.shape[0]):
        v = a[j] + f * (np.float64(b[j]) - a[j])
        s[j] = v if v > s[j] else s[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sweep_join(a: np.ndarray, s: np.ndarray) -> None:
    for j in range(s.shape[0]):
        v = np.float64(a[j])
        s[j] = v if v > s[j] else s[j]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sweep_drop(s: np.ndarray, drop: float) -> None:
    for j in range(s.shape[0]):
        s[j] -= drop


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _shadow_sweep_rows(
    z: np.ndarray, di: int, e: float, drop: float, out: np.ndarray, s: np.ndarray
) -> None:
    """The row sweep of :func:`shadow_sweep_kernel`: rows from the sun's side (the rays of
    row i go to row i + di)."""
    h = z.shape[0]
    u0 = math.floor(min(0.0, -e * (h - 1))) - 1
    for j in range(s.shape[0]):
        s[j] = _NOTHING
    for n in range(h):
        i = n if di < 0 else h - 1 - n
        _sweep_line(z[i], i, e, u0, s, out[i], drop)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _shadow_sweep_cols(
    z: np.ndarray, dj: int, e: float, drop: float, out: np.ndarray, s: np.ndarray,
    zt: np.ndarray, lt: np.ndarray,
) -> None:  # fmt: skip
    """The column sweep: columns from the sun's side, ``zt.shape[0]`` at a time copied into
    the rows of ``zt`` (contiguous lines, without transposing the grid), their shadows from
    ``lt`` back into ``out``."""
    h, w = z.shape
    m = zt.shape[0]
    u0 = math.floor(min(0.0, -e * (w - 1))) - 1
    for j in range(s.shape[0]):
        s[j] = _NOTHING
    for n0 in range(0, w, m):
        k = min(m, w - n0)
        # the strip's columns, in sweep order: n0 .. n0 + k - 1 from the sun's side
        lo = n0 if dj < 0 else w - n0 - k
        for i in range(h):
            zr = z[i]
            if dj < 0:
                for q in range(k):
                    zt[q, i] = zr[lo + q]
            else:
                for q in range(k):
                    zt[q, i] = zr[lo + k - 1 - q]
        for q in range(k):
            col = lo + q if dj < 0 else lo + k - 1 - q
            _sweep_line(zt[q, :h], col, e, u0, s, lt[q, :h], drop)
        for i in range(h):
            orow = out[i]
            if dj < 0:
                for q in range(k):
                    orow[lo + q] = lt[q, i]
            else:
                for q in range(k):
                    orow[lo + k - 1 - q] = lt[q, i]


def _march_steps(step_lens: np.ndarray, radius: float, h: int, w: int) -> np.ndarray:
    """The steps each direction's ray takes within ``radius`` metres (at most ``h + w``), in
    float64 arithmetic as the band kernels used to take them."""
    return np.array(
        [min(math.floor(radius / float(s) * (1.0 + 1e-12)), h + w) for s in step_lens],
        dtype=np.int64,
    )


def sky_view_reference_kernel(
    z: np.ndarray,
    d_rows: np.ndarray,
    d_cols: np.ndarray,
    step_lens: np.ndarray,
    row_ubs: np.ndarray,
    col_ubs: np.ndarray,
    row_which: np.ndarray,
    col_which: np.ndarray,
    local_ub: np.ndarray,
    radius: float,
) -> np.ndarray:
    h, w = z.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    max_steps = _march_steps(step_lens, radius, h, w)
    run_bands(
        _sky_view_rows, h, z, d_rows, d_cols, step_lens, row_ubs, col_ubs, row_which, col_which,
        local_ub, max_steps, out,
    )  # fmt: skip
    return out


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sky_view_rows(
    i0: int,
    i1: int,
    z: np.ndarray,
    d_rows: np.ndarray,
    d_cols: np.ndarray,
    step_lens: np.ndarray,
    row_ubs: np.ndarray,
    col_ubs: np.ndarray,
    row_which: np.ndarray,
    col_which: np.ndarray,
    local_ub: np.ndarray,
    max_steps: np.ndarray,
    out: np.ndarray,
) -> None:
    """Rows ``i0 .. i1`` of :func:`sky_view_reference_kernel` into ``out`` (one band of
    :func:`.run_bands`); ``max_steps`` are the steps of each direction within the radius."""
    w = z.shape[1]
    n = d_rows.shape[0]
    for i in range(i0, i1):
        for j in range(w):
            if np.isnan(z[i, j]):
                continue
            acc = 0.0
            for d in range(n):
                t = _horizon_tan(
                    z,
                    i,
                    j,
                    d_rows[d],
                    d_cols[d],
                    step_lens[d],
                    row_ubs,
                    row_which[d],
                    col_ubs,
                    col_which[d],
                    local_ub[i, j],
                    0.0,
                    np.inf,
                    max_steps[d],
                )
                acc += t / math.sqrt(1.0 + t * t)  # sin(atan(t)), t >= 0
            out[i, j] = 1.0 - acc / n


def openness_reference_kernel(
    z: np.ndarray,
    d_rows: np.ndarray,
    d_cols: np.ndarray,
    step_lens: np.ndarray,
    row_ubs: np.ndarray,
    col_ubs: np.ndarray,
    row_which: np.ndarray,
    col_which: np.ndarray,
    local_ub: np.ndarray,
    radius: float,
) -> np.ndarray:
    """Positive openness in degrees (Yokoyama et al. 2002) of every cell of ``z``: the mean
    over the directions of ``90 - elevation angle`` of the highest sample within ``radius``
    (the angle may be negative: a peak sees only lower ground). A ray without a sample (at
    the grid edge, or over nodata only) counts as a horizontal horizon, 90 degrees."""
    h, w = z.shape
    out = np.full((h, w), np.nan, dtype=np.float32)
    max_steps = _march_steps(step_lens, radius, h, w)
    run_bands(
        _openness_rows, h, z, d_rows, d_cols, step_lens, row_ubs, col_ubs, row_which, col_which,
        local_ub, max_steps, out,
    )  # fmt: skip
    return out


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _openness_rows(
    i0: int,
    i1: int,
    z: np.ndarray,
    d_rows: np.ndarray,
    d_cols: np.ndarray,
    step_lens: np.ndarray,
    row_ubs: np.ndarray,
    col_ubs: np.ndarray,
    row_which: np.ndarray,
    col_which: np.ndarray,
    local_ub: np.ndarray,
    max_steps: np.ndarray,
    out: np.ndarray,
) -> None:
    """Rows ``i0 .. i1`` of :func:`openness_reference_kernel` into ``out`` (one band of
    :func:`.run_bands`)."""
    w = z.shape[1]
    n = d_rows.shape[0]
    for i in range(i0, i1):
        for j in range(w):
            if np.isnan(z[i, j]):
                continue
            acc = 0.0
            for d in range(n):
                # No floor: the highest sample may lie below the cell. No early stop at a
                # target angle either; the bounds still end the march where nothing ahead
                # could raise the horizon.
                t = _horizon_tan(
                    z,
                    i,
                    j,
                    d_rows[d],
                    d_cols[d],
                    step_lens[d],
                    row_ubs,
                    row_which[d],
                    col_ubs,
                    col_which[d],
                    local_ub[i, j],
                    -np.inf,
                    np.inf,
                    max_steps[d],
                )
                if t > -np.inf:
                    acc += 90.0 - math.degrees(math.atan(t))
                else:
                    acc += 90.0
            out[i, j] = acc / n


# The loops of one step, over views that start at the span (a loop indexing a[j + k] with a
# runtime k does not vectorise).
@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _step_max(a: np.ndarray, z0: np.ndarray, best: np.ndarray, inv: np.float32) -> None:
    for j in range(best.shape[0]):
        t = (a[j] - z0[j]) * inv
        best[j] = t if t > best[j] else best[j]  # NaN (nodata) never raises it


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _step_lerp_max(
    a: np.ndarray, b: np.ndarray, z0: np.ndarray, best: np.ndarray, f: np.float32,
    inv: np.float32,
) -> None:  # fmt: skip
    for j in range(best.shape[0]):
        v = a[j] + f * (b[j] - a[j])
        t = (v - z0[j]) * inv
        best[j] = t if t > best[j] else best[j]


#: Columns of the row march's blocks: a block's rays are marched through every step before
#: the next block's, its row of bests, heights and samples (4 x 8 KB) in a core's L1 cache.
MARCH_BLOCK = 2048


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _steps_in(h: int, w: int, d_row: float, d_col: float, n_in: np.ndarray) -> None:
    """``n_in[j]``: the steps the ray of a cell of column ``j`` takes inside the grid across
    the rows' axis (the same formula, and rounding, as the march): a row march's bound of
    each column, the same for every row, so taken once per direction."""
    if abs(d_row) == 1.0:
        for j in range(w):
            if d_col > 0.0:
                n_in[j] = int((w - 1 - j) / d_col + 1e-9)
            elif d_col < 0.0:
                n_in[j] = int(j / -d_col + 1e-9)
            else:
                n_in[j] = h + w
    else:
        dj = int(d_col)
        for j in range(w):
            n_in[j] = w - 1 - j if dj > 0 else j


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _step4_max(
    a0: np.ndarray, a1: np.ndarray, a2: np.ndarray, a3: np.ndarray, z0: np.ndarray,
    best: np.ndarray, i0: np.float32, i1: np.float32, i2: np.float32, i3: np.float32,
) -> None:  # fmt: skip
    """Four steps of samples on cell centres at once (:func:`_step_max` four times): the
    running maximum stays in a register and is stored once, unconditionally. A loop that
    stores ``best[j]`` only where a sample raises it is compiled (llvmlite 0.50) to masked stores
    (``vmaskmovps``), microcoded on AMD Zen: the one-step loop ran at ~1.7 cycles a sample."""
    for j in range(best.shape[0]):
        u = z0[j]
        m = best[j]
        t = (a0[j] - u) * i0
        m = t if t > m else m  # NaN (nodata) never raises it
        t = (a1[j] - u) * i1
        m = t if t > m else m
        t = (a2[j] - u) * i2
        m = t if t > m else m
        t = (a3[j] - u) * i3
        m = t if t > m else m
        best[j] = m


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _step4_lerp_max(
    a0: np.ndarray, b0: np.ndarray, a1: np.ndarray, b1: np.ndarray, a2: np.ndarray,
    b2: np.ndarray, a3: np.ndarray, b3: np.ndarray, z0: np.ndarray, best: np.ndarray,
    f0: np.float32, f1: np.float32, f2: np.float32, f3: np.float32,
    i0: np.float32, i1: np.float32, i2: np.float32, i3: np.float32,
) -> None:  # fmt: skip
    """Four interpolated steps at once (:func:`_step_lerp_max` four times, the same float32
    expression per sample, so the same maxima bit for bit). A step on a cell centre comes
    with ``b = a`` and ``f = 0``: ``a + 0 (a - a)`` is ``a``, and a nodata neighbour it must
    not read is not read. More than four steps at once was slower (16 streams of rows)."""
    for j in range(best.shape[0]):
        u = z0[j]
        m = best[j]
        t = (a0[j] + f0 * (b0[j] - a0[j]) - u) * i0
        m = t if t > m else m
        t = (a1[j] + f1 * (b1[j] - a1[j]) - u) * i1
        m = t if t > m else m
        t = (a2[j] + f2 * (b2[j] - a2[j]) - u) * i2
        m = t if t > m else m
        t = (a3[j] + f3 * (b3[j] - a3[j]) - u) * i3
        m = t if t > m else m
        best[j] = m


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _one_step(
    z: np.ndarray, i: int, k: int, rows_major: bool, d_row: float, d_col: float, inv: np.float32,
    best: np.ndarray, lo: int, hi: int,
) -> None:  # fmt: skip
    """Step ``k`` of the rays of cells ``lo .. hi`` of row ``i`` (all inside the grid at that
    step), as :func:`_horizon_row` takes it: the cells whose sample and its neighbour lie
    inside the row in one loop, the (at most two) others by :func:`_sample`'s clamps."""
    if lo >= hi:
        return
    h, w = z.shape
    zi = z[i]
    if rows_major:
        r = i + k * int(d_row)
        o = k * d_col
        b = math.floor(o)
        f = np.float32(o - b)
        zr = z[r]
        va = max(lo, -b)
        vb = min(hi, w - 1 - b)
        if f == np.float32(0.0):
            vb = min(hi, w - b)
            if va < vb:
                _step_max(zr[va + b : vb + b], zi[va:vb], best[va:vb], inv)
        elif va < vb:
            _step_lerp_max(zr[va + b : vb + b], zr[va + b + 1 : vb + b + 1], zi[va:vb],
                           best[va:vb], f, inv)  # fmt: skip
        if va >= vb:
            va = vb = hi
        for part in range(2):
            p0 = lo if part == 0 else max(vb, lo)
            p1 = min(va, hi) if part == 0 else hi
            for j in range(p0, p1):
                cs, ff = _sample(j, o, w)
                a = zr[cs]
                v = a + np.float32(ff) * (zr[cs + 1] - a) if ff > 0.0 else a
                t = (v - zi[j]) * inv
                best[j] = t if t > best[j] else best[j]
    else:
        r0, ff = _sample(i, k * d_row, h)
        f = np.float32(ff)
        za = z[r0]
        shift = k * int(d_col)
        if f == np.float32(0.0):
            _step_max(za[lo + shift : hi + shift], zi[lo:hi], best[lo:hi], inv)
        else:
            zb = z[r0 + 1]
            _step_lerp_max(za[lo + shift : hi + shift], zb[lo + shift : hi + shift],
                           zi[lo:hi], best[lo:hi], f, inv)  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _fused4(
    z: np.ndarray, rows_major: bool, gi: np.ndarray, ff: np.ndarray, iv: np.ndarray,
    best: np.ndarray, fa: int, fb: int,
) -> None:  # fmt: skip
    """Four steps of the cells ``fa .. fb`` of row ``gi[4, 0]``, every sample and its
    neighbour inside the grid: step ``s`` reads row ``gi[0, s]`` shifted by ``gi[1, s]``
    columns (and the next column, rows-major, or the next row, columns-major), weight
    ``ff[s]``, inverse distance ``iv[s]``."""
    zi = z[gi[4, 0]]
    z0 = zi[fa:fb]
    bt = best[fa:fb]
    r0, r1, r2, r3 = gi[0, 0], gi[0, 1], gi[0, 2], gi[0, 3]
    s0, s1, s2, s3 = fa + gi[1, 0], fa + gi[1, 1], fa + gi[1, 2], fa + gi[1, 3]
    n = fb - fa
    a0, a1, a2, a3 = z[r0][s0 : s0 + n], z[r1][s1 : s1 + n], z[r2][s2 : s2 + n], z[r3][s3 : s3 + n]
    z32 = np.float32(0.0)
    if ff[0] == z32 and ff[1] == z32 and ff[2] == z32 and ff[3] == z32:
        _step4_max(a0, a1, a2, a3, z0, bt, iv[0], iv[1], iv[2], iv[3])
        return
    # the interpolation neighbour: the next column (rows-major) or row; a step on a cell
    # centre reads its cell twice
    dr = 0 if rows_major else 1
    dc = 1 if rows_major else 0
    b0 = z[r0 + dr][s0 + dc : s0 + dc + n] if ff[0] != z32 else a0
    b1 = z[r1 + dr][s1 + dc : s1 + dc + n] if ff[1] != z32 else a1
    b2 = z[r2 + dr][s2 + dc : s2 + dc + n] if ff[2] != z32 else a2
    b3 = z[r3 + dr][s3 + dc : s3 + dc + n] if ff[3] != z32 else a3
    _step4_lerp_max(a0, b0, a1, b1, a2, b2, a3, b3, z0, bt, ff[0], ff[1], ff[2], ff[3],
                    iv[0], iv[1], iv[2], iv[3])  # fmt: skip


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _horizon_row(
    z: np.ndarray,
    i: int,
    d_row: float,
    d_col: float,
    step_len: float,
    max_steps: int,
    row_ub: np.ndarray,
    rw: int,
    col_ub: np.ndarray,
    cw: int,
    floor_tan: float,
    best: np.ndarray,
    n_in: np.ndarray,
    gi: np.ndarray,
    ff: np.ndarray,
    iv: np.ndarray,
    fused: int,
) -> None:
    """``best[j]``: the largest ``(sample - z[i, j]) / distance`` along the ray of every cell
    of row ``i`` in one direction (at least ``floor_tan``), as :func:`_horizon_tan` marches it:
    the same samples, steps and grid-edge rule; nodata samples never raise it. ``n_in``: the
    direction's :func:`_steps_in`.

    The row is marched in blocks of ``MARCH_BLOCK`` cells, each through all its steps (its
    bests, heights and samples stay in the first-level cache), in groups of four steps. With
    ``fused`` (what :func:`sky_view_kernel` runs), the cells all four of whose samples (and
    their interpolation neighbours) lie inside the grid take one loop over the four steps
    (:func:`_fused4`), which loads and stores their running maxima once; the few others, near
    the grid's edges, and every cell without ``fused`` (the one-step march,
    :func:`sky_view_march_kernel`), step by step (:func:`_one_step`). The same float32
    expression per sample either way, and a maximum does not depend on the order it is taken
    in: the same ``best`` bit for bit. ``gi`` (5, 4) int64, ``ff``, ``iv`` (4,) float32:
    scratch for a group's rows, column shifts, spans, weights and inverse distances."""
    h, w = z.shape
    zi = z[i]
    f0 = np.float32(floor_tan)
    for j in range(w):
        best[j] = f0
    rows_major = abs(d_row) == 1.0
    di = int(d_row)
    dj = int(d_col)
    if rows_major:
        n_row = h - 1 - i if di > 0 else i
    elif d_row > 0.0:
        n_row = int((h - 1 - i) / d_row + 1e-9)
    elif d_row < 0.0:
        n_row = int(i / -d_row + 1e-9)
    else:
        n_row = h + w
    n_k = min(n_row, max_steps)
    far = n_k * step_len
    gi[4, 0] = i
    for c0 in range(0, w, MARCH_BLOCK):
        c1 = min(c0 + MARCH_BLOCK, w)
        # the cells whose ray is still inside the grid at step k: n_in is monotone in j, so
        # the span only shrinks as k grows
        ja = c0
        jb = c1
        k = 1
        while k <= n_k:
            g = min(4, n_k - k + 1)
            fa = c0  # the cells inside, with their neighbours, at all g steps
            fb = c1
            for s in range(g):
                ks = k + s
                if rows_major:
                    if d_col > 0.0:
                        while jb > ja and n_in[jb - 1] < ks:
                            jb -= 1
                    elif d_col < 0.0:
                        while ja < jb and n_in[ja] < ks:
                            ja += 1
                    o = ks * d_col
                    b = math.floor(o)
                    f = np.float32(o - b)
                    gi[0, s] = i + ks * di
                    gi[1, s] = b
                    ff[s] = f
                    fa = max(fa, ja, -b)
                    fb = min(fb, jb, w - b if f == np.float32(0.0) else w - 1 - b)
                else:
                    if dj > 0:
                        jb = min(c1, max(w - ks, 0))
                    else:
                        ja = max(c0, min(ks, w))
                    r0, fr = _sample(i, ks * d_row, h)
                    gi[0, s] = r0
                    gi[1, s] = ks * dj
                    ff[s] = np.float32(fr)
                    fa = max(fa, ja)
                    fb = min(fb, jb)
                gi[2, s] = ja
                gi[3, s] = jb
                iv[s] = np.float32(1.0 / (ks * step_len))
            if gi[2, 0] >= gi[3, 0]:
                break  # no ray inside at step k, nor later
            together = fused and g == 4 and fa < fb
            if together:
                _fused4(z, rows_major, gi, ff, iv, best, fa, fb)
            # the cells outside the fused span (all of them after a short group, the last
            # one, or a span too narrow): step by step; one call site, as each is compiled
            for q in range(2 * g):
                s = q >> 1
                lo = gi[2, s] if q & 1 == 0 or not together else fb
                hi = (fa if together else gi[3, s]) if q & 1 == 0 else (gi[3, s] if together else 0)
                _one_step(z, i, k + s, rows_major, d_row, d_col, iv[s], best, lo, hi)
            k += g
            if ja >= jb:
                break
            # every four steps: stop once no cell's ray can rise further (the test of
            # :func:`_horizon_row`, at the same steps)
            last = k - 1
            if last % 4 == 0 and last < n_k:
                nxt = (last + 1) * step_len
                done = True
                if rows_major:
                    rub = row_ub[rw, min(max(i + (last + 1) * di, 0), h - 1)]
                    for j in range(ja, jb):
                        reach = far if best[j] < 0 else nxt
                        if rub - zi[j] > best[j] * reach:
                            done = False
                            break
                else:
                    r1, _ = _sample(i, (last + 1) * d_row, h)
                    rub = row_ub[rw, r1]
                    for j in range(ja, jb):
                        reach = far if best[j] < 0 else nxt
                        cub = col_ub[cw, min(max(j + (last + 1) * dj, 0), w - 1)]
                        if min(rub, cub) - zi[j] > best[j] * reach:
                            done = False
                            break
                if done:
                    break


def _row_march(z: np.ndarray, rays: tuple, mode: int, fused: int = 1) -> np.ndarray:
    """``mode`` 0 (sky-view factor) or 1 (positive openness) of every cell of ``z`` by the row
    march (:func:`_horizon_row`), four steps at a time (``fused`` 1) or one (0); ``rays``
    the arguments of the reference kernels after ``z`` (its ``local_ub``, the per-cell
    bound, is not used and may be None)."""
    d_rows, d_cols, step_lens, row_ubs, col_ubs, row_which, col_which, _, radius = rays
    h, w = z.shape
    out = np.empty((h, w), dtype=np.float32)
    max_steps = _march_steps(step_lens, radius, h, w)
    run_bands(
        _sky_rows, h, z, d_rows, d_cols, step_lens, row_ubs, col_ubs, row_which, col_which,
        max_steps, mode, fused, out,
        scratch=lambda: (np.empty(w, np.float32), np.empty((len(d_rows), w), np.int64),
                         np.empty(w), np.empty((5, 4), np.int64), np.empty(4, np.float32),
                         np.empty(4, np.float32)),
    )  # fmt: skip
    return out


def sky_view_kernel(z: np.ndarray, *rays: object) -> np.ndarray:
    """Sky-view factor of every cell of ``z``, row by row, four steps at a time
    (:func:`_horizon_row` fused); the arguments of :func:`sky_view_reference_kernel`."""
    return _row_march(z, rays, 0)


def openness_kernel(z: np.ndarray, *rays: object) -> np.ndarray:
    """Positive openness of every cell of ``z``, row by row, four steps at a time
    (:func:`_horizon_row` fused); the arguments of :func:`openness_reference_kernel`."""
    return _row_march(z, rays, 1)


def sky_view_march_kernel(z: np.ndarray, *rays: object) -> np.ndarray:
    """:func:`sky_view_kernel` one step at a time (:func:`_horizon_row` not fused, the row
    march before the fused steps): the reference the fused route is tested against, bit for
    bit."""
    return _row_march(z, rays, 0, 0)


def openness_march_kernel(z: np.ndarray, *rays: object) -> np.ndarray:
    """:func:`openness_kernel` one step at a time (:func:`_horizon_row` not fused)."""
    return _row_march(z, rays, 1, 0)


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _sky_rows(
    i0: int,
    i1: int,
    z: np.ndarray,
    d_rows: np.ndarray,
    d_cols: np.ndarray,
    step_lens: np.ndarray,
    row_ubs: np.ndarray,
    col_ubs: np.ndarray,
    row_which: np.ndarray,
    col_which: np.ndarray,
    max_steps: np.ndarray,
    mode: int,
    fused: int,
    out: np.ndarray,
    best: np.ndarray,
    n_in: np.ndarray,
    acc: np.ndarray,
    gi: np.ndarray,
    ff: np.ndarray,
    iv: np.ndarray,
) -> None:
    """Rows ``i0 .. i1`` of the sky-view factor (``mode`` 0: ``1 - mean sin(max(0, horizon))``)
    or the positive openness (1: ``mean (90 - horizon)`` in degrees, a ray without a sample
    90) into ``out``."""
    w = z.shape[1]
    n = d_rows.shape[0]
    floor_tan = 0.0 if mode == 0 else -np.inf
    deg = np.float32(180.0 / math.pi)
    h = z.shape[0]
    for d in range(n):
        _steps_in(h, w, d_rows[d], d_cols[d], n_in[d])
    for i in range(i0, i1):
        for j in range(w):
            acc[j] = 0.0
        for d in range(n):
            _horizon_row(z, i, d_rows[d], d_cols[d], step_lens[d], max_steps[d], row_ubs,
                         row_which[d], col_ubs, col_which[d], floor_tan, best, n_in[d], gi, ff,
                         iv, fused)  # fmt: skip
            if mode == 0:
                for j in range(w):
                    t = best[j]
                    acc[j] += t / np.sqrt(np.float32(1.0) + t * t)  # sin(atan(t)), t >= 0
            else:
                for j in range(w):
                    t = best[j]
                    a = _atan_pos(abs(t)) * deg
                    a = -a if t < np.float32(0) else a
                    # -inf: no sample, a horizontal horizon (atan gives -90 there: 180)
                    acc[j] += np.float32(90.0) - a if t > -np.inf else np.float32(90.0)
        zi = z[i]
        o = out[i]
        for j in range(w):
            v = 1.0 - acc[j] / n if mode == 0 else acc[j] / n
            o[j] = np.float32(np.nan) if np.isnan(zi[j]) else np.float32(v)
