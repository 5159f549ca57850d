"""The one table of file formats the readers know: suffix -> kind of data and how it is read.

Every place that decides what a file is asks this table (:func:`kind_of`, :func:`suffixes`):
``read_dem`` for its in-memory parsers and for which files GDAL reads in windows,
``read_scene`` and the explorer for what a path holds, the cameras for which world axis is up
(:func:`up_axis`). Adding a format is one line here (plus its parser). A suffix that is not
listed is a mesh for PyVista/VTK's own readers, and a folder is a DICOM series.

The up axis follows each format's convention: the graphics world's interchange formats
(OFF, OBJ, PLY, glTF) are y-up, as are most scanned meshes in them; CAD and science formats
(STL, VTK's own, DEMs) and DICOM (patient LPS, head at +z) are z-up, and so are Newell's
Bezier patch files (the teapot's axis is z).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ._dem_files import (
    RawDEM,
    read_asc,
    read_geotiff,
    read_hgt,
    read_npy,
    read_npz,
    read_usgs_dem,
)

__all__ = [
    "FORMATS",
    "KINDS",
    "UP_AXES",
    "Format",
    "kind_of",
    "suffix_of",
    "suffixes",
    "up_axis",
]

#: What a path can hold: a DEM grid, a surface/volume mesh, Bezier patches, a DICOM series, a
#: volume image file (NRRD, MetaImage, NIfTI).
KINDS = ("dem", "mesh", "patches", "dicom", "volume")
#: The world axes a file's convention can make upright.
UP_AXES = ("x", "y", "z")


@dataclass(frozen=True)
class Format:
    """One file format.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    description : str
        What the format is, for messages and ``--help``.
    read_raw : callable or None
        For DEM formats: ``Path -> RawDEM`` (heights and georeference as the file gives them).
    windowed : bool
        True if GDAL (rasterio) reads it in windows, so ``read_dem(chunks=)`` is lazy and it
        can be a tile of a mosaic; False if it is parsed whole in memory.
    up : {"x", "y", "z"}
        The world axis the format's convention makes upright: the default view-up of the
        cameras built from such a file (``up=`` / ``--up`` override it).
    """

    kind: str
    description: str
    read_raw: Callable[[Path], RawDEM] | None = None
    windowed: bool = False
    up: str = "z"


#: suffix (lower case, with the dot) -> :class:`Format`.
FORMATS: dict[str, Format] = {
    ".asc": Format("dem", "ESRI ASCII grid", read_asc, windowed=True),
    ".dem": Format("dem", "USGS DEM", read_usgs_dem),
    ".hgt": Format("dem", "SRTM HGT tile", read_hgt, windowed=True),
    ".npy": Format("dem", "NumPy array of heights", read_npy),
    ".npz": Format("dem", "NumPy archive with heights (and transform/crs)", read_npz),
    ".tif": Format("dem", "GeoTIFF", read_geotiff, windowed=True),
    ".tiff": Format("dem", "GeoTIFF", read_geotiff, windowed=True),
    ".bpt": Format("patches", "Bezier patch set"),
    # Meshes: read by PyVista/VTK (any other suffix is tried as a mesh too, z-up).
    ".stl": Format("mesh", "STL triangles"),
    ".vtk": Format("mesh", "legacy VTK dataset"),
    ".vtp": Format("mesh", "VTK XML polygonal data"),
    ".vtu": Format("mesh", "VTK XML unstructured grid"),
    ".ply": Format("mesh", "PLY polygons", up="y"),
    ".obj": Format("mesh", "Wavefront OBJ", up="y"),
    ".off": Format("mesh", "Object File Format", up="y"),
    ".gltf": Format("mesh", "glTF scene", up="y"),
    ".glb": Format("mesh", "binary glTF scene", up="y"),
    # Volume images (readers/volume.py), in patient coordinates like DICOM: z-up.
    ".nrrd": Format("volume", "NRRD volume"),
    ".nhdr": Format("volume", "NRRD header (detached data)"),
    ".mha": Format("volume", "MetaImage volume"),
    ".mhd": Format("volume", "MetaImage header (detached data)"),
    ".nii": Format("volume", "NIfTI volume"),
    ".nii.gz": Format("volume", "gzipped NIfTI volume"),
}


def suffixes(kind: str) -> tuple[str, ...]:
    """The listed suffixes of one kind, sorted (e.g. every DEM suffix)."""
    return tuple(sorted(s for s, f in FORMATS.items() if f.kind == kind))


def kind_of(path: str | os.PathLike) -> str:
    """What ``path`` holds by its name: a folder is ``"dicom"``, a listed suffix its kind,
    anything else ``"mesh"`` (for PyVista/VTK's readers, which know many formats)."""
    p = Path(path)
    if p.is_dir():
        return "dicom"
    fmt = FORMATS.get(suffix_of(p))
    return fmt.kind if fmt is not None else "mesh"


def suffix_of(path: str | os.PathLike) -> str:
    """The suffix :data:`FORMATS` knows ``path`` by: the last one, lower case, or a listed
    double suffix (``.nii.gz``) whole."""
    name = Path(path).name.lower()
    for double in (s for s in FORMATS if s.count(".") > 1):
        if name.endswith(double):
            return double
    return Path(name).suffix


def up_axis(path: str | os.PathLike | None) -> str:
    """The world axis that is upright by the convention of ``path``'s format (``"x"``, ``"y"``
    or ``"z"``): ``"y"`` for OFF/OBJ/PLY/glTF, ``"z"`` for everything else (STL, VTK, DEMs,
    Bezier patches, a DICOM folder, unlisted suffixes, and no path at all)."""
    if path is None:
        return "z"
    fmt = FORMATS.get(suffix_of(path))
    return fmt.up if fmt is not None else "z"
