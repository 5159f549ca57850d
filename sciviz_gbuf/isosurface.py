"""Old import path of :func:`sciviz_gbuf.core.isosurface.isosurface` (shown in the README)."""

from .core.isosurface import isosurface

__all__ = ["isosurface"]
