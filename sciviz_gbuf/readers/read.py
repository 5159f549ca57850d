"""One entry for any path: what it holds (by :mod:`~sciviz_gbuf.readers.formats`), read."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..errors import InputError
from .dem import read_dem
from .dicom import read_dicom_series
from .formats import kind_of
from .mesh import read_mesh
from .patches import read_patches
from .volume import read_volume

__all__ = ["read_scene"]

# kind -> reader of a path of that kind (the kinds of formats.KINDS).
_READ = {
    "dem": read_dem,
    "mesh": read_mesh,
    "patches": read_patches,
    "dicom": read_dicom_series,
    "volume": read_volume,
}


def read_scene(path: str | os.PathLike) -> tuple[Any, str]:
    """Read a file or folder as what its name says it holds.

    Parameters
    ----------
    path : str or path-like
        A DEM file (``.tif``, ``.asc``, ``.hgt``, ...), a Bezier patch file (``.bpt``), a
        folder of DICOM slices, a volume file (``.nrrd``, ``.nhdr``, ``.mha``, ``.mhd``,
        ``.nii``, ``.nii.gz``), or any mesh file PyVista/VTK reads. Only read, never
        modified.

    Returns
    -------
    (data, kind)
        ``kind`` is ``"dem"`` (data: :class:`~sciviz_gbuf.readers.DEM`), ``"mesh"``
        (a PyVista dataset), ``"patches"`` (:class:`~sciviz_gbuf.readers.PatchSet`) or
        ``"dicom"`` (the CT volume of :func:`~sciviz_gbuf.readers.read_dicom_series`) or
        ``"volume"`` (a NRRD / MetaImage / NIfTI volume of
        :func:`~sciviz_gbuf.readers.read_volume`, in the same patient frame).

    Raises
    ------
    InputError
        If ``path`` does not exist, or from the reader of its kind.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such file or folder")
    kind = kind_of(p)
    return _READ[kind](p), kind
