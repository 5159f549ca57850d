"""Argument checks shared by every layer, with one message style: ``"name: expected ..., got ..."``.

Each check returns the value in the form the caller computes with (float, float32 array, ...)
and raises :class:`~sciviz_gbuf.errors.InputError` otherwise, so a bad argument is refused with
one line naming it before any work or allocation starts.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .errors import InputError

__all__ = [
    "LIMITS",
    "at_most",
    "boolean",
    "colormap",
    "finite",
    "image",
    "levels",
    "mask",
    "number_in",
    "positive",
    "rgb",
    "unit_interval",
]


#: Upper bounds of the size-like parameters, one table for the Python API, the command line and
#: the explorer (documented in the README's "Limits"). Each is refused with an InputError
#: before any allocation.
LIMITS: dict[str, float] = {
    "line_width": 64.0,  # px: edge, contour, hatch and profile line widths
    "levels": 100_000,  # contour / band / isophote levels in one call
    "bands": 4096,  # colour band count
    "directions": 360,  # sky-view horizon directions
    "image_side": 16384,  # px: one side of a capture or an output image
    "supersample": 8,  # capture supersampling factor
    "image_pixels": 2**28,  # width x height x supersample^2 of one capture
}


def at_most(value: float, name: str, limit: str) -> float:
    """``value`` itself if it is at most ``LIMITS[limit]``, else an InputError naming it."""
    bound = LIMITS[limit]
    if not value <= bound:
        raise InputError(f"{name}: expected at most {bound:g}, got {value!r}")
    return value


def finite(value: object, name: str) -> float:
    """A finite float."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a finite number, got {value!r}") from None
    if not np.isfinite(v):
        raise InputError(f"{name}: expected a finite number, got {value!r}")
    return v


def positive(value: object, name: str) -> float:
    """A finite float > 0."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a finite number > 0, got {value!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{name}: expected a finite number > 0, got {value!r}")
    return v


def number_in(value: object, name: str, low: float, high: float = np.inf) -> float:
    """A float in the closed interval ``[low, high]`` (booleans are refused)."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        v = np.nan
    if isinstance(value, (bool, np.bool_)) or not (low <= v <= high):
        raise InputError(f"{name}: expected a number in [{low}, {high}], got {value!r}")
    return v


def unit_interval(value: object, name: str) -> float:
    """A float in [0, 1]."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        v = float("nan")
    if isinstance(value, (bool, np.bool_)) or not 0.0 <= v <= 1.0:
        raise InputError(f"{name}: expected a number in [0, 1], got {value!r}")
    return v


def boolean(value: object, name: str) -> bool:
    """True or False (numpy booleans too; not 0/1 or strings)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name}: expected True or False, got {value!r}")
    return bool(value)


def rgb(value: object, name: str) -> np.ndarray:
    """An RGB colour: three finite floats in [0, 1], as float32 ``(3,)``."""
    try:
        c = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        c = np.zeros(0)
    if c.size != 3 or not np.all(np.isfinite(c)) or c.min() < 0 or c.max() > 1:
        raise InputError(f"{name}: expected an RGB triple of floats in [0, 1], got {value!r}")
    return c.astype(np.float32)


def image(value: object, name: str = "image") -> np.ndarray:
    """A non-empty real 2-D image as C-contiguous float32."""
    a = np.asarray(value)
    if a.ndim != 2:
        raise InputError(f"{name}: expected a 2-D (H, W) image, got shape {a.shape}")
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise InputError(f"{name}: expected a real-valued image, got dtype {a.dtype}")
    if a.size == 0:
        raise InputError(f"{name}: the image is empty (shape {a.shape})")
    return np.ascontiguousarray(a, dtype=np.float32)


def mask(value: object, shape: Sequence[int]) -> np.ndarray | None:
    """None, or a coverage mask of ``shape`` as C-contiguous bool (integers: non-zero)."""
    if value is None:
        return None
    m = np.asarray(value)
    if m.shape != tuple(shape):
        raise InputError(f"mask: expected a bool array of shape {tuple(shape)}, got {m.shape}")
    if m.dtype != np.bool_:
        if not np.issubdtype(m.dtype, np.integer):
            raise InputError(f"mask: expected a bool array, got dtype {m.dtype}")
        m = m != 0
    return np.ascontiguousarray(m)


def levels(value: object, name: str = "levels") -> np.ndarray:
    """Sorted, distinct, finite level values as float64 (at least one)."""
    lv = np.asarray(value, dtype=np.float64).ravel()
    if lv.size == 0:
        raise InputError(f"{name}: expected at least one level value")
    if not np.all(np.isfinite(lv)):
        raise InputError(f"{name}: expected finite values, got {lv.tolist()}")
    return np.unique(lv)


def colormap(cmap: object, name: str = "cmap"):
    """A matplotlib colour map from its registered name, or the Colormap itself."""
    import matplotlib

    try:
        cm = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    except KeyError:
        raise InputError(f"{name}: unknown colour map {cmap!r}") from None
    if not callable(cm):
        raise InputError(f"{name}: expected a colour map name or Colormap, got {cmap!r}")
    return cm
