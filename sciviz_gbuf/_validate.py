"""Argument checks shared by every layer, with one message style: ``"name: expected ..., got ..."``.

Each check returns the value in the form the caller computes with (float, float32 array, ...)
and raises :class:`~sciviz_gbuf.errors.InputError` otherwise, so a bad argument is refused with
one line naming it before any work or allocation starts.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from .errors import InputError

try:  # POSIX only: the ulimit -v check is skipped elsewhere
    import resource
except ImportError:  # pragma: no cover - Windows
    resource = None  # type: ignore[assignment]

__all__ = [
    "LIMITS",
    "at_most",
    "available_memory",
    "boolean",
    "brief",
    "check_memory",
    "choice",
    "colormap",
    "count",
    "finite",
    "image",
    "levels",
    "mask",
    "number_in",
    "out_array",
    "positive",
    "rgb",
    "size",
    "unit_interval",
]


#: Upper bounds of the size-like parameters, one table for the Python API, the command line and
#: the explorer (documented in docs/limits.md). Each is refused with an InputError
#: before any allocation.
LIMITS: dict[str, float] = {
    "line_width": 64.0,  # px: edge, contour, hatch, stroke and profile line widths
    "spacing": 1024.0,  # px: hatch and stroke spacing, contour dense spacing
    "levels": 100_000,  # contour / band / isophote levels and reflection stripes in one call
    "segments": 10_000_000,  # contour polyline segments (cell crossings) of one call
    "bands": 4096,  # colour band count
    "directions": 360,  # sky-view horizon directions
    "reach": 4096,  # cells: sky-view search radius (radius / min(dx, dy))
    "families": 16,  # hatch stroke families (angles)
    "shade_levels": 256,  # texels of the toon shade texture
    "copies": 100,  # photocopy generations
    "blur": 64.0,  # px: photocopy toner spread (Gaussian sigma; its kernel grows with it)
    "resolution": 4096,  # tessellation intervals per patch side (patches, parametric surfaces)
    "mesh_points": 2**24,  # points of one tessellation (all patches together)
    "image_side": 16384,  # px: one side of a capture or an output image
    "dpi": 9600,  # dots per inch of a map scale or a PNG's pHYs (high-end scanners, printers)
    "supersample": 8,  # capture supersampling factor
    "image_pixels": 2**28,  # width x height x supersample^2 of one capture
    "layers": 8,  # surfaces kept per pixel by capture(layers=k)
    "font_size": 512.0,  # px: contour label and map furniture text
    "label_spacing": 16384.0,  # px: distance between contour labels along a line
    "tiles": 1_000_000,  # web-map tiles of one pyramid (all zoom levels)
}


def at_most(value: float, name: str, limit: str) -> float:
    """``value`` itself if it is at most ``LIMITS[limit]``, else an InputError naming it."""
    bound = LIMITS[limit]
    if not value <= bound:
        raise InputError(f"{name}: expected at most {bound:g}, got {brief(value)}")
    return value


def brief(value: object, limit: int = 60) -> str:
    """``repr(value)`` on one short line (an array's repr spans lines and may be huge)."""
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _real(value: object) -> float:
    """``value`` as a float if it is one real number (not a bool, string or array), else NaN."""
    if isinstance(value, (bool, np.bool_, str, bytes)) or np.ndim(value) != 0:
        return float("nan")
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        return float("nan")


def size(
    value: object,
    name: str,
    limit: str,
    *,
    low: float = 0.0,
    closed: bool = False,
    buffer: bool = False,
) -> float:
    """A size-like float in ``(low, LIMITS[limit]]`` (``[low, ...]`` if ``closed``).

    ``buffer``: the size is in pixels of the image the function gets, which may be a
    supersampled G-buffer channel (callers scale output pixels by ``gb.supersample``), so the
    bound is ``LIMITS[limit] * LIMITS["supersample"]``. Booleans, strings, arrays, NaN and
    infinities are refused, so a size can never slip past its bound by comparing oddly.
    """
    v = _real(value)
    bound = LIMITS[limit] * (LIMITS["supersample"] if buffer else 1)
    if not ((low <= v if closed else low < v) and v <= bound):
        interval = f"{'[' if closed else '('}{low:g}, {bound:g}]"
        source = f"LIMITS[{limit!r}]" + (" x LIMITS['supersample']" if buffer else "")
        raise InputError(f"{name}: expected a number in {interval} ({source}), got {brief(value)}")
    return v


def count(value: object, name: str, limit: str, *, low: int = 1) -> int:
    """An integer (Python or numpy, not a bool) in ``[low, LIMITS[limit]]``."""
    bound = int(LIMITS[limit])
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if not (ok and low <= int(value) <= bound):  # type: ignore[arg-type]
        raise InputError(
            f"{name}: expected an integer in [{low}, {bound}] (LIMITS[{limit!r}]), "
            f"got {brief(value)}"
        )
    return int(value)  # type: ignore[arg-type]


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (OSError, ValueError, AttributeError):
        return None


def _cgroup_available() -> int | None:
    """Room left under a cgroup v2 memory limit (containers, systemd-run -p MemoryMax)."""
    try:
        with open("/proc/self/cgroup", encoding="utf-8") as f:
            rel = next(line.split(":", 2)[2].strip() for line in f if line.startswith("0::"))
        base = os.path.join("/sys/fs/cgroup", rel.lstrip("/"))
        with open(os.path.join(base, "memory.max"), encoding="ascii") as f:
            cap = f.read().strip()
        if cap == "max":
            return None
        with open(os.path.join(base, "memory.current"), encoding="ascii") as f:
            used = int(f.read().strip())
        return max(int(cap) - used, 0)
    except (OSError, ValueError, StopIteration, IndexError):
        return None


def _address_space_available() -> int | None:
    """Room left under ``ulimit -v`` (RLIMIT_AS), where bad_alloc comes from first."""
    if resource is None:
        return None
    try:
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft == resource.RLIM_INFINITY:
            return None
        with open("/proc/self/statm", encoding="ascii") as f:
            used = int(f.read().split()[0]) * int(os.sysconf("SC_PAGE_SIZE"))
        return max(int(soft) - used, 0)
    except (OSError, ValueError, IndexError):
        return None


def available_memory() -> int | None:
    """Bytes a new allocation can still get: the least of the system's ``MemAvailable``
    (``os.sysconf("SC_AVPHYS_PAGES")`` where there is no ``/proc/meminfo``), the room under a
    cgroup v2 memory limit and under ``ulimit -v``; None if none of them is known."""
    known = [
        v
        for v in (_meminfo_available(), _cgroup_available(), _address_space_available())
        if v is not None
    ]
    return min(known) if known else None


def check_memory(nbytes: float, name: str, what: str) -> None:
    """Refuse an allocation of ``nbytes`` that the memory available now cannot hold.

    Called before the largest buffers are made, so an oversized request fails with one line
    naming the parameter (``name``) instead of ``MemoryError`` or ``std::bad_alloc``.
    """
    avail = available_memory()
    if avail is not None and nbytes > avail:
        raise InputError(
            f"{name}: {what} needs {nbytes / 2**30:.2f} GiB of memory, but only "
            f"{avail / 2**30:.2f} GiB is available"
        )


def finite(value: object, name: str) -> float:
    """A finite float."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: expected a finite number, got {brief(value)}") from None
    if not np.isfinite(v):
        raise InputError(f"{name}: expected a finite number, got {brief(value)}")
    return v


def positive(value: object, name: str) -> float:
    """A finite float > 0."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: expected a finite number > 0, got {brief(value)}") from None
    if not (np.isfinite(v) and v > 0):
        raise InputError(f"{name}: expected a finite number > 0, got {brief(value)}")
    return v


def number_in(value: object, name: str, low: float, high: float = np.inf) -> float:
    """A float in the closed interval ``[low, high]`` (booleans are refused)."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        v = np.nan
    if isinstance(value, (bool, np.bool_)) or not (low <= v <= high):
        raise InputError(f"{name}: expected a number in [{low}, {high}], got {brief(value)}")
    return v


def unit_interval(value: object, name: str) -> float:
    """A float in [0, 1]."""
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        v = float("nan")
    if isinstance(value, (bool, np.bool_)) or not 0.0 <= v <= 1.0:
        raise InputError(f"{name}: expected a number in [0, 1], got {brief(value)}")
    return v


def choice(value: object, name: str, options: Sequence[str]) -> str:
    """One of the strings ``options`` (anything else, an array too, is refused by name)."""
    if not (isinstance(value, str) and value in options):
        raise InputError(f"{name}: expected one of {tuple(options)}, got {brief(value)}")
    return value


def boolean(value: object, name: str) -> bool:
    """True or False (numpy booleans too; not 0/1 or strings)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name}: expected True or False, got {brief(value)}")
    return bool(value)


def rgb(value: object, name: str) -> np.ndarray:
    """An RGB colour: three finite floats in [0, 1], as float32 ``(3,)``."""
    try:
        c = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        c = np.zeros(0)
    if c.size != 3 or not np.all(np.isfinite(c)) or c.min() < 0 or c.max() > 1:
        raise InputError(f"{name}: expected an RGB triple of floats in [0, 1], got {brief(value)}")
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


def levels(value: object, name: str = "levels", limit: str = "levels") -> np.ndarray:
    """Sorted, distinct, finite level values as float64 (at least one, at most
    ``LIMITS[limit]``)."""
    try:
        lv = np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: expected a sequence of numbers, got {brief(value)}") from None
    if lv.size == 0:
        raise InputError(f"{name}: expected at least one level value")
    bound = int(LIMITS[limit])
    if lv.size > bound:
        raise InputError(
            f"{name}: expected at most {bound} values (LIMITS[{limit!r}]), got {lv.size}"
        )
    if not np.all(np.isfinite(lv)):
        raise InputError(f"{name}: expected finite values, got {brief(lv.tolist())}")
    return np.unique(lv)


def colormap(cmap: object, name: str = "cmap"):
    """A matplotlib colour map from its registered name, or the Colormap itself."""
    import matplotlib

    try:
        cm = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    except KeyError:
        raise InputError(f"{name}: unknown colour map {brief(cmap)}") from None
    if not callable(cm):
        raise InputError(f"{name}: expected a colour map name or Colormap, got {brief(cmap)}")
    return cm


def out_array(out: object, shape: tuple[int, ...], source: object) -> np.ndarray:
    """``out`` as an operator's preallocated result: a C-contiguous, writeable float32
    array of ``shape`` that shares no memory with ``source`` (the kernel reads the source
    while it writes the result)."""
    if not isinstance(out, np.ndarray):
        raise InputError(f"out: expected a numpy array, got {type(out).__name__}")
    if out.dtype != np.float32 or out.shape != tuple(shape):
        raise InputError(
            f"out: expected a float32 array of shape {tuple(shape)}, got {out.dtype} {out.shape}"
        )
    if not out.flags.c_contiguous or not out.flags.writeable:
        raise InputError("out: expected a C-contiguous, writeable array")
    if isinstance(source, np.ndarray) and np.shares_memory(out, source):
        raise InputError("out: shares memory with the heights; pass a separate array")
    return out
