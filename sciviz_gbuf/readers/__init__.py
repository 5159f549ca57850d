"""Readers: mesh files -> PyVista datasets; DEM grids -> DEM; DICOM and volume files (NRRD,
MetaImage, NIfTI) -> patient-space volumes; Bezier patch sets.

:data:`~sciviz_gbuf.readers.formats.FORMATS` is the one suffix table; :func:`read_scene` reads
any path by it.
"""

from typing import TYPE_CHECKING

from .._atomic import lazy_exports

#: Public name -> module (relative to this package) that defines it: imported on first
#: use (``_atomic.lazy_exports``), so importing one module of the package does
#: not import them all.
_EXPORTS = {
    "metres_per_degree": "_dem_model",
    "DEM": "dem",
    "read_dem": "dem",
    "dicom_report": "dicom",
    "read_dicom_series": "dicom",
    "FORMATS": "formats",
    "KINDS": "formats",
    "UP_AXES": "formats",
    "Format": "formats",
    "kind_of": "formats",
    "suffix_of": "formats",
    "suffixes": "formats",
    "up_axis": "formats",
    "read_mesh": "mesh",
    "PatchSet": "patches",
    "read_patches": "patches",
    "read_scene": "read",
    "VOLUME_SUFFIXES": "volume",
    "read_volume": "volume",
}

__all__ = [
    "DEM",
    "FORMATS",
    "KINDS",
    "UP_AXES",
    "VOLUME_SUFFIXES",
    "Format",
    "PatchSet",
    "dicom_report",
    "kind_of",
    "metres_per_degree",
    "read_dem",
    "read_dicom_series",
    "read_mesh",
    "read_patches",
    "read_scene",
    "read_volume",
    "suffix_of",
    "suffixes",
    "up_axis",
]

lazy_exports(__name__, _EXPORTS)

if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from ._dem_model import metres_per_degree
    from .dem import DEM, read_dem
    from .dicom import dicom_report, read_dicom_series
    from .formats import FORMATS, KINDS, UP_AXES, Format, kind_of, suffix_of, suffixes, up_axis
    from .mesh import read_mesh
    from .patches import PatchSet, read_patches
    from .read import read_scene
    from .volume import VOLUME_SUFFIXES, read_volume
