"""Readers: mesh files -> PyVista datasets; DEM grids -> DEM (later DICOM, Bezier patches)."""

from .dem import DEM, read_dem
from .dicom import dicom_report, read_dicom_series
from .mesh import read_mesh

__all__ = ["DEM", "dicom_report", "read_dem", "read_dicom_series", "read_mesh"]
