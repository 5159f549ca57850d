"""Checks of mesh files and datasets before VTK's readers and filters touch them.

VTK trusts what a file says: its PLY reader allocates whatever the header declares and reads
past the end of a truncated body (a segfault or ``std::bad_alloc``), its legacy reader loops
on a lying ``POINTS`` count, and its filters index the point array with whatever the
connectivity holds (a segfault for an index past the points or below zero). So, in order:

1. :func:`check_file`: cheap header and size checks per format, before any allocation
   (declared counts against the file size, text formats must be text);
2. :func:`read_isolated`: a reader that cannot be checked cheaply parses in a child process
   with a time limit, and its death becomes an :class:`~sciviz_gbuf.errors.InputError`;
3. :func:`check_dataset`: connectivity in range, offsets consistent, cell sizes matching
   their types, finite points, for every dataset (from a file or given in memory).

:func:`vtk_messages` keeps VTK's output window, logger and PyVista's warnings off stderr and
folds what they report into one line for the error message.
"""

from __future__ import annotations

import logging
import multiprocessing
import pickle
import re
import signal
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

from ..errors import InputError

__all__ = [
    "ISOLATED_TIMEOUT",
    "VTKMessages",
    "check_dataset",
    "check_file",
    "fold",
    "read_isolated",
    "vtk_messages",
]

#: Seconds a child process may take to parse a file that cannot be checked beforehand.
ISOLATED_TIMEOUT = 120.0

# ---------------------------------------------------------------------------- messages


def fold(text: str, limit: int = 300) -> str:
    """One line of at most ``limit`` characters: whitespace runs (newlines too) become one
    space, VTK's object addresses ``(0x55d5...)`` are dropped."""
    text = re.sub(r"\s*\(0x[0-9a-fA-F]+\)", "", str(text))
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


class VTKMessages:
    """What VTK and PyVista reported inside a :func:`vtk_messages` block."""

    def __init__(self) -> None:
        self.window = vtkStringOutputWindow()
        self.caught: list[warnings.WarningMessage] = []

    def _blocks(self) -> list[tuple[str, str]]:
        raw = self.window.GetOutput()
        if isinstance(raw, bytes):
            raw = raw.decode("utf-8", errors="replace")
        out = []
        # Each report is "LEVEL: In file.cxx, line N\nvtkClass (0x...): text\n\n\n".
        for block in re.split(r"\n\s*\n", raw or ""):
            lines = [ln for ln in block.strip().splitlines() if ln.strip()]
            if not lines:
                continue
            level = "error" if lines[0].upper().startswith("ERROR") else "warning"
            body = lines[1:] if re.match(r"^\w[\w ]*: In ", lines[0]) else lines
            # The executive's "returned failure for request" dumps a vtkInformation: noise.
            body = [ln for ln in body if not ln.startswith(" ")] or body
            out.append((level, fold(" ".join(body))))
        return out

    @property
    def errors(self) -> list[str]:
        """VTK error reports (one line each), and warnings that report an error."""
        errs = [t for lvl, t in self._blocks() if lvl == "error" or "rror" in t]
        errs += [fold(str(w.message)) for w in self.caught if "rror" in str(w.message)]
        return errs

    def first_error(self) -> str | None:
        """The most telling error: the first that is not the pipeline's generic epilogue."""
        errs = self.errors
        useful = [e for e in errs if "returned failure for request" not in e]
        return (useful or errs or [None])[0]


@contextmanager
def vtk_messages() -> Iterator[VTKMessages]:
    """Collect, instead of printing, what VTK (output window, logger) and PyVista (warnings,
    logging) report in the block; the caller folds it into its own message."""
    msgs = VTKMessages()
    previous = vtkOutputWindow.GetInstance()
    vtkOutputWindow.SetInstance(msgs.window)
    # vtkLogger has no getter for the stderr level: restore VTK's default (INFO) afterwards.
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    disabled = logging.root.manager.disable
    logging.disable(logging.CRITICAL)  # PyVista logs VTK's errors through the root logger
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                yield msgs
            finally:
                msgs.caught = [w for w in caught if not issubclass(w.category, DeprecationWarning)]
    finally:
        logging.disable(disabled)
        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_INFO)
        vtkOutputWindow.SetInstance(previous)


# ---------------------------------------------------------------------------- file checks

_HEAD = 1 << 20  # headers are searched in the first MiB
_TEXT_OK = bytes(range(32, 127)) + b"\t\n\r\f\v"


def _text(data: bytes, shown: str, what: str) -> None:
    """A text format holds text: flipped or binary bytes are refused, with where."""
    if not data.translate(None, _TEXT_OK):
        return
    try:
        data.decode("utf-8")  # names and comments may be UTF-8
        bad = next((i for i, b in enumerate(data) if b < 32 and b not in b"\t\n\r\f\v"), None)
    except UnicodeDecodeError as exc:
        bad = exc.start
    if bad is not None:
        raise InputError(
            f"{shown}: byte {bad} (0x{data[bad]:02x}) is not text: the {what} file is corrupt"
        )


def _check_stl(data: bytes, shown: str) -> None:
    size = len(data)
    n = int(np.frombuffer(data[80:84], "<u4")[0]) if size >= 84 else -1
    if n >= 0 and size == 84 + 50 * n:
        if n == 0:
            raise InputError(f"{shown}: the binary STL file holds no triangles")
        return
    if data[:1024].lstrip().lower().startswith(b"solid") and not data[:1024].translate(
        None, _TEXT_OK
    ):
        _text(data, shown, "ASCII STL")
        if b"endsolid" not in data[-1024:].lower():
            raise InputError(f"{shown}: the ASCII STL file is truncated (no 'endsolid' at its end)")
        return
    if n < 0:
        raise InputError(f"{shown}: {size} bytes is too short for an STL file (84 at least)")
    raise InputError(
        f"{shown}: the binary STL header declares {n} triangles ({84 + 50 * n} bytes) but the "
        f"file has {size} bytes (truncated, or not an STL file)"
    )


_PLY_SIZE = {
    **dict.fromkeys(("char", "uchar", "int8", "uint8"), 1),
    **dict.fromkeys(("short", "ushort", "int16", "uint16"), 2),
    **dict.fromkeys(("int", "uint", "int32", "uint32", "float", "float32"), 4),
    **dict.fromkeys(("double", "float64"), 8),
}
_PLY_DTYPE = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
}  # fmt: skip


def _ply_header(data: bytes, shown: str) -> tuple[str, list, int]:
    """(format, [(element, count, [(name, type) | (name, count type, item type)])], body)."""
    m = re.search(rb"\bend_header[ \t]*\r?\n", data[:_HEAD])
    if not data.startswith(b"ply") or m is None:
        raise InputError(f"{shown}: not a PLY file (expected 'ply' ... 'end_header' at its start)")
    fmt, elements = None, []
    for raw in data[: m.start()].decode("ascii", errors="replace").splitlines()[1:]:
        tok = raw.split()
        if not tok or tok[0] in ("comment", "obj_info"):
            continue
        if tok[0] == "format" and len(tok) >= 2:
            fmt = tok[1]
        elif tok[0] == "element" and len(tok) == 3 and tok[2].isdigit():
            elements.append((tok[1], int(tok[2]), []))
        elif tok[0] == "property" and elements and len(tok) == 3 and tok[1] in _PLY_SIZE:
            elements[-1][2].append((tok[2], tok[1]))
        elif (
            tok[0] == "property" and elements and len(tok) == 5 and tok[1] == "list"
            and tok[2] in _PLY_DTYPE and tok[3] in _PLY_SIZE
        ):  # fmt: skip
            elements[-1][2].append((tok[4], tok[2], tok[3]))
        else:
            raise InputError(f"{shown}: PLY header line not understood: {fold(raw, 80)!r}")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise InputError(f"{shown}: PLY format {fmt!r} not understood")
    return fmt, elements, m.end()


def _ply_binary_rows(body: np.ndarray, offset: int, count: int, props: list, order: str) -> int:
    """Offset after ``count`` rows of one element, or -1 if the body ends first."""
    size = len(body)
    if all(len(p) == 2 for p in props):
        end = offset + count * sum(_PLY_SIZE[p[1]] for p in props)
        return end if end <= size else -1
    # Fast path: every row has the list lengths of the first (all triangles, say); the
    # lengths are checked at a fixed stride with one numpy view.
    pos, lengths = offset, []
    for p in props:
        if len(p) == 3:
            if pos + _PLY_SIZE[p[1]] > size:
                return -1
            k = int(body[pos : pos + _PLY_SIZE[p[1]]].view(order + _PLY_DTYPE[p[1]])[0])
            if k < 0:
                return -1
            lengths.append((pos - offset, p[1], k))
            pos += _PLY_SIZE[p[1]] + k * _PLY_SIZE[p[2]]
        else:
            pos += _PLY_SIZE[p[1]]
    row = pos - offset
    if row > 0 and offset + count * row <= size:
        uniform = True
        for at, ctype, k in lengths:
            width = _PLY_SIZE[ctype]
            block = body[offset : offset + count * row].reshape(count, row)[:, at : at + width]
            if not np.all(np.ascontiguousarray(block).view(order + _PLY_DTYPE[ctype]) == k):
                uniform = False
                break
        if uniform:
            return offset + count * row
    # Mixed list lengths: walk the rows (stops as soon as the body is overrun).
    pos = offset
    for _ in range(count):
        for p in props:
            if len(p) == 2:
                pos += _PLY_SIZE[p[1]]
                continue
            width = _PLY_SIZE[p[1]]
            if pos + width > size:
                return -1
            k = int(body[pos : pos + width].view(order + _PLY_DTYPE[p[1]])[0])
            if k < 0:
                return -1
            pos += width + k * _PLY_SIZE[p[2]]
        if pos > size:
            return -1
    return pos


def _ply_ascii_rows(lines: list[bytes], elements: list, shown: str, declared: str) -> None:
    """Every row of an ASCII PLY body on its line with exactly the values its properties take
    (a truncated file loses rows or ends inside one; VTK would read zeros instead)."""
    rows = iter(ln for ln in lines if ln.strip())
    for name, count, props in elements:
        for r in range(count):
            tok = next(rows, None)
            if tok is None:
                raise InputError(
                    f"{shown}: the PLY header declares {declared} but the body ends in the "
                    f"{name!r} rows after {r} of them (truncated, or a lying header)"
                )
            tok = tok.split()
            pos = 0
            for p in props:
                if len(p) == 3 and pos < len(tok):
                    k = int(tok[pos]) if tok[pos].isdigit() else -1
                    pos += 1 + k if k >= 0 else len(tok) + 1
                else:
                    pos += 1
            if pos != len(tok):
                raise InputError(
                    f"{shown}: {name!r} row {r} of the PLY body has {len(tok)} values, not "
                    "what its properties declare (truncated or corrupt)"
                )


def _check_ply(data: bytes, shown: str) -> None:
    fmt, elements, start = _ply_header(data, shown)
    declared = ", ".join(f"{n} {name}" for name, n, _ in elements)
    if fmt == "ascii":
        body = data[start:]
        _text(body, shown, "ASCII PLY")
        _ply_ascii_rows(body.split(b"\n"), elements, shown, declared)
        return
    order = "<" if fmt == "binary_little_endian" else ">"
    body = np.frombuffer(data, dtype=np.uint8)
    pos = start
    for name, count, props in elements:
        pos = _ply_binary_rows(body, pos, count, props, order)
        if pos < 0:
            raise InputError(
                f"{shown}: the PLY header declares {declared} but the file ends (at "
                f"{len(data)} bytes) inside the {name!r} rows (truncated, or a lying header)"
            )


_VTK_TYPE = {
    "bit": 1, "unsigned_char": 1, "char": 1, "unsigned_short": 2, "short": 2, "unsigned_int": 4,
    "int": 4, "unsigned_long": 8, "long": 8, "float": 4, "double": 8, "vtktypeint64": 8,
    "vtktypeuint64": 8, "vtkidtype": 8,
}  # fmt: skip


_VTK_KEYWORD = re.compile(
    rb"(?m)^(POINTS|CELLS|POLYGONS|LINES|VERTICES|TRIANGLE_STRIPS|CELL_TYPES|OFFSETS|"
    rb"CONNECTIVITY)[ \t]+(\S+)(?:[ \t]+(\S+))?"
)


# Attribute keywords of a POINT_DATA/CELL_DATA section: values per tuple and header tokens.
_VTK_ATTR = {b"NORMALS": (3, 2), b"VECTORS": (3, 2), b"TENSORS": (9, 2), b"TENSORS6": (6, 2)}
_VTK_SECTIONS = {
    *_VTK_ATTR, b"POINTS", b"POLYGONS", b"LINES", b"VERTICES", b"TRIANGLE_STRIPS", b"CELLS",
    b"CELL_TYPES", b"POINT_DATA", b"CELL_DATA", b"SCALARS", b"TEXTURE_COORDINATES", b"FIELD",
    b"COLOR_SCALARS", b"LOOKUP_TABLE",
}  # fmt: skip


def _walk_legacy_ascii(tok: list[bytes], shown: str) -> None:
    """Count the values of every section of an ASCII legacy file against its keyword line.

    VTK's reader silently keeps a short last array (a truncated file draws as if whole);
    sections this walk does not know end it without complaint (VTK still parses them).
    """
    i, n_tok, tuples = 0, len(tok), 0

    def skip(count: int, what: str) -> int:
        if i + count > n_tok:
            raise InputError(
                f"{shown}: the VTK file ends inside its {what} section ({n_tok - i} of "
                f"{count} values): truncated, or a lying header"
            )
        return i + count

    def num(j: int) -> int:
        return int(tok[j]) if j < n_tok and tok[j].isdigit() else -1

    while i < n_tok:
        key = tok[i].upper()
        if key == b"POINTS" and num(i + 1) >= 0:
            count, i = num(i + 1), i + 3
            i = skip(3 * count, "POINTS")
        elif key in (b"POLYGONS", b"LINES", b"VERTICES", b"TRIANGLE_STRIPS", b"CELLS"):
            n, m, i = num(i + 1), num(i + 2), i + 3
            if n < 0 or m < 0:
                return
            if i < n_tok and tok[i].upper() == b"OFFSETS":
                i = skip(n + 2, key.decode())  # OFFSETS type, n values
                if i >= n_tok or tok[i].upper() != b"CONNECTIVITY":
                    return
                i = skip(m + 2, key.decode())
            else:
                i = skip(m, key.decode())
        elif key == b"CELL_TYPES" and num(i + 1) >= 0:
            count, i = num(i + 1), i + 2
            i = skip(count, "CELL_TYPES")
        elif key in (b"POINT_DATA", b"CELL_DATA") and num(i + 1) >= 0:
            tuples, i = num(i + 1), i + 2
        elif key == b"SCALARS" and tuples:
            # SCALARS name type [components], then LOOKUP_TABLE name
            j = i + 3
            comps = num(j) if num(j) > 0 else 1
            j += 1 if num(j) > 0 else 0
            if j < n_tok and tok[j].upper() == b"LOOKUP_TABLE":
                j += 2
            i = j
            i = skip(tuples * comps, "SCALARS")
        elif key in _VTK_ATTR and tuples:
            per, head = _VTK_ATTR[key]
            i += 1 + head
            i = skip(tuples * per, key.decode())
        elif key == b"TEXTURE_COORDINATES" and tuples and num(i + 2) > 0:
            dim, i = num(i + 2), i + 4
            i = skip(tuples * dim, "TEXTURE_COORDINATES")
        elif key in (b"#", b"DATASET", b"ASCII", b"POLYDATA", b"UNSTRUCTURED_GRID"):
            i += 1
        elif key == b"METADATA":
            # INFORMATION/NAME/DATA records up to a blank line: on to the next section.
            i += 1
            while i < n_tok and tok[i].upper() not in _VTK_SECTIONS:
                i += 1
        else:
            return  # FIELD, METADATA, LOOKUP_TABLE tables, ...: left to VTK


def _check_legacy_vtk(data: bytes, shown: str) -> None:
    lines = data[:4096].split(b"\n", 4)
    if len(lines) < 4 or not lines[0].startswith(b"# vtk DataFile"):
        raise InputError(f"{shown}: not a legacy VTK file (expected '# vtk DataFile Version')")
    binary = lines[2].strip().upper() == b"BINARY"
    if not binary:
        _text(data, shown, "ASCII VTK")
        # after the version line and the title (free text)
        rest = data.split(b"\n", 2)[2] if data.count(b"\n") >= 2 else b""
        _walk_legacy_ascii(rest.split(), shown)
    # Values the keyword lines declare, and the bytes they need at least: checked before VTK's
    # reader allocates them (it loops for minutes on a lying POINTS count).
    need = 0
    for m in _VTK_KEYWORD.finditer(data):
        key, a, b = m.group(1), m.group(2), m.group(3)
        if key == b"POINTS" and a.isdigit():
            width = _VTK_TYPE.get((b or b"float").decode("ascii", "replace").lower(), 4)
            need += 3 * int(a) * (width if binary else 2)
        elif key == b"CELL_TYPES" and a.isdigit():
            need += int(a) * (4 if binary else 2)
        elif key in (b"OFFSETS", b"CONNECTIVITY"):
            continue  # counted with their cell section
        elif a.isdigit() and b is not None and b.isdigit():
            # classic layout: b values; 5.1 layout: a offsets + b connectivity
            values = int(b) + (int(a) if b"OFFSETS" in data[m.end() : m.end() + 64] else 0)
            need += values * (4 if binary else 2)
    if need > len(data) + 1:
        raise InputError(
            f"{shown}: the VTK header declares data of at least {need} bytes but the file has "
            f"{len(data)} (truncated, or a lying header)"
        )


def _check_xml(data: bytes, shown: str) -> None:
    # A compressed array shrinks by 1032x at most (zlib); an uncompressed one takes at least
    # a byte per value. A declared count beyond that is a lie VTK would try to allocate.
    ratio = 1032 if b"compressor=" in data[:_HEAD] else 1
    for key, per in ((rb"NumberOfPoints", 3), (rb"NumberOfCells", 1), (rb"NumberOfPolys", 1)):
        for m in re.finditer(key + rb'="(\d+)"', data[:_HEAD]):
            if int(m.group(1)) * per > len(data) * ratio:
                raise InputError(
                    f"{shown}: the file declares {key.decode()}={m.group(1)}, more than "
                    f"{len(data)} bytes can hold (truncated, or a lying header)"
                )


_CHECKS = {
    ".stl": _check_stl,
    ".ply": _check_ply,
    ".vtk": _check_legacy_vtk,
    ".obj": lambda data, shown: _text(data, shown, "OBJ"),
    ".vtp": _check_xml,
    ".vtu": _check_xml,
    ".vts": _check_xml,
    ".vtr": _check_xml,
    ".vti": _check_xml,
}

#: Suffixes whose reader is not run in a child: their files are checked beforehand (above).
CHECKED_SUFFIXES = frozenset(_CHECKS)


def check_file(path: Path, shown: str) -> None:
    """Cheap checks of a mesh file before any reader allocates what it declares.

    Raises
    ------
    InputError
        Empty file, counts that the file size cannot hold, a truncated body, binary bytes in
        a text format; the message names ``shown`` (the path as the user gave it).
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{shown}: cannot read ({fold(exc.strerror or exc)})") from exc
    if not data.strip():
        raise InputError(f"{shown}: the file is empty")
    check = _CHECKS.get(path.suffix.lower())
    if check is not None:
        check(data, shown)


# ---------------------------------------------------------------------------- isolated reads


def _child_read(path: str, conn) -> None:  # pragma: no cover - runs in the child
    with vtk_messages() as msgs:
        try:
            data = pv.read(path)
            err = msgs.first_error()
            payload = ("error", err) if err else ("ok", pickle.dumps(data))
        except Exception as exc:  # reported to the parent as text
            payload = ("error", fold(f"{exc}"))
    conn.send(payload)
    conn.close()


def read_isolated(path: Path, shown: str, timeout: float = ISOLATED_TIMEOUT) -> pv.DataObject:
    """``pyvista.read`` in a child process: a reader that crashes, aborts or hangs on a bad
    file costs the child, and the caller gets an InputError naming the file."""
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    ctx = multiprocessing.get_context(method)
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child_read, args=(str(path), child), daemon=True)
    proc.start()
    child.close()
    try:
        if not parent.poll(timeout):
            raise InputError(
                f"{shown}: reading took more than {timeout:g} s (the file is corrupt?)"
            )
        status, payload = parent.recv()
    except EOFError:
        proc.join(5)
        code = proc.exitcode
        how = (
            f"signal {signal.Signals(-code).name}" if code is not None and code < 0
            else f"exit status {code}"
        )  # fmt: skip
        raise InputError(
            f"{shown}: VTK's reader crashed on this file ({how}): it is truncated or corrupt"
        ) from None
    finally:
        parent.close()
        if proc.is_alive():
            proc.kill()
        proc.join(5)
    if status != "ok":
        raise InputError(f"{shown}: cannot read as a mesh ({payload})")
    return pickle.loads(payload)


# ---------------------------------------------------------------------------- datasets

# Point count of each fixed-size VTK cell type (minimum for the variable ones).
_CELL_POINTS = {
    0: 0, 1: 1, 3: 2, 5: 3, 8: 4, 9: 4, 10: 4, 11: 8, 12: 8, 13: 6, 14: 5, 15: 10, 16: 12,
    21: 3, 22: 6, 23: 8, 24: 10, 25: 20, 26: 15, 27: 13, 28: 9, 29: 27, 30: 6, 31: 12, 32: 18,
    33: 24, 34: 7, 35: 4, 37: 19,
}  # fmt: skip
_CELL_MIN_POINTS = {2: 1, 4: 2, 6: 3, 7: 3, 36: 6, 41: 1, 42: 4}
_CELL_MIN_POINTS.update(dict.fromkeys(range(68, 82), 2))  # Lagrange and Bezier cells


def _array(vtk_array) -> np.ndarray:
    if vtk_array is None:
        return np.zeros(0, dtype=np.int64)
    return np.asarray(pv.convert_array(vtk_array))


def _check_cells(name: str, what: str, cells, n_points: int) -> np.ndarray:
    """Offsets consistent and every index in ``[0, n_points)``; returns the cell sizes."""
    offsets = _array(cells.GetOffsetsArray()).astype(np.int64, copy=False)
    conn = _array(cells.GetConnectivityArray())
    if offsets.size == 0:
        if conn.size:
            raise InputError(f"{name}: {what} connectivity without offsets")
        return np.zeros(0, dtype=np.int64)
    sizes = np.diff(offsets)
    if offsets[0] != 0 or offsets[-1] != conn.size or (sizes < 0).any():
        raise InputError(
            f"{name}: {what} offsets do not describe the connectivity array "
            f"(expected 0 ... {conn.size}, increasing)"
        )
    if conn.size:
        lo, hi = int(conn.min()), int(conn.max())
        if lo < 0:
            raise InputError(f"{name}: {what} connectivity holds a negative point index ({lo})")
        if hi >= n_points:
            raise InputError(
                f"{name}: {what} connectivity refers to point {hi} but the mesh has "
                f"{n_points} points"
            )
    return sizes


def check_dataset(ds: object, name: str) -> None:
    """Refuse a dataset VTK's filters would crash on or draw wrongly.

    Checks that every cell index lies in the point array (no negative index, none past the
    end), that offsets describe the connectivity, that unstructured cells have a known type
    with as many points as the type needs, and that all points are finite.

    Raises
    ------
    InputError
        Naming ``name`` (the file, or ``dataset i (Type)`` for in-memory data).
    """
    data = pv.wrap(ds)
    if isinstance(data, pv.MultiBlock):
        for i, block in enumerate(data):
            if block is not None:
                check_dataset(block, f"{name} block {i}")
        return
    if isinstance(data, (pv.PolyData, pv.UnstructuredGrid, pv.StructuredGrid, pv.PointSet)):
        pts = np.asarray(data.points) if data.GetPoints() is not None else np.zeros((0, 3))
        if pts.size and not np.isfinite(pts).all():
            bad = int(np.count_nonzero(~np.isfinite(pts).all(axis=1)))
            raise InputError(f"{name}: {bad} point(s) have NaN or infinite coordinates")
    elif isinstance(data, (pv.ImageData, pv.RectilinearGrid)):
        bounds = np.asarray(data.bounds, dtype=np.float64)
        if not np.isfinite(bounds).all():
            raise InputError(f"{name}: the grid has NaN or infinite origin, spacing or coordinates")
    n = data.n_points
    if isinstance(data, pv.PolyData):
        for what, cells in (
            ("vertex", data.GetVerts()),
            ("line", data.GetLines()),
            ("polygon", data.GetPolys()),
            ("strip", data.GetStrips()),
        ):
            if cells is not None:
                _check_cells(name, what, cells, n)
    elif isinstance(data, pv.UnstructuredGrid):
        if data.GetCells() is None:
            return
        sizes = _check_cells(name, "cell", data.GetCells(), n)
        types = np.asarray(data.celltypes, dtype=np.int64)
        if types.size != sizes.size:
            raise InputError(f"{name}: {types.size} cell types for {sizes.size} cells")
        fixed = np.full(256, -1, dtype=np.int64)
        least = np.full(256, -1, dtype=np.int64)
        for t, k in _CELL_POINTS.items():
            fixed[t] = k
        for t, k in _CELL_MIN_POINTS.items():
            least[t] = k
        t = types.clip(0, 255)
        unknown = (types != t) | ((fixed[t] < 0) & (least[t] < 0))
        if unknown.any():
            i = int(np.flatnonzero(unknown)[0])
            raise InputError(f"{name}: cell {i} has type {int(types[i])}, which VTK does not know")
        wrong = ((fixed[t] >= 0) & (sizes != fixed[t])) | ((least[t] >= 0) & (sizes < least[t]))
        if wrong.any():
            i = int(np.flatnonzero(wrong)[0])
            cls = pv.CellType(int(t[i])).name
            need = fixed[t[i]] if fixed[t[i]] >= 0 else f"at least {least[t[i]]}"
            raise InputError(
                f"{name}: cell {i} is a {cls} with {int(sizes[i])} points (expected {need})"
            )
        faces = data.GetPolyhedronFaces() if hasattr(data, "GetPolyhedronFaces") else None
        if faces is not None and faces.GetNumberOfCells():
            _check_cells(name, "polyhedron face", faces, n)
