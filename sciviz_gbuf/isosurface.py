"""Old import path of :func:`sciviz_gbuf.core.isosurface.isosurface` (shown in docs/medical.md)."""

from .core.isosurface import isosurface

__all__ = ["isosurface"]
