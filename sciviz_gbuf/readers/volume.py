"""Volume files -> PyVista volume in patient coordinates (LPS, mm): NRRD, MetaImage, NIfTI.

The same volume as :func:`~sciviz_gbuf.readers.read_dicom_series` makes of a DICOM series: an
:class:`pyvista.ImageData` with point array ``"HU"`` (float32, the stored values with the file's
own rescaling), its ``origin``, ``spacing`` and ``direction_matrix`` placing voxel ``(i, j, k)``
at ``origin + direction @ (i * sx, j * sy, k * sz)`` in LPS millimetres (x to the patient's
left, y posterior, z superior: DICOM's frame, so a volume looks the same whichever file it came
from). Files are opened read-only.

- **NRRD** (``.nrrd`` with the data attached, ``.nhdr`` with a detached data file): the header's
  ``space`` (``left-posterior-superior`` / ``LPS``, ``right-anterior-superior`` / ``RAS``,
  ``left-anterior-superior`` / ``LAS``), ``space directions`` and ``space origin``; without
  them ``spacings`` (or 1) along the axes. Encodings ``raw``, ``gzip`` and ``ascii``.
- **MetaImage** (``.mha`` attached, ``.mhd`` + ``ElementDataFile``): ``Offset`` (or
  ``Position`` / ``Origin``), ``ElementSpacing``, ``TransformMatrix`` (its rows: the directions
  of the i, j, k axes, as ITK writes them), in ITK's LPS space; zlib ``CompressedData``.
- **NIfTI-1/2** (``.nii``, ``.nii.gz``, read by nibabel): the sform (or qform) affine, RAS+
  by definition, turned into LPS; ``scl_slope`` / ``scl_inter`` applied.

Only single-channel 3-D volumes (a 2-D image is one slice); anything else (vectors, time
series, unknown encodings or types, a data file shorter than the header says) raises
:class:`~sciviz_gbuf.errors.InputError` naming the file and what was expected.
"""

from __future__ import annotations

import os
import re
import zlib
from pathlib import Path

import numpy as np
import pyvista as pv

from .. import _validate
from ..errors import InputError
from .formats import suffix_of, suffixes

__all__ = ["VOLUME_SUFFIXES", "read_volume"]

#: File names this module reads (``.nii.gz`` is matched on the whole name).
VOLUME_SUFFIXES = suffixes("volume")
# Largest header read as text (a header is a few hundred bytes).
_MAX_HEADER = 1 << 20
# RAS <-> LPS: x and y change sign.
_FLIP = np.diag([-1.0, -1.0, 1.0])


def read_volume(path: str | os.PathLike) -> pv.ImageData:
    """Read a NRRD, MetaImage or NIfTI volume (see the module notes for each format).

    Parameters
    ----------
    path : str or path-like
        ``.nrrd``, ``.nhdr``, ``.mha``, ``.mhd``, ``.nii`` or ``.nii.gz``.

    Returns
    -------
    pyvista.ImageData
        Point array ``"HU"`` (float32, Fortran order: ``ds["HU"].reshape(nz, ny, nx)[k, j, i]``
        is voxel (i, j, k)), ``origin``, ``spacing`` (mm) and an orthonormal
        ``direction_matrix`` in LPS; ``field_data["volume_source"]`` names the file and format.

    Raises
    ------
    InputError
        A missing file, an unknown suffix, or a file that is not a single-channel 3-D volume
        of a known encoding (the message names the file and the field).
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such file")
    suffix = suffix_of(p)
    if suffix not in VOLUME_SUFFIXES:
        raise InputError(f"{p}: expected a volume file ({', '.join(VOLUME_SUFFIXES)})")
    if suffix in (".nrrd", ".nhdr"):
        values, affine, fmt = _read_nrrd(p)
    elif suffix in (".mha", ".mhd"):
        values, affine, fmt = _read_meta(p)
    else:
        values, affine, fmt = _read_nifti(p)
    return _to_image(p, values, affine, fmt)


# ------------------------------------------------------------------ the volume


def _check_voxels(p: Path, sizes) -> None:
    """The header's size must fit in memory (the values and their float32 copy) before any
    data is read: a lying header fails with one line, not ``MemoryError``."""
    n = float(np.prod(np.asarray(sizes, dtype=np.float64)))
    _validate.check_memory(n * 12.0, str(p), f"a volume of {' x '.join(map(str, sizes))} voxels")


def _to_image(p: Path, values: np.ndarray, affine: np.ndarray, fmt: str) -> pv.ImageData:
    """``values`` indexed [i, j, k]; ``affine`` (4, 4): voxel index -> LPS mm."""
    if values.ndim == 2:
        values = values[:, :, None]
    if values.ndim != 3 or min(values.shape) < 1:
        raise InputError(f"{p}: expected a 3-D volume, got an array of shape {values.shape}")
    m = np.asarray(affine[:3, :3], dtype=np.float64)
    origin = np.asarray(affine[:3, 3], dtype=np.float64)
    if not (np.isfinite(m).all() and np.isfinite(origin).all()):
        raise InputError(f"{p}: the voxel-to-patient transform is not finite")
    spacing = np.linalg.norm(m, axis=0)
    if not (spacing > 0).all():
        raise InputError(f"{p}: an axis of the voxel grid has zero length (spacing {spacing})")
    direction = m / spacing
    # ImageData needs orthonormal axes: a sheared grid (rare outside tilted CT) is refused.
    if not np.allclose(direction.T @ direction, np.eye(3), atol=1e-4):
        raise InputError(
            f"{p}: the voxel axes are not orthogonal (a sheared grid); resample it to a "
            "rectangular grid first"
        )
    ds = pv.ImageData(dimensions=values.shape, spacing=tuple(spacing), origin=tuple(origin))
    ds.direction_matrix = direction
    ds.point_data["HU"] = np.asarray(values, dtype=np.float32).ravel(order="F")
    ds.field_data["volume_source"] = f"{p.name} ({fmt})"
    return ds


# ------------------------------------------------------------------ NRRD

_NRRD_TYPES = {
    "int8": "i1", "signed char": "i1", "int8_t": "i1", "char": "i1",
    "uint8": "u1", "uchar": "u1", "unsigned char": "u1", "uint8_t": "u1",
    "int16": "i2", "short": "i2", "short int": "i2", "signed short": "i2",
    "signed short int": "i2", "int16_t": "i2",
    "uint16": "u2", "ushort": "u2", "unsigned short": "u2", "unsigned short int": "u2",
    "uint16_t": "u2",
    "int32": "i4", "int": "i4", "signed int": "i4", "int32_t": "i4",
    "uint32": "u4", "uint": "u4", "unsigned int": "u4", "uint32_t": "u4",
    "int64": "i8", "longlong": "i8", "long long": "i8", "long long int": "i8",
    "signed long long": "i8", "signed long long int": "i8", "int64_t": "i8",
    "uint64": "u8", "ulonglong": "u8", "unsigned long long": "u8",
    "unsigned long long int": "u8", "uint64_t": "u8",
    "float": "f4", "double": "f8",
}  # fmt: skip
_SPACES = {
    "left-posterior-superior": np.eye(3),
    "lps": np.eye(3),
    "right-anterior-superior": _FLIP,
    "ras": _FLIP,
    "left-anterior-superior": np.diag([1.0, -1.0, 1.0]),
    "las": np.diag([1.0, -1.0, 1.0]),
}
_VECTOR = re.compile(r"\(([^)]*)\)|none", re.IGNORECASE)


def _header_lines(p: Path, raw: bytes, blank_ends: bool) -> tuple[list[str], int]:
    """The header lines of ``raw`` and the offset of the data after it (NRRD: up to the first
    blank line; MetaImage: through the ``ElementDataFile`` line)."""
    lines: list[str] = []
    pos = 0
    while pos < len(raw):
        end = raw.find(b"\n", pos)
        if end < 0:
            end = len(raw)
        line = raw[pos:end].rstrip(b"\r")
        pos = end + 1
        try:
            text = line.decode("ascii")
        except UnicodeDecodeError:
            raise InputError(f"{p}: the header is not text (not a volume header?)") from None
        if blank_ends and text.strip() == "":
            return lines, pos
        lines.append(text)
        if not blank_ends and text.split("=")[0].strip() == "ElementDataFile":
            return lines, pos
    return lines, len(raw)


def _data_bytes(p: Path, field: str, name: str | None, data_at: int) -> bytes:
    """The data of a header ``p``: its own bytes from ``data_at`` on (``name`` None), else the
    file ``name`` (header ``field``) beside it."""
    if name is None:
        with open(p, "rb") as f:
            f.seek(data_at)
            return f.read()
    src = (p.parent / name).resolve()
    if not src.is_file():
        raise InputError(f"{p}: {field}: {src} does not exist")
    return src.read_bytes()


def _numbers(p: Path, field: str, text: str, n: int | None = None) -> np.ndarray:
    try:
        vals = np.array([float(v) for v in text.replace(",", " ").split()], dtype=np.float64)
    except ValueError:
        raise InputError(f"{p}: {field}: expected numbers, got {text.strip()!r}") from None
    if n is not None and vals.size != n:
        raise InputError(f"{p}: {field}: expected {n} numbers, got {text.strip()!r}")
    return vals


def _read_nrrd(p: Path) -> tuple[np.ndarray, np.ndarray, str]:
    with open(p, "rb") as f:
        head = f.read(_MAX_HEADER)
    if not head.startswith(b"NRRD000"):
        raise InputError(f"{p}: not a NRRD file (expected the magic line 'NRRD000x')")
    lines, data_at = _header_lines(p, head, blank_ends=True)
    fields: dict[str, str] = {}
    for line in lines[1:]:
        if line.startswith("#") or ":=" in line:
            continue  # comments and key/value pairs
        key, sep, value = line.partition(": ")
        if not sep:
            raise InputError(f"{p}: header line {line!r} is not 'field: value'")
        fields[key.strip().lower()] = value.strip()
    for need in ("type", "dimension", "sizes", "encoding"):
        if need not in fields:
            raise InputError(f"{p}: the NRRD header has no '{need}' field")
    dim = int(_numbers(p, "dimension", fields["dimension"], 1)[0])
    sizes = _numbers(p, "sizes", fields["sizes"], dim).astype(np.int64)
    if dim not in (2, 3) or (sizes < 1).any():
        raise InputError(
            f"{p}: expected a 2-D or 3-D single-channel volume, got dimension {dim}, sizes "
            f"{fields['sizes']!r}"
        )
    _check_voxels(p, sizes)
    code = _NRRD_TYPES.get(fields["type"].lower())
    if code is None:
        raise InputError(f"{p}: type: {fields['type']!r} is not a NRRD scalar type")
    endian = fields.get("endian", "little").lower()
    if endian not in ("little", "big"):
        raise InputError(f"{p}: endian: expected 'little' or 'big', got {endian!r}")
    dtype = np.dtype(("<" if endian == "little" else ">") + code)
    # where the data is
    data_file = fields.get("data file", fields.get("datafile"))
    if data_file is not None:
        if data_file.upper().startswith("LIST") or " " in data_file.strip():
            raise InputError(f"{p}: data file: {data_file!r}: only one data file is supported")
        blob = _data_bytes(p, "data file", data_file, data_at)
    elif p.suffix.lower() == ".nhdr":
        raise InputError(f"{p}: a detached header (.nhdr) needs a 'data file' field")
    else:
        blob = _data_bytes(p, "data file", None, data_at)
    count = int(np.prod(sizes))
    values = _decode(p, blob, fields["encoding"].lower(), dtype, count, fields)
    values = values.reshape(tuple(sizes), order="F")  # the first axis runs fastest
    affine = _nrrd_affine(p, fields, dim)
    return values, affine, "NRRD"


def _decode(
    p: Path, blob: bytes, encoding: str, dtype: np.dtype, count: int, fields: dict[str, str]
) -> np.ndarray:
    skip = int(fields.get("byte skip", "0"))
    if encoding in ("ascii", "text", "txt"):
        vals = np.array(blob.decode("ascii", errors="replace").split(), dtype=np.float64)
        if vals.size < count:
            raise InputError(f"{p}: the data has {vals.size} values, the header says {count}")
        return vals[:count]
    if encoding in ("gzip", "gz"):
        blob = _inflate(p, blob, count * dtype.itemsize + max(skip, 0), wbits=31)
    elif encoding != "raw":
        raise InputError(
            f"{p}: encoding: {encoding!r} is not supported (expected raw, gzip or ascii)"
        )
    need = count * dtype.itemsize
    if skip == -1:
        skip = len(blob) - need  # NRRD: "-1" means the data is the last bytes of the file
    if skip < 0 or len(blob) - skip < need:
        raise InputError(
            f"{p}: the data is {max(len(blob) - skip, 0)} bytes, the header says {need} "
            f"({count} values of {dtype.name}): truncated?"
        )
    return np.frombuffer(blob, dtype=dtype, count=count, offset=skip)


def _inflate(p: Path, blob: bytes, need: int, wbits: int) -> bytes:
    """Decompress gzip (``wbits`` 31) or zlib (15) data, at most ``need`` bytes: a file that
    inflates beyond what its header says is not read past that."""
    try:
        out = zlib.decompressobj(wbits).decompress(blob, need)
    except zlib.error as exc:
        raise InputError(f"{p}: the compressed data cannot be decompressed ({exc})") from None
    return out


def _nrrd_affine(p: Path, fields: dict[str, str], dim: int) -> np.ndarray:
    affine = np.eye(4)
    if "space directions" in fields:
        space = fields.get("space", "left-posterior-superior").lower()
        if space not in _SPACES:
            raise InputError(
                f"{p}: space: {space!r} is not a patient space (expected "
                "left-posterior-superior, right-anterior-superior or left-anterior-superior)"
            )
        to_lps = _SPACES[space]
        vectors = [m.group(1) for m in _VECTOR.finditer(fields["space directions"])]
        if len(vectors) != dim or any(v is None for v in vectors):
            raise InputError(
                f"{p}: space directions: expected {dim} vectors, got {fields['space directions']!r}"
            )
        cols = [_numbers(p, "space directions", v, 3) for v in vectors]
        if dim == 2:
            cols.append(np.cross(cols[0], cols[1]) / np.linalg.norm(np.cross(cols[0], cols[1])))
        affine[:3, :3] = to_lps @ np.stack(cols, axis=1)
        origin = fields.get("space origin")
        if origin is not None:
            affine[:3, 3] = to_lps @ _numbers(p, "space origin", origin.strip("()"), 3)
        return affine
    if "spacings" in fields:
        sp = _numbers(p, "spacings", fields["spacings"].replace("nan", "1"), dim)
        affine[:dim, :dim] = np.diag(sp)
    return affine


# ------------------------------------------------------------------ MetaImage

_MET_TYPES = {
    "MET_CHAR": "i1", "MET_UCHAR": "u1", "MET_SHORT": "i2", "MET_USHORT": "u2",
    "MET_INT": "i4", "MET_UINT": "u4", "MET_LONG": "i4", "MET_ULONG": "u4",
    "MET_LONG_LONG": "i8", "MET_ULONG_LONG": "u8", "MET_FLOAT": "f4", "MET_DOUBLE": "f8",
}  # fmt: skip


def _read_meta(p: Path) -> tuple[np.ndarray, np.ndarray, str]:
    with open(p, "rb") as f:
        head = f.read(_MAX_HEADER)
    lines, data_at = _header_lines(p, head, blank_ends=False)
    fields: dict[str, str] = {}
    for line in lines:
        if not line.strip():
            continue
        key, sep, value = line.partition("=")
        if not sep:
            raise InputError(f"{p}: header line {line!r} is not 'Key = Value'")
        fields[key.strip()] = value.strip()
    if "ElementDataFile" not in fields or "DimSize" not in fields:
        raise InputError(f"{p}: not a MetaImage header (no DimSize / ElementDataFile)")
    if fields.get("ObjectType", "Image").lower() != "image":
        raise InputError(f"{p}: ObjectType: expected Image, got {fields['ObjectType']!r}")
    dim = int(_numbers(p, "NDims", fields.get("NDims", "3"), 1)[0])
    sizes = _numbers(p, "DimSize", fields["DimSize"], dim).astype(np.int64)
    channels = int(_numbers(p, "ElementNumberOfChannels",
                            fields.get("ElementNumberOfChannels", "1"), 1)[0])  # fmt: skip
    if dim not in (2, 3) or channels != 1 or (sizes < 1).any():
        raise InputError(
            f"{p}: expected a 2-D or 3-D single-channel volume, got NDims {dim}, DimSize "
            f"{fields['DimSize']!r}, {channels} channel(s)"
        )
    _check_voxels(p, sizes)
    code = _MET_TYPES.get(fields.get("ElementType", ""))
    if code is None:
        raise InputError(f"{p}: ElementType: {fields.get('ElementType')!r} is not supported")
    msb = fields.get("BinaryDataByteOrderMSB", fields.get("ElementByteOrderMSB", "False"))
    dtype = np.dtype((">" if msb.lower() == "true" else "<") + code)
    name = fields["ElementDataFile"]
    if name.upper() == "LIST" or "%" in name:
        raise InputError(f"{p}: ElementDataFile: {name!r}: only one data file is supported")
    local = name.upper() == "LOCAL"
    blob = _data_bytes(p, "ElementDataFile", None if local else name, data_at)
    count = int(np.prod(sizes))
    if fields.get("CompressedData", "False").lower() == "true":
        blob = _inflate(p, blob, count * dtype.itemsize, wbits=15)
    values = _decode(p, blob, "raw", dtype, count, {"byte skip": fields.get("HeaderSize", "0")})
    values = values.reshape(tuple(sizes), order="F")
    spacing = _numbers(p, "ElementSpacing", fields.get("ElementSpacing", " ".join(["1"] * dim)),
                       dim)  # fmt: skip
    offset_key = next((k for k in ("Offset", "Position", "Origin") if k in fields), None)
    offset = _numbers(p, offset_key, fields[offset_key], dim) if offset_key else np.zeros(dim)
    rot_key = next((k for k in ("TransformMatrix", "Rotation", "Orientation") if k in fields), None)
    rows = (
        _numbers(p, rot_key, fields[rot_key], dim * dim).reshape(dim, dim)
        if rot_key
        else np.eye(dim)
    )
    affine = np.eye(4)
    # ITK writes row d of TransformMatrix as the direction of axis d: the columns of the map
    directions = np.eye(3)
    directions[:dim, :dim] = rows.T
    if dim == 2:
        directions[:, 2] = np.cross(directions[:, 0], directions[:, 1])
    scales = np.ones(3)
    scales[:dim] = spacing
    affine[:3, :3] = directions * scales
    affine[:dim, 3] = offset
    return values, affine, "MetaImage"


# ------------------------------------------------------------------ NIfTI


def _read_nifti(p: Path) -> tuple[np.ndarray, np.ndarray, str]:
    try:
        import nibabel
        from nibabel.filebasedimages import ImageFileError
    except ImportError:  # pragma: no cover - a dependency of the package
        raise InputError(f"{p}: reading NIfTI needs nibabel (pip install nibabel)") from None
    try:
        img = nibabel.load(str(p))
        shape = tuple(int(v) for v in img.shape)
        if len(shape) == 4 and shape[3] == 1:
            shape = shape[:3]
        if len(shape) not in (2, 3):
            raise InputError(
                f"{p}: expected a 2-D or 3-D single-channel volume, got shape {img.shape}"
            )
        _check_voxels(p, shape)
        values = np.asarray(img.dataobj, dtype=np.float32).reshape(shape, order="F")
        affine = np.asarray(img.affine, dtype=np.float64)
    except InputError:
        raise
    except (ImageFileError, OSError, EOFError, ValueError, zlib.error) as exc:
        raise InputError(f"{p}: not a readable NIfTI file ({exc})") from None
    lps = np.eye(4)
    lps[:3, :] = _FLIP @ affine[:3, :]  # NIfTI's world is RAS+ (its affine is 3-D, 2-D too)
    return values, lps, "NIfTI"
