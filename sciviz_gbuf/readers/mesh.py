"""Surface and volume mesh files -> PyVista datasets, with errors that name the file."""

from __future__ import annotations

import os
from pathlib import Path

import pyvista as pv

from ..errors import InputError

__all__ = ["read_mesh"]


def read_mesh(path: str | os.PathLike) -> pv.DataSet:
    """Read any mesh format PyVista/VTK reads (STL, PLY, OBJ, VTK, VTP, VTU, ...).

    Parameters
    ----------
    path : str or path-like
        The file. It is only read, never modified.

    Returns
    -------
    pyvista.DataSet
        The mesh (a MultiBlock is combined into one dataset).

    Raises
    ------
    InputError
        If the file is missing, of an unknown type, unreadable or holds no cells.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such mesh file")
    try:
        data = pv.read(p)
    except Exception as exc:  # pyvista raises ValueError/OSError/IOError by format
        raise InputError(f"{p}: cannot read as a mesh ({exc})") from exc
    if isinstance(data, pv.MultiBlock):
        data = data.combine(merge_points=False)
    if data is None or data.n_cells == 0:
        raise InputError(f"{p}: the file holds no cells (expected a surface or volume mesh)")
    return data
