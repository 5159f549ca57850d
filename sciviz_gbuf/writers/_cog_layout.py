"""The Cloud-Optimised GeoTIFF layout, written without a re-encode: tiles are deflated where
their pixels are computed (on dask workers), and the file is assembled from them.

GDAL's COG driver copies a finished GeoTIFF: it decompresses every tile, deflates it again
and computes the overviews, serially in one process, which made it most of the time of a
large map on a cluster. Here a worker that computed a block of the map also

- deflates the block's tiles of the full-resolution image and of the overview levels whose
  tiles lie wholly inside the block (a 2048-pixel block holds whole tiles of levels 0, 1 and
  2: 512 pixels of level k cover ``512 * 2**k`` map pixels), and
- halves the block once more and returns that small piece (1/64 of the block's pixels for a
  2048-pixel block),

and this process writes the tiles' bytes to a scratch file as they arrive (in any order),
puts the pieces together into the next level, computes the few coarser levels from it and
finally writes the COG: header, GDAL's structural metadata ("ghost area"), the image file
directories of every level, then the tiles from the smallest overview to the full
resolution, row by row, each with GDAL's leader (its size) and trailer (its last 4 bytes
again). GDAL reads such a file as ``LAYOUT=COG``; ``validate_cloud_optimized_geotiff.py``
accepts it.

Overview pixels are the mean of the 2 x 2 pixels below them (GDAL's ``AVERAGE``, each level
from the previous one); with an alpha band the colour is the alpha-weighted mean and the
alpha the plain mean, so transparent (nodata) pixels do not darken the edges (GDAL averages
the colour over the pixels its alpha mask marks valid: the same for 0/255 alpha). At the
right and bottom edges of an odd-sized level the mean is over the pixels that exist.
"""

from __future__ import annotations

import errno
import os
import struct
import threading
import zlib
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from ._cog_kernels import halve_rows

try:
    from isal import isal_zlib as _deflate

    _FAST, _SMALL = 1, 3  # ISA-L's levels run 0..3
except ImportError:  # pragma: no cover - isal is a dependency; zlib is the fallback
    _deflate = zlib
    _FAST, _SMALL = 1, 6

__all__ = [
    "CLASSIC_LIMIT",
    "TILE",
    "TileStore",
    "deflate_level",
    "encode_block",
    "encode_tile",
    "geo_entries",
    "halve",
    "level_shapes",
    "worker_levels",
]

#: Tile edge of every level, pixels (GDAL's default for the COG driver).
TILE = 512
#: A file at least this large is a BigTIFF (a classic TIFF's offsets are 32-bit).
CLASSIC_LIMIT = 2**32
#: A level larger than this (bytes) is kept in a scratch file rather than in memory.
_IN_MEMORY_LEVEL = 64 * 2**20
#: The structural metadata GDAL's COG driver writes after the header; GDAL reports
#: ``LAYOUT=COG`` for a file that declares these four properties (and honours them).
_GHOST = (
    "LAYOUT=IFDS_BEFORE_DATA\n"
    "BLOCK_ORDER=ROW_MAJOR\n"
    "BLOCK_LEADER=SIZE_AS_UINT4\n"
    "BLOCK_TRAILER=LAST_4_BYTES_REPEATED\n"
    "KNOWN_INCOMPATIBLE_EDITION=NO\n"
)
# TIFF field types: (code, bytes per value, struct letter)
_SHORT, _LONG, _DOUBLE, _LONG8 = (3, 2, "H"), (4, 4, "I"), (12, 8, "d"), (16, 8, "Q")
_TYPE_SIZE = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 6: 1, 7: 1, 8: 2, 9: 4, 10: 8, 11: 4, 12: 8, 16: 8}
#: GeoTIFF's tags (pixel scale, tie points, transformation, the three GeoKey tags).
_GEO_TAGS = (33550, 33922, 34264, 34735, 34736, 34737)


def deflate_level(large: bool) -> int:
    """The deflate level of a COG's tiles: the fastest on large maps (~3x faster than zlib's
    6 for a few % more bytes), the strongest this deflate has on small ones."""
    return _FAST if large else _SMALL


def level_shapes(h: int, w: int) -> list[tuple[int, int]]:
    """(rows, columns) of the full resolution and of every overview level: halving (rounded
    up, GDAL's ``DIV_ROUND_UP``) until a level fits one tile (the COG driver's
    ``OVERVIEWS=AUTO``)."""
    shapes = [(int(h), int(w))]
    while max(shapes[-1]) > TILE:
        a, b = shapes[-1]
        shapes.append(((a + 1) // 2, (b + 1) // 2))
    return shapes


def worker_levels(chunks: Sequence[Sequence[int]], n_levels: int) -> int:
    """The highest level whose tiles lie wholly inside every block of a grid of ``chunks``
    (row and column chunk sizes, each a multiple of :data:`TILE` but the last): levels
    ``0..k`` are encoded where the blocks are computed; ``n_levels - 1`` when every level is."""
    k = n_levels - 1
    for sizes in chunks[:2]:
        if len(sizes) == 1:
            continue  # one block across this axis: every level's tiles are inside it
        step = int(sizes[0])
        j = 0
        while j < k and step % (TILE << (j + 1)) == 0:
            j += 1
        k = min(k, j)
    return k


def halve(a: np.ndarray) -> np.ndarray:
    """The next overview level of an (h, w, c) uint8 image: each pixel the rounded mean of
    the 2 x 2 below it (1 or 2 at an odd edge); with c == 4 the colour is weighted by alpha
    (0 where all four are transparent). One pass of :func:`._cog_kernels.halve_rows` on the
    calling thread (a block's worker); :func:`halve_reference` is the numpy statement."""
    a = np.ascontiguousarray(a, dtype=np.uint8)
    h, w, c = a.shape
    out = np.empty(((h + 1) // 2, (w + 1) // 2, c), np.uint8)
    halve_rows(0, out.shape[0], a, out)
    return out


def halve_reference(a: np.ndarray) -> np.ndarray:
    """:func:`halve` by numpy expressions (the statement the kernel is tested against)."""
    h, w, c = a.shape
    h2, w2 = (h + 1) // 2, (w + 1) // 2
    if h % 2 or w % 2:
        p = np.zeros((2 * h2, 2 * w2, c), np.uint8)
        p[:h, :w] = a
    else:
        p = a
    q = p.reshape(h2, 2, w2, 2, c)
    rows = np.full(h2, 2, np.uint32)
    cols = np.full(w2, 2, np.uint32)
    rows[-1] = 2 - h % 2
    cols[-1] = 2 - w % 2
    n = (rows[:, None] * cols[None, :])[..., None]  # pixels present under each
    out = np.empty((h2, w2, c), np.uint8)
    if c == 4:
        alpha = q[..., 3:4].astype(np.uint32)
        sa = alpha.sum(axis=(1, 3))
        rgb = (q[..., :3] * alpha).sum(axis=(1, 3), dtype=np.uint32)
        out[..., :3] = (rgb + sa // 2) // np.maximum(sa, 1)
        out[..., 3:] = (sa + n // 2) // n
    else:
        s = q.sum(axis=(1, 3), dtype=np.uint32)
        out[...] = (s + n // 2) // n
    return out


def encode_tile(t: np.ndarray, level: int) -> bytes:
    """One TIFF tile of at most :data:`TILE` x :data:`TILE` (h, w, c) uint8 pixels: padded
    to the full tile, horizontal differencing (TIFF predictor 2: each sample minus the same
    sample of the pixel to its left, modulo 256), deflated in a zlib stream."""
    th, tw, c = t.shape
    buf = np.zeros((TILE, TILE, c), np.uint8)
    buf[:th, 0] = t[:, 0]
    np.subtract(t[:, 1:], t[:, :-1], out=buf[:th, 1:tw])
    return _deflate.compress(memoryview(buf).cast("B"), level)


Tiles = list[tuple[int, int, int, bytes]]


def encode_block(
    block: np.ndarray, r0: int, c0: int, top: int, n_levels: int, level: int
) -> tuple[Tiles, np.ndarray | None]:
    """Encode the tiles of levels ``0..top`` that lie in an (h, w, c) uint8 block at pixel
    (r0, c0) of the full image: ``[(level, tile row, tile column, bytes)]``, and the block
    at level ``top + 1`` (None when ``top`` is the last of ``n_levels``).

    ``r0`` and ``c0`` are multiples of ``TILE * 2**top`` (so are the block's sizes, except at
    the image's edge): every tile of those levels is whole inside one block. This runs on the
    worker that computed the block."""
    a = np.ascontiguousarray(block, dtype=np.uint8)
    tiles: Tiles = []
    for k in range(top + 1):
        h, w = a.shape[:2]
        ty0, tx0 = (r0 >> k) // TILE, (c0 >> k) // TILE
        for i, y in enumerate(range(0, h, TILE)):
            for j, x in enumerate(range(0, w, TILE)):
                tile = encode_tile(a[y : y + TILE, x : x + TILE], level)
                tiles.append((k, ty0 + i, tx0 + j, tile))
        if k < n_levels - 1:
            a = halve(a)
    return tiles, (a if top < n_levels - 1 else None)


def geo_entries(transform: Sequence[float], crs: Any) -> list[tuple[int, int, int, bytes]]:
    """The GeoTIFF tags of an image with GDAL geotransform ``transform`` and rasterio CRS
    ``crs`` (or None), as GDAL writes them: ``[(tag, type, count, value bytes)]``.

    GDAL writes a one-pixel GeoTIFF in memory with this georeference and its tags are copied:
    the CRS's GeoKeys are GDAL's own (EPSG codes, user-defined projections alike), and the
    tie point and pixel scale are per pixel, the same for an image of any size."""
    from rasterio.io import MemoryFile
    from rasterio.transform import Affine

    with MemoryFile() as mem:
        with mem.open(
            driver="GTiff", width=1, height=1, count=1, dtype="uint8",
            transform=Affine.from_gdal(*transform), crs=crs,
        ) as dst:  # fmt: skip
            dst.write(np.zeros((1, 1, 1), np.uint8))
        data = mem.read()
    return [e for e in _read_ifd(data) if e[0] in _GEO_TAGS]


def _read_ifd(data: bytes) -> list[tuple[int, int, int, bytes]]:
    """Every entry ``(tag, type, count, value bytes)`` of the first directory of a little-endian
    classic TIFF (what GDAL writes for a one-pixel GeoTIFF)."""
    if data[:4] != b"II*\x00":
        raise ValueError("expected a little-endian classic TIFF")
    (at,) = struct.unpack_from("<I", data, 4)
    (n,) = struct.unpack_from("<H", data, at)
    out = []
    for e in range(n):
        tag, typ, count, value = struct.unpack_from("<HHI4s", data, at + 2 + 12 * e)
        size = _TYPE_SIZE.get(typ, 1) * count
        if size > 4:
            (off,) = struct.unpack("<I", value)
            value = data[off : off + size]
        out.append((tag, typ, count, value[:size]))
    return out


class TileStore:
    """The encoded tiles of every level of an (h, w, c) image, kept in a scratch file as they
    arrive (any order, from any thread), and the COG written from them (:meth:`write`).

    Parameters
    ----------
    shape : (h, w, c)
        The full-resolution image.
    scratch : callable
        ``scratch(tag)`` returns a path for a working file, removed by the caller.
    """

    def __init__(self, shape: tuple[int, int, int], scratch: Callable[[str], Path]) -> None:
        h, w, c = shape
        self.shape = (int(h), int(w), int(c))
        self.shapes = level_shapes(h, w)
        self.index = [
            np.full((-(-a // TILE), -(-b // TILE), 2), -1, np.int64) for a, b in self.shapes
        ]
        self._scratch = scratch
        self._file: BinaryIO = open(scratch("tiles"), "w+b")  # closed by close()
        self._end = 0
        self._lock = threading.Lock()
        self._levels: dict[int, np.ndarray] = {}

    def close(self) -> None:
        """Close the scratch files (the caller removes them)."""
        self._file.close()
        for a in self._levels.values():
            if isinstance(a, np.memmap):
                a._mmap.close()  # type: ignore[attr-defined]
        self._levels.clear()

    def add(self, tiles: Iterable[tuple[int, int, int, bytes]]) -> None:
        """Store encoded tiles ``(level, tile row, tile column, bytes)``."""
        tiles = list(tiles)
        size = sum(len(t[3]) for t in tiles)
        with self._lock:
            at = self._end
            self._end += size
        fd = self._file.fileno()
        for k, ty, tx, data in tiles:
            _pwrite_all(fd, data, at)
            self.index[k][ty, tx] = (at, len(data))
            at += len(data)

    def level(self, k: int) -> np.ndarray:
        """The pixels of level ``k`` (filled by :meth:`put`), in memory or a scratch file;
        made once, whichever thread asks first."""
        with self._lock:
            if k not in self._levels:
                a, b = self.shapes[k]
                shape = (a, b, self.shape[2])
                if a * b * self.shape[2] > _IN_MEMORY_LEVEL:
                    path = self._scratch(f"level{k}")
                    self._levels[k] = np.memmap(path, np.uint8, "w+", shape=shape)
                else:
                    self._levels[k] = np.zeros(shape, np.uint8)
            return self._levels[k]

    def put(self, k: int, r0: int, c0: int, piece: np.ndarray) -> None:
        """Place a block's piece of level ``k`` at pixel (r0, c0) of that level."""
        self.level(k)[r0 : r0 + piece.shape[0], c0 : c0 + piece.shape[1]] = piece

    def encode_levels(self, first: int, level: int, step: Callable[[str], None]) -> None:
        """Encode every tile of levels ``first ..`` from the pixels of level ``first`` (put
        together from the blocks' pieces), each level halved from the one before, in strips
        of two tile rows; tiles deflate on this process's threads."""
        n = len(self.shapes)
        with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
            for k in range(first, n):
                a = self.level(k)
                h, w = a.shape[:2]
                for y in range(0, h, 2 * TILE):
                    strip = np.asarray(a[y : y + 2 * TILE])
                    jobs = [
                        (y // TILE + i, j, strip[i * TILE : (i + 1) * TILE, x : x + TILE])
                        for i in range(-(-strip.shape[0] // TILE))
                        for j, x in enumerate(range(0, w, TILE))
                    ]
                    data = pool.map(lambda job: encode_tile(job[2], level), jobs)
                    self.add((k, ty, tx, d) for (ty, tx, _), d in zip(jobs, data, strict=True))
                    if k < n - 1:
                        self.put(k + 1, y // 2, 0, halve(strip))
                step(f"overview level {k}")
                if isinstance(a, np.memmap):
                    a._mmap.close()  # type: ignore[attr-defined]
                self._levels.pop(k, None)

    def missing(self) -> tuple[int, int, int] | None:
        """(level, tile row, tile column) of a tile not yet stored, or None."""
        for k, idx in enumerate(self.index):
            where = np.argwhere(idx[..., 1] < 0)
            if len(where):
                return (k, int(where[0][0]), int(where[0][1]))
        return None

    def write(self, out: BinaryIO, geo: list[tuple[int, int, int, bytes]]) -> int:
        """Write the COG to ``out`` (a file open for binary writing at its start); returns its
        size in bytes. A BigTIFF when a classic TIFF's 32-bit offsets cannot reach every tile.
        """
        sizes = [idx[..., 1] for idx in self.index]
        data_bytes = int(sum(int(s.sum()) + 8 * s.size for s in sizes))
        for big in (False, True):
            plan = self._plan(big, sizes, geo)
            total = plan[0] + data_bytes
            if big or total < CLASSIC_LIMIT:
                break
        data_start, ifds = plan
        out.write(self._header(big, ifds[0][0]))
        for at, entries, nxt in ifds:
            pad = at - out.tell()
            out.write(b"\0" * pad)
            out.write(_ifd_bytes(entries, at, big, nxt))
        out.write(b"\0" * (data_start - out.tell()))
        fd = self._file.fileno()
        for k in range(len(self.shapes) - 1, -1, -1):
            idx = self.index[k]
            for ty in range(idx.shape[0]):
                for tx in range(idx.shape[1]):
                    off, n = (int(v) for v in idx[ty, tx])
                    data = os.pread(fd, n, off)
                    if len(data) != n:
                        raise OSError(f"scratch file of the tiles cut short at tile {k}/{ty}/{tx}")
                    out.write(struct.pack("<I", n))
                    out.write(data)
                    out.write(data[-4:])
        return total

    def _header(self, big: bool, first_ifd: int) -> bytes:
        head = b"II+\x00" + struct.pack("<HHQ", 8, 0, first_ifd) if big else (
            b"II*\x00" + struct.pack("<I", first_ifd)
        )  # fmt: skip
        ghost = f"GDAL_STRUCTURAL_METADATA_SIZE={len(_GHOST):06d} bytes\n{_GHOST}".encode()
        return head + ghost

    def _plan(
        self, big: bool, sizes: list[np.ndarray], geo: list[tuple[int, int, int, bytes]]
    ) -> tuple[int, list[tuple[int, list, int]]]:
        """Where each directory and each tile goes: (start of the tile data, [(directory
        offset, its entries, next directory's offset)]). Tiles of the smallest overview come
        first, the full resolution last, each level row by row."""
        header = len(self._header(big, 0))
        n = len(self.shapes)
        # directory sizes do not depend on the offsets they hold: lay them out first
        at = header + header % 2
        places = []
        for k in range(n):
            size = len(_ifd_bytes(self._entries(k, big, sizes[k], sizes[k], geo), at, big, 0))
            places.append(at)
            at += size + size % 2
        data_start = at
        # tiles: each behind a 4-byte leader, followed by its last 4 bytes again
        offsets: list[np.ndarray] = [np.empty(0)] * n
        pos = data_start
        for k in range(n - 1, -1, -1):
            s = sizes[k].ravel()
            step = s + 8
            starts = pos + np.concatenate(([0], np.cumsum(step)[:-1])) + 4
            offsets[k] = starts.reshape(sizes[k].shape)
            pos += int(step.sum())
        ifds = [
            (
                places[k],
                self._entries(k, big, offsets[k], sizes[k], geo),
                places[k + 1] if k + 1 < n else 0,
            )
            for k in range(n)
        ]
        return data_start, ifds

    def _entries(
        self, k: int, big: bool, offsets: np.ndarray, counts: np.ndarray, geo: list
    ) -> list[tuple[int, int, int, bytes]]:
        h, w = self.shapes[k]
        c = self.shape[2]
        off_type = _LONG8 if big else _LONG
        e = [
            _entry(254, _LONG, [0 if k == 0 else 1]),  # NewSubfileType: reduced image
            _entry(256, _LONG, [w]),
            _entry(257, _LONG, [h]),
            _entry(258, _SHORT, [8] * c),  # BitsPerSample
            _entry(259, _SHORT, [8]),  # Compression: deflate
            _entry(262, _SHORT, [1 if c == 1 else 2]),  # Photometric: grey / RGB
            _entry(277, _SHORT, [c]),  # SamplesPerPixel
            _entry(284, _SHORT, [1]),  # PlanarConfiguration: pixel-interleaved
            _entry(317, _SHORT, [2]),  # Predictor: horizontal differencing
            _entry(322, _LONG, [TILE]),
            _entry(323, _LONG, [TILE]),
            _entry(324, off_type, offsets.ravel()),  # TileOffsets
            _entry(325, _LONG, counts.ravel()),  # TileByteCounts
        ]
        if c == 4:
            e.append(_entry(338, _SHORT, [2]))  # ExtraSamples: unassociated alpha
        e.append(_entry(339, _SHORT, [1] * c))  # SampleFormat: unsigned
        if k == 0:
            e.extend(geo)
        return sorted(e, key=lambda t: t[0])


def _pwrite_all(fd: int, data: bytes, at: int) -> None:
    """``os.pwrite`` until all of ``data`` is written: a write that meets a file-size limit
    or a full disk writes part of it and returns the count; the next one raises the OS's
    error (EFBIG, ENOSPC), which names the reason."""
    view = memoryview(data)
    while len(view):
        n = os.pwrite(fd, view, at)
        if n <= 0:
            raise OSError(errno.EIO, "the scratch file of the tiles takes no more bytes")
        view = view[n:]
        at += n


def _entry(
    tag: int, typ: tuple[int, int, str], values: Iterable[int]
) -> tuple[int, int, int, bytes]:
    v = np.asarray(list(values) if not isinstance(values, np.ndarray) else values)
    dtype = {"H": "<u2", "I": "<u4", "Q": "<u8", "d": "<f8"}[typ[2]]
    return (tag, typ[0], int(v.size), v.astype(dtype).tobytes())


def _ifd_bytes(entries: list[tuple[int, int, int, bytes]], at: int, big: bool, nxt: int) -> bytes:
    """One image file directory at file offset ``at``: its entries (values longer than the
    entry's slot follow the directory, each at an even offset), then ``nxt``, the offset of
    the next directory (0: the last)."""
    slot = 8 if big else 4
    head = struct.pack("<Q", len(entries)) if big else struct.pack("<H", len(entries))
    entry_size = 20 if big else 12
    extra_at = at + len(head) + entry_size * len(entries) + slot
    body, extra = [], []
    for tag, typ, count, value in entries:
        if len(value) <= slot:
            field = value + b"\0" * (slot - len(value))
        else:
            where = extra_at + sum(len(x) for x in extra)
            field = struct.pack("<Q" if big else "<I", where)
            extra.append(value + b"\0" * (len(value) % 2))
        fmt = "<HHQ" if big else "<HHI"
        body.append(struct.pack(fmt, tag, typ, count) + field)
    tail = struct.pack("<Q" if big else "<I", nxt)
    return head + b"".join(body) + tail + b"".join(extra)
