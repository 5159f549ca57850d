"""Readers: mesh files (later DEM grids, DICOM series, Bezier patches) -> PyVista datasets."""

from .mesh import read_mesh

__all__ = ["read_mesh"]
