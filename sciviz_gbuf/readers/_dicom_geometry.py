"""Slice geometry of a DICOM series: order, spacing, gaps, shear, and the resampling kernels.

Pure numpy; no pydicom. Patient coordinates are LPS millimetres throughout.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "SliceGeometry",
    "analyse_positions",
    "duplicate_pairs",
    "resample_along_normal",
    "shift_bilinear",
    "slice_frame",
]

# A step deviating from the median step by more than this fraction makes the spacing uneven.
UNEVEN_TOLERANCE = 0.01
# Slices whose origins drift in-plane by at most this fraction of a pixel count as rectangular.
SHEAR_TOLERANCE = 0.01


def slice_frame(iop: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | str:
    """Unit row cosine, column cosine and slice normal from ImageOrientationPatient.

    Parameters
    ----------
    iop : numpy.ndarray
        The 6 values: direction of increasing column index, then of increasing row index.

    Returns
    -------
    tuple of numpy.ndarray or str
        ``(r, c, n)`` with ``n = r x c`` (all re-normalised), or a message saying what is wrong.
    """
    iop = np.asarray(iop, dtype=np.float64)
    if iop.shape != (6,) or not np.all(np.isfinite(iop)):
        return f"needs 6 finite numbers, got {iop.tolist()}"
    r, c = iop[:3], iop[3:]
    nr, nc = np.linalg.norm(r), np.linalg.norm(c)
    # Scanners write the cosines with ~6 decimals; anything further off is not a rotation.
    if abs(nr - 1) > 1e-3 or abs(nc - 1) > 1e-3:
        return f"direction cosines are not unit vectors (lengths {nr:.6g}, {nc:.6g})"
    r, c = r / nr, c / nc
    if abs(float(r @ c)) > 1e-3:
        return f"direction cosines are not orthogonal (dot product {float(r @ c):.6g})"
    # Re-orthogonalise so the direction matrix is a rotation to machine precision.
    c = c - (r @ c) * r
    c /= np.linalg.norm(c)
    n = np.cross(r, c)
    return r, c, n


@dataclass(frozen=True, eq=False)
class SliceGeometry:
    """Where the slices of a series lie, after sorting along the slice normal.

    Attributes
    ----------
    order : numpy.ndarray
        Indices into the input positions, ascending along the normal.
    s : numpy.ndarray
        Sorted positions along the normal (mm).
    steps : numpy.ndarray
        ``diff(s)``.
    step : float
        Median step (mm); for a single slice the caller's default.
    uneven : numpy.ndarray
        Indices ``k`` of steps ``s[k+1] - s[k]`` deviating by more than 1% from ``step``.
    offsets : numpy.ndarray
        (N, 2) in-plane origin offsets of each sorted slice from the first, in mm along the row
        cosine (column index) and the column cosine (row index).
    sheared : bool
        True if any slice origin drifts in-plane by more than 1% of a pixel.
    shear : numpy.ndarray
        Least-squares in-plane drift per median step, as an LPS 3-vector (mm per slice).
    """

    order: np.ndarray
    s: np.ndarray
    steps: np.ndarray
    step: float
    uneven: np.ndarray
    offsets: np.ndarray
    sheared: bool
    shear: np.ndarray

    @property
    def rectangular(self) -> bool:
        """No shear and no uneven step: an ImageData describes it exactly (within 1%)."""
        return not self.sheared and self.uneven.size == 0


def duplicate_pairs(s_sorted: np.ndarray) -> list[int]:
    """Indices ``k`` where sorted slices ``k`` and ``k+1`` share a position along the normal.

    Two slices coincide within 1e-3 of the median non-zero step, or 1e-4 mm if larger.
    """
    if s_sorted.size < 2:
        return []
    steps = np.diff(s_sorted)
    positive = steps[steps > 1e-4]
    tol = max(1e-4, 1e-3 * float(np.median(positive))) if positive.size else 1e-4
    return np.flatnonzero(steps <= tol).tolist()


def analyse_positions(
    positions: np.ndarray,
    frame: tuple[np.ndarray, np.ndarray, np.ndarray],
    pixel_spacing: tuple[float, float],
    default_step: float,
) -> SliceGeometry:
    """Sort slice origins along the normal and measure step, gaps and in-plane drift.

    Parameters
    ----------
    positions : numpy.ndarray
        (N, 3) ImagePositionPatient of each slice, in any order.
    frame : tuple of numpy.ndarray
        ``(r, c, n)`` from :func:`slice_frame`.
    pixel_spacing : (float, float)
        ``(column spacing, row spacing)``: mm between columns and between rows.
    default_step : float
        Slice step used when there is a single slice.

    Returns
    -------
    SliceGeometry
        Duplicates are not rejected here: check :func:`duplicate_pairs` on ``s`` before
        trusting ``step`` and ``uneven``.
    """
    r, c, n = frame
    s_all = positions @ n
    # Sorting by position alone is order-independent because ties (duplicates) are rejected.
    order = np.argsort(s_all, kind="stable")
    p = positions[order]
    s = s_all[order]
    steps = np.diff(s)
    step = float(np.median(steps)) if steps.size else float(default_step)
    uneven = np.flatnonzero(np.abs(steps - step) > UNEVEN_TOLERANCE * step)
    drift = p - p[0] - np.outer(s - s[0], n)
    offsets = np.stack([drift @ r, drift @ c], axis=1)
    sheared = bool(
        np.any(np.abs(offsets[:, 0]) > SHEAR_TOLERANCE * pixel_spacing[0])
        or np.any(np.abs(offsets[:, 1]) > SHEAR_TOLERANCE * pixel_spacing[1])
    )
    t = (s - s[0]) / step if step > 0 else np.zeros_like(s)
    denom = float(t @ t)
    shear = (t @ drift) / denom if denom > 0 else np.zeros(3)
    return SliceGeometry(order, s, steps, step, uneven, offsets, sheared, shear)


def shift_bilinear(img: np.ndarray, dy: float, dx: float) -> np.ndarray:
    """Sample ``img`` at ``(row + dy, column + dx)`` for every pixel, bilinearly.

    Parameters
    ----------
    img : numpy.ndarray
        (H, W) float image; NaN marks unusable pixels and spreads to every sample using it.
    dy, dx : float
        Shift in pixels (any sign, fractional).

    Returns
    -------
    numpy.ndarray
        (H, W) float64; NaN where the sample needs a pixel outside the image. A zero weight
        never pulls in its neighbour, so integer shifts copy pixels exactly.
    """
    out = _shift_axis(np.asarray(img, dtype=np.float64), dy, axis=0)
    return _shift_axis(out, dx, axis=1)


def _shift_axis(a: np.ndarray, d: float, axis: int) -> np.ndarray:
    base = int(np.floor(d))
    t = d - base
    # Snap fractions that are rounding noise so that exact-integer shifts stay exact.
    if t < 1e-9:
        t = 0.0
    elif t > 1 - 1e-9:
        base, t = base + 1, 0.0
    out = _take_shifted(a, base, axis)
    if t > 0:
        out = out * (1 - t) + _take_shifted(a, base + 1, axis) * t
    return out


def _take_shifted(a: np.ndarray, k: int, axis: int) -> np.ndarray:
    """``out[i] = a[i + k]`` along ``axis``, NaN where ``i + k`` is outside."""
    out = np.full_like(a, np.nan)
    n = a.shape[axis]
    lo, hi = max(0, -k), min(n, n - k)
    if lo < hi:
        dst = [slice(None)] * a.ndim
        src = [slice(None)] * a.ndim
        dst[axis] = slice(lo, hi)
        src[axis] = slice(lo + k, hi + k)
        out[tuple(dst)] = a[tuple(src)]
    return out


def resample_along_normal(
    volume: np.ndarray, s: np.ndarray, targets: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Linear interpolation of a (N, H, W) stack from positions ``s`` onto ``targets``.

    Returns
    -------
    out : numpy.ndarray
        (M, H, W) float64; NaN propagates from either neighbour with a non-zero weight.
    lower : numpy.ndarray
        (M,) index of the lower source slice of each target.
    weight : numpy.ndarray
        (M,) weight of the upper neighbour (0 = exactly the lower slice).
    """
    lower = np.clip(np.searchsorted(s, targets, side="right") - 1, 0, max(len(s) - 2, 0))
    if len(s) < 2:
        return volume[np.zeros(len(targets), dtype=int)].copy(), lower, np.zeros(len(targets))
    span = s[lower + 1] - s[lower]
    w = np.clip((targets - s[lower]) / span, 0.0, 1.0)
    # Targets that sit on a source slice (to 1e-6 of the step) copy it untouched.
    w[w < 1e-6] = 0.0
    hit_upper = w > 1 - 1e-6
    w[hit_upper] = 0.0
    lower = np.where(hit_upper, lower + 1, lower)
    out = np.empty((len(targets), *volume.shape[1:]), dtype=np.float64)
    for m, (k, wk) in enumerate(zip(lower, w, strict=True)):
        if wk == 0.0:
            out[m] = volume[k]
        else:
            out[m] = volume[k] * (1 - wk) + volume[k + 1] * wk
    return out, lower, w
