"""Numba kernels of :mod:`._ink`: the opening of line ink by a disc, on the ink pixels only."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["clump_mask"]


@njit(parallel=True, cache=True)
def clump_mask(solid, dr, dc, core, clump):
    """``core``: the erosion of ``solid`` by the structuring element with offsets ``(dr, dc)``
    (outside the image counts as no ink, as ``scipy.ndimage.binary_erosion``); ``clump``: its
    dilation by the same (symmetric) element, within ``solid``. Returns whether ``core`` has a
    pixel. Lines cover a few per cent of a picture: only their pixels are tested."""
    h, w = solid.shape
    n = dr.size
    found = np.zeros(h, dtype=np.bool_)
    for r in prange(h):
        r = np.int64(r)
        for c in range(w):
            v = False
            if solid[r, c]:
                v = True
                for k in range(n):
                    r2, c2 = r + dr[k], c + dc[k]
                    if not (0 <= r2 < h and 0 <= c2 < w and solid[r2, c2]):
                        v = False
                        break
            core[r, c] = v
            if v:
                found[r] = True
    if not found.any():
        for r in prange(h):
            for c in range(w):
                clump[r, c] = False
        return False
    for r in prange(h):
        r = np.int64(r)
        for c in range(w):
            v = False
            if solid[r, c]:
                for k in range(n):
                    r2, c2 = r - dr[k], c - dc[k]
                    if 0 <= r2 < h and 0 <= c2 < w and core[r2, c2]:
                        v = True
                        break
            clump[r, c] = v
    return True
