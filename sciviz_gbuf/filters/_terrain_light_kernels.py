"""Numba kernels of :mod:`sciviz_gbuf.filters.terrain_light`: horizons along sun and sky rays."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..core.bands import run_bands


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


@njit(cache=True)
def line_max(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Largest height of every row and every column (-inf where all nodata)."""
    h, w = z.shape
    rows = np.full(h, -np.inf)
    cols = np.full(w, -np.inf)
    for i in range(h):
        for j in range(w):
            v = z[i, j]
            if v > rows[i]:  # NaN compares False
                rows[i] = v
            if v > cols[j]:
                cols[j] = v
    return rows, cols


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


def _march_steps(step_lens: np.ndarray, radius: float, h: int, w: int) -> np.ndarray:
    """The steps each direction's ray takes within ``radius`` metres (at most ``h + w``), in
    float64 arithmetic as the band kernels used to take them."""
    return np.array(
        [min(math.floor(radius / float(s) * (1.0 + 1e-12)), h + w) for s in step_lens],
        dtype=np.int64,
    )


def sky_view_kernel(
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
    """Rows ``i0 .. i1`` of :func:`sky_view_kernel` into ``out`` (one band of
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


def openness_kernel(
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
    """Rows ``i0 .. i1`` of :func:`openness_kernel` into ``out`` (one band of
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
