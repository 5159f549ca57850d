"""Surface and volume mesh files -> PyVista datasets, with errors that name the file.

Nothing reaches VTK unchecked (see :mod:`sciviz_gbuf.readers._mesh_check`): a file's header
and size are checked before its reader allocates anything, readers that cannot be checked
beforehand parse in a child process, and every dataset's connectivity and points are checked
before any VTK filter runs on it (:func:`check_mesh`, also used by the capture for in-memory
datasets).
"""

from __future__ import annotations

import os
from contextlib import AbstractContextManager
from pathlib import Path

import numpy as np
import pyvista as pv

from ..errors import InputError
from ._mesh_check import (
    CHECKED_SUFFIXES,
    VTKMessages,
    check_dataset,
    check_file,
    fold,
    read_isolated,
    vtk_messages,
)
from .formats import kind_of

__all__ = ["IMAGE_SUFFIXES", "SOURCE_ARRAY", "check_mesh", "quiet_vtk", "read_mesh", "source_name"]

#: Field-data array in which :func:`read_mesh` records the path it read (as the user gave it),
#: so that later errors (in the capture, say) name the file rather than "dataset 0".
SOURCE_ARRAY = "__sciviz_gbuf_source"
#: Picture formats VTK reads as a flat image grid: never a mesh to draw.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".gif", ".webp", ".pnm", ".ppm", ".pgm")


def quiet_vtk() -> AbstractContextManager[VTKMessages]:
    """A block in which VTK's output window, logger and PyVista's warnings print nothing;
    the yielded object's ``first_error()`` is what they reported (one line), or None."""
    return vtk_messages()


def check_mesh(data: object, name: str) -> None:
    """Refuse a dataset VTK's filters would crash on (connectivity out of range, negative or
    inconsistent offsets, cells of an unknown type or the wrong size) or NaN/inf points.

    Parameters
    ----------
    data : pyvista or VTK dataset (or MultiBlock)
    name : str
        What the message names: the file, or ``dataset i (Type)``.

    Raises
    ------
    InputError
    """
    check_dataset(data, name)


def source_name(data: object) -> str | None:
    """The path :func:`read_mesh` read ``data`` from, or None."""
    fd = getattr(pv.wrap(data), "field_data", None) if data is not None else None
    if fd is None or SOURCE_ARRAY not in fd:
        return None
    values = np.asarray(fd[SOURCE_ARRAY])
    return str(values.ravel()[0]) if values.size else None


def read_mesh(path: str | os.PathLike) -> pv.DataSet:
    """Read any mesh format PyVista/VTK reads (STL, PLY, OBJ, VTK, VTP, VTU, ...).

    Parameters
    ----------
    path : str or path-like
        The file. It is only read, never modified.

    Returns
    -------
    pyvista.DataSet
        The mesh (a MultiBlock is combined into one dataset), with the path in its field
        data (:data:`SOURCE_ARRAY`) for later messages.

    Raises
    ------
    InputError
        If the file is missing, of an unknown type, empty, truncated, declares more than it
        holds, has connectivity outside its points, NaN/inf points, or holds no cells; VTK's
        own report is folded into the one-line message.
    """
    shown = os.fsdecode(path)
    p = Path(path)
    if p.is_dir():
        raise InputError(
            f"{shown}: is a folder, not a mesh file (give the file inside it; "
            f"`sciviz-gbuf ct {shown}` reads a DICOM series)"
        )
    if not p.is_file():
        raise InputError(f"{shown}: no such mesh file")
    if p.suffix.lower() in IMAGE_SUFFIXES:
        # VTK reads a picture as a flat grid: a capture would draw one grey quad
        raise InputError(
            f"{shown}: is a {p.suffix.lower()[1:].upper()} image, not a mesh (expected STL, "
            "PLY, OBJ, OFF, VTK/VTP/VTU, glTF, ...)"
        )
    if kind_of(p) == "dem":
        raise InputError(
            f"{shown}: is a DEM grid ({p.suffix.lower()}), not a mesh: `sciviz-gbuf topo` "
            f"and `birdseye` draw it (in Python: read_dem and DEM.to_pyvista)"
        )
    if kind_of(p) == "volume":
        # VTK would read it as an image whose outer box is all a capture draws
        raise InputError(
            f"{shown}: is a volume image, not a mesh: `sciviz-gbuf ct {shown}` draws its "
            "isosurface (in Python: read_volume and core.isosurface)"
        )
    check_file(p, shown)
    if p.suffix.lower() in CHECKED_SUFFIXES:
        with vtk_messages() as msgs:
            try:
                data = pv.read(p)
            except Exception as exc:  # pyvista raises ValueError/OSError/RuntimeError by format
                reason = msgs.first_error() or fold(exc)
                raise InputError(f"{shown}: cannot read as a mesh ({reason})") from exc
        reason = msgs.first_error()
        if reason is not None:
            # A reader that reports an error returns what it parsed so far: never use it.
            raise InputError(f"{shown}: cannot read as a mesh ({reason})")
    else:
        data = read_isolated(p, shown)
    if data is None:
        raise InputError(f"{shown}: the file holds no cells (expected a surface or volume mesh)")
    check_dataset(data, shown)
    if isinstance(data, pv.MultiBlock):
        with vtk_messages():
            data = data.combine(merge_points=False)
    if data is None or data.n_cells == 0:
        raise InputError(f"{shown}: the file holds no cells (expected a surface or volume mesh)")
    data.field_data[SOURCE_ARRAY] = np.array([shown])
    return data
