"""NaN-aware k x k box filter of supersampled G-buffer images (``GBuffer.downsample``)."""

from __future__ import annotations

import numpy as np
from numba import njit

from .bands import run_bands

__all__ = ["block_mean"]


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _block_mean_rows(r0, r1, src, k, out):
    """Output rows ``r0 .. r1`` of :func:`block_mean` (one band of :func:`.run_bands`)."""
    w, c = out.shape[1], out.shape[2]
    for r in range(r0, r1):
        for col in range(w):
            for ch in range(c):
                # float64 sums: a 4x4 block of float32 samples averages without round-off drift
                total = 0.0
                n = 0
                for i in range(r * k, r * k + k):
                    for j in range(col * k, col * k + k):
                        v = src[i, j, ch]
                        if not np.isnan(v):
                            total += v
                            n += 1
                out[r, col, ch] = total / n if n > 0 else np.nan


def block_mean(image: np.ndarray, k: int, shape: tuple[int, int]) -> np.ndarray:
    """Mean of each ``k x k`` block of ``image`` (H, W) or (H, W, C), NaN samples left out;
    all-NaN blocks are NaN. ``shape`` is the output (h, w); rows/columns beyond ``h k`` /
    ``w k`` are ignored. float32 result."""
    h, w = shape
    img = np.asarray(image)
    src = img.reshape(*img.shape[:2], -1)[: h * k, : w * k]
    src = np.ascontiguousarray(src, dtype=np.float32)
    out = np.empty((h, w, src.shape[2]), dtype=np.float32)
    run_bands(_block_mean_rows, h, src, k, out)
    return out.reshape(h, w, *img.shape[2:])
