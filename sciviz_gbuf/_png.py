"""A PNG encoder for large images that compresses blocks of rows on several threads.

Pillow deflates a PNG on one thread at level 6: 24 s for an 8192² RGBA map. Here each block of
rows is deflated separately (zlib releases the GIL) and the blocks are joined into the single
zlib stream PNG requires, as ``pigz`` does: every block but the last ends with a sync flush, so
the raw deflate streams concatenate, and the Adler-32 of the whole is computed alongside.
Rows use PNG's "Up" filter, computed with numpy, which suits maps (large areas of one colour).
Deflate is ISA-L's (the ``isal`` package: 6x zlib's speed at level 1, output 4% larger) when
installed, else zlib's.
"""

from __future__ import annotations

import os
import struct
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

__all__ = ["encode_png", "write_png_fast"]

try:
    from isal import isal_zlib as _deflate
except ImportError:  # pragma: no cover - isal is a dependency; zlib is the fallback
    _deflate = zlib

_COLOUR_TYPE = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> grey, grey+alpha, RGB, RGBA
_BLOCK_ROWS = 256


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (
        struct.pack(">I", len(data))
        + kind
        + data
        + struct.pack(">I", zlib.crc32(data, zlib.crc32(kind)))
    )


def _filtered_block(a: np.ndarray, r0: int, r1: int) -> bytes:
    """Rows ``r0:r1`` with PNG filter type 2 (Up): each byte minus the byte above, mod 256."""
    rows = a[r0:r1].reshape(r1 - r0, -1)
    above = a[r0 - 1 : r1 - 1].reshape(r1 - r0, -1) if r0 > 0 else None
    out = np.empty((r1 - r0, rows.shape[1] + 1), dtype=np.uint8)
    out[:, 0] = 2
    if above is None:
        out[0, 1:] = rows[0]
        np.subtract(rows[1:], rows[:-1], out=out[1:, 1:])
    else:
        np.subtract(rows, above, out=out[:, 1:])
    return out.tobytes()


def encode_png(image: np.ndarray, *, level: int = 1, threads: int | None = None) -> bytes:
    """PNG bytes of a uint8 image ``(H, W)``, ``(H, W, 2)``, ``(H, W, 3)`` or ``(H, W, 4)``;
    ``level`` 0-3 (ISA-L's range; zlib's levels above 3 are not used)."""
    a = np.ascontiguousarray(image, dtype=np.uint8)
    if a.ndim == 2:
        a = a[..., None]
    h, w, c = a.shape
    starts = list(range(0, h, _BLOCK_ROWS))

    def deflate(r0: int) -> tuple[bytes, bytes]:
        raw = _filtered_block(a, r0, min(r0 + _BLOCK_ROWS, h))
        comp = _deflate.compressobj(min(max(level, 0), 3), zlib.DEFLATED, -15)
        last = r0 == starts[-1]
        mode = _deflate.Z_FINISH if last else _deflate.Z_FULL_FLUSH
        return raw, comp.compress(raw) + comp.flush(mode)

    n = threads or min(len(starts), os.cpu_count() or 1)
    with ThreadPoolExecutor(max_workers=max(n, 1)) as pool:
        parts = list(pool.map(deflate, starts))
    adler = 1
    for raw, _ in parts:
        adler = _deflate.adler32(raw, adler)
    stream = b"".join([b"\x78\x01", *(p for _, p in parts), struct.pack(">I", adler)])
    header = struct.pack(">IIBBBBB", w, h, 8, _COLOUR_TYPE[c], 0, 0, 0)
    idat = b"".join(
        _chunk(b"IDAT", stream[i : i + (1 << 24)]) for i in range(0, len(stream), 1 << 24)
    )
    return b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header) + idat + _chunk(b"IEND", b"")


def write_png_fast(path: Path, image: np.ndarray) -> Path:
    """Write :func:`encode_png` bytes to ``path``."""
    path.write_bytes(encode_png(image))
    return path
