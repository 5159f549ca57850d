"""Readers: mesh files -> PyVista datasets; DEM grids -> DEM; DICOM; Bezier patch sets."""

from .dem import DEM, read_dem
from .dicom import dicom_report, read_dicom_series
from .mesh import read_mesh
from .patches import PatchSet, read_patches

__all__ = [
    "DEM",
    "PatchSet",
    "dicom_report",
    "read_dem",
    "read_dicom_series",
    "read_mesh",
    "read_patches",
]
