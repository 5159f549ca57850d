"""PMTiles archives: a whole tile pyramid in one file that web maps read by HTTP range
requests (PMTiles version 3, the Protomaps specification), written from an XYZ folder.

An archive is a 127-byte header, a root directory (within the first 16 KiB, so one request
reads both), the metadata (JSON), leaf directories when the root would be larger, then the
tiles' bytes. Tiles are addressed by a *tile id*: the tiles of the zoom levels below, then the
tile's position along the Hilbert curve of its level (neighbouring tiles have near ids, so a
viewer's requests hit contiguous bytes). Directories list runs of ids with their offsets and
lengths as varints, gzip-compressed. Tiles with the same bytes (a uniform sea, say) are stored
once. The tiles are written in id order (a *clustered* archive).
"""

from __future__ import annotations

import gzip
import hashlib
import json
import os
import shutil
import struct
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path

from .._atomic import atomic_output
from ..errors import InputError

__all__ = ["PMTILES_TYPES", "pmtiles_tile_id", "write_pmtiles"]

#: PMTiles' tile type codes of the tile formats written here.
PMTILES_TYPES = {"png": 2, "webp": 4}
_MAGIC = b"PMTiles\x03"
_HEADER = 127
#: The root directory must end within the first 16 KiB (the header included).
_ROOT_MAX = 16384 - _HEADER
#: Internal compression: gzip; tile compression: none (PNG and WebP are compressed).
_GZIP, _NONE = 2, 1
_MAX_ZOOM = 26  # ids stay below 2**53 (JavaScript's numbers), as the specification says


def pmtiles_tile_id(z: int, x: int, y: int) -> int:
    """The PMTiles id of tile ``(z, x, y)``: the ``(4**z - 1) / 3`` tiles of levels
    ``0 .. z - 1``, plus the tile's index along its level's Hilbert curve."""
    if not 0 <= z <= _MAX_ZOOM:
        raise InputError(f"zoom: expected 0..{_MAX_ZOOM}, got {z}")
    n = 1 << z
    if not (0 <= x < n and 0 <= y < n):
        raise InputError(f"tile ({z}, {x}, {y}): x and y must lie in 0..{n - 1}")
    d = 0
    s = n >> 1
    while s > 0:
        rx = 1 if x & s else 0
        ry = 1 if y & s else 0
        d += s * s * ((3 * rx) ^ ry)
        # rotate the quadrant (the curve's orientation in the next level down)
        if ry == 0:
            if rx == 1:
                x, y = s - 1 - x, s - 1 - y
            x, y = y, x
        s >>= 1
    return (n * n - 1) // 3 + d


def _varint(v: int, out: bytearray) -> None:
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)


def _directory(entries: Sequence[tuple[int, int, int, int]]) -> bytes:
    """Entries ``(tile id, offset, length, run length)``, sorted by id, as a gzip-compressed
    PMTiles directory: the count, then the id deltas, run lengths, lengths and offsets (0
    where an entry's bytes follow the previous entry's, else offset + 1), varints."""
    out = bytearray()
    _varint(len(entries), out)
    last = 0
    for tid, _, _, _ in entries:
        _varint(tid - last, out)
        last = tid
    for _, _, _, run in entries:
        _varint(run, out)
    for _, _, length, _ in entries:
        _varint(length, out)
    for i, (_, offset, _, _) in enumerate(entries):
        prev = entries[i - 1] if i else None
        _varint(0 if prev is not None and offset == prev[1] + prev[2] else offset + 1, out)
    return gzip.compress(bytes(out), mtime=0)


def _directories(entries: list[tuple[int, int, int, int]]) -> tuple[bytes, bytes]:
    """``(root, leaves)``: all entries in the root if it fits in the first 16 KiB, else leaf
    directories of 4096 entries (doubled until the root that lists them fits)."""
    root = _directory(entries)
    if len(root) <= _ROOT_MAX:
        return root, b""
    size = 4096
    while True:
        leaves = bytearray()
        index = []
        for i in range(0, len(entries), size):
            leaf = _directory(entries[i : i + size])
            # a root entry with run length 0 points to a leaf directory
            index.append((entries[i][0], len(leaves), len(leaf), 0))
            leaves += leaf
        root = _directory(index)
        if len(root) <= _ROOT_MAX:
            return root, bytes(leaves)
        size *= 2


def _e7(v: float) -> int:
    return round(float(v) * 1e7)


def write_pmtiles(
    tiles: Iterable[tuple[int, int, int, Path]],
    path: str | os.PathLike,
    *,
    fmt: str,
    bounds: Sequence[float],
    name: str,
) -> Path:
    """Write the tiles ``(z, x, y, file)`` (their encoded bytes in ``file``) as a PMTiles
    archive (atomically: nothing is left of a failed write).

    Parameters
    ----------
    tiles : iterable of (int, int, int, Path)
        The tiles, in any order; at least one.
    path : str or path-like
        The ``.pmtiles`` file; its folder must exist.
    fmt : {"png", "webp"}
        The tiles' encoding.
    bounds : (west, south, east, north)
        The data's extent in degrees (the header's bounds; its centre is the view's start).
    name : str
        The archive's name (metadata).

    Returns
    -------
    pathlib.Path
    """
    p = Path(path)
    if p.suffix.lower() != ".pmtiles":
        raise InputError(f"path: expected a file name ending in .pmtiles, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"path: no such directory {str(p.parent)!r}")
    if fmt not in PMTILES_TYPES:
        raise InputError(f"fmt: expected one of {', '.join(PMTILES_TYPES)}, got {fmt!r}")
    order = sorted((pmtiles_tile_id(z, x, y), z, file) for z, x, y, file in tiles)
    if not order:
        raise InputError(f"{p}: no tiles to write (every tile was empty)")
    entries: list[tuple[int, int, int, int]] = []
    stored: dict[bytes, tuple[int, int]] = {}  # sha-256 of a tile's bytes: (offset, length)
    end = 0
    with atomic_output(p) as part, tempfile.TemporaryFile(dir=p.parent) as data:
        for tid, _, file in order:
            blob = Path(file).read_bytes()
            key = hashlib.sha256(blob).digest()
            if key in stored:
                offset, length = stored[key]
            else:
                offset, length = end, len(blob)
                data.write(blob)
                stored[key] = (offset, length)
                end += length
            last = entries[-1] if entries else None
            if last is not None and last[1] == offset and last[0] + last[3] == tid:
                entries[-1] = (last[0], last[1], last[2], last[3] + 1)  # a run of one tile
            else:
                entries.append((tid, offset, length, 1))
        root, leaves = _directories(entries)
        west, south, east, north = (float(v) for v in bounds)
        zooms = [z for _, z, _ in order]
        meta = {
            "name": name, "format": fmt, "type": "baselayer", "version": "1",
            "description": "topographic map (sciviz_gbuf)",
            "bounds": f"{west},{south},{east},{north}",
            "minzoom": min(zooms), "maxzoom": max(zooms),
        }  # fmt: skip
        metadata = gzip.compress(json.dumps(meta).encode(), mtime=0)
        m_off = _HEADER + len(root)
        l_off = m_off + len(metadata)
        d_off = l_off + len(leaves)
        header = _MAGIC + struct.pack(
            "<11Q4B2B4iB2i",
            _HEADER, len(root), m_off, len(metadata), l_off, len(leaves), d_off, end,
            len(order), len(entries), len(stored),
            1, _GZIP, _NONE, PMTILES_TYPES[fmt], min(zooms), max(zooms),
            _e7(west), _e7(south), _e7(east), _e7(north),
            min(zooms), _e7((west + east) / 2), _e7((south + north) / 2),
        )  # fmt: skip
        with open(part.path, "wb") as f:
            f.write(header + root + metadata + leaves)
            data.seek(0)
            shutil.copyfileobj(data, f, 8 * 2**20)
        part.expected_size = d_off + end
    return p
