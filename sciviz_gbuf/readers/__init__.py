"""Readers: mesh files -> PyVista datasets; DEM grids -> DEM (later DICOM, Bezier patches)."""

from .dem import DEM, read_dem
from .mesh import read_mesh

__all__ = ["DEM", "read_dem", "read_mesh"]
