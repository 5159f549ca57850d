"""Numba kernels of :mod:`._ink`: the opening of line ink by a disc, on the ink pixels only."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.bands import run_bands

__all__ = ["clump_mask"]


def clump_mask(solid, dr, dc, core, clump):
    """``core``: the erosion of ``solid`` by the structuring element with offsets ``(dr, dc)``
    (outside the image counts as no ink, as ``scipy.ndimage.binary_erosion``); ``clump``: its
    dilation by the same (symmetric) element, within ``solid``. Returns whether ``core`` has a
    pixel. Lines cover a few per cent of a picture: only their pixels are tested.

    Two passes over bands of rows: the dilation reads ``core`` rows beyond its band, so it
    starts once every band of the erosion has ended."""
    h = solid.shape[0]
    found = np.zeros(h, dtype=np.bool_)
    run_bands(_erosion_rows, h, solid, dr, dc, core, found)
    if not found.any():
        clump[...] = False
        return False
    run_bands(_dilation_rows, h, solid, dr, dc, core, clump)
    return True


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _erosion_rows(r0, r1, solid, dr, dc, core, found):
    """Rows ``r0 .. r1`` of ``core`` (one band of :func:`.run_bands`); ``found[r]``: whether
    row r of it has a pixel."""
    h, w = solid.shape
    n = dr.size
    for r in range(r0, r1):
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


@njit(cache=True, nogil=True, _nrt=False, error_model="numpy")
def _dilation_rows(r0, r1, solid, dr, dc, core, clump):
    """Rows ``r0 .. r1`` of ``clump``, from the whole of ``core``."""
    h, w = solid.shape
    n = dr.size
    for r in range(r0, r1):
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
