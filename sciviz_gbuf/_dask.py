"""Out-of-core evaluation of the plan-view terrain operators on dask arrays.

An image operator of this package reads, for each output cell, only the cells within a fixed
*stencil radius* (Chebyshev distance) of it: 1 for the 3x3 operators of 1990 Eq. 1-4, 9 and the
contour operator, 1 for the GDAL hillshade window, 3 for the relief of a map with nodata (the
nodata ring fill reaches 2 cells further), ``floor(radius / cell)`` for the sky view.
:func:`map_stencil` runs the in-memory operator on every chunk extended by that many cells of
its neighbours (``dask.array.map_overlap``, no padding at the grid's own edges) and keeps the
chunk's own cells: each output cell then sees exactly the neighbourhood it sees in memory, so
the result is bit-identical to the in-memory path whatever the chunking, chunk borders
included. Operators whose reach is the whole grid (cast shadows: a ray may cross the map) have
no such radius and are refused.

Parameters that need the whole grid (a default colour range, a default contour interval from
the data's range and slope) are computed first in a cheap reduction pass (:func:`reduce`);
each function that does this says so.

Memory that does not grow with the raster. ``map_overlap`` builds each output chunk from its
own input chunk and slices of its eight neighbours, so an input chunk stays in memory until
the last of its neighbours is done: in a row-major traversal, about two rows of input chunks,
a number that grows with the raster's width. Sources that can read any window themselves (a
GDAL raster read lazily, :func:`~sciviz_gbuf.datasets.synthetic_dem`) are registered here
(:func:`register_windows`); :func:`map_windows` then makes one task per output chunk that reads
its chunk *with* the halo and computes everything from it: no task depends on another, and a
worker holds only the chunks it is computing, whatever the raster's size.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .errors import InputError

__all__ = [
    "any_dask",
    "as_dask",
    "is_dask",
    "map_stencil",
    "map_windows",
    "reduce",
    "register_windows",
    "windows_of",
]

#: Window readers by the name of the dask array they read (dask names are tokens of the
#: source: the same file and chunks give the same name). Bounded: the oldest are forgotten.
_WINDOWS: OrderedDict[str, Any] = OrderedDict()
_MAX_WINDOWS = 256


def is_dask(x: object) -> bool:
    """True for a ``dask.array.Array`` (checked without importing dask)."""
    return type(x).__module__.startswith("dask.array") and hasattr(x, "chunks")


def any_dask(*xs: object) -> bool:
    """True if any argument is a dask array."""
    return any(is_dask(x) for x in xs)


def as_dask(name: str, a: Any, like: Any | None) -> Any:
    import dask.array as da

    if not is_dask(a):
        a = np.asarray(a)
        if like is not None and a.shape != like.shape:
            raise InputError(f"{name}: expected shape {like.shape} (like the image), got {a.shape}")
        a = da.from_array(a, chunks=like.chunks if like is not None else "auto")
    if a.ndim != 2:
        raise InputError(f"{name}: expected a 2-D (H, W) array, got shape {a.shape}")
    if not (np.issubdtype(a.dtype, np.number) or np.issubdtype(a.dtype, np.bool_)) or np.issubdtype(
        a.dtype, np.complexfloating
    ):
        raise InputError(f"{name}: expected real numbers, got dtype {a.dtype}")
    if like is not None and a.shape != like.shape:
        raise InputError(f"{name}: expected shape {like.shape} (like the image), got {a.shape}")
    return a


def map_stencil(
    func: Callable[..., np.ndarray],
    arrays: Mapping[str, Any],
    *,
    halo: int,
    dtype: type = np.float32,
    **params: Any,
) -> Any:
    """``func(**arrays, **params)`` evaluated chunk by chunk with a halo of ``halo`` cells.

    Parameters
    ----------
    func : callable
        The in-memory operator, taking the arrays as keyword arguments.
    arrays : mapping of str to array or None
        2-D arrays of one shape by parameter name (the first one sets the chunking; numpy
        arrays are chunked like it); None values are passed on as None.
    halo : int >= 0
        The operator's stencil radius: how far from an output cell the cells it reads lie.
    dtype : numpy dtype
        Of the 2-D output.
    **params
        Passed on to ``func`` unchanged. They are checked now, by running ``func`` on a 3x3
        sample, so a bad parameter raises here and not in the middle of a computation.

    Returns
    -------
    dask.array.Array
        Lazy (H, W) result, chunked like the first array, equal bit for bit to
        ``func(**computed arrays, **params)``.
    """
    import dask.array as da

    names = [k for k, v in arrays.items() if v is not None]
    lead = next(k for k in names if is_dask(arrays[k]))
    first = as_dask(lead, arrays[lead], None)
    blocks = [as_dask(k, arrays[k], first) for k in names]
    blocks = list(da.core.unify_chunks(*(x for b in blocks for x in (b, "ij")))[1])
    # The same checks the in-memory path makes, on a sample of each input's dtype.
    func(**{k: np.zeros((3, 3), b.dtype) for k, b in zip(names, blocks, strict=True)}, **params)

    def block(*parts: np.ndarray) -> np.ndarray:
        return func(**dict(zip(names, parts, strict=True)), **params)

    if halo == 0:
        return da.map_blocks(block, *blocks, dtype=dtype, meta=np.empty((0, 0), dtype))
    # A halo may not be wider than a chunk: merge chunks smaller than it with a
    # neighbour (values are unchanged; only the task grid is coarser).
    chunks = tuple(da.overlap.ensure_minimum_chunksize(halo, c) for c in blocks[0].chunks)
    if chunks != blocks[0].chunks:
        blocks = [b.rechunk(chunks) for b in blocks]
    return da.map_overlap(
        block,
        *blocks,
        depth=halo,
        boundary="none",
        trim=True,
        align_arrays=False,
        dtype=dtype,
        meta=np.empty((0, 0), dtype),
    )


def reduce(*values: Any) -> tuple:
    """Compute several lazy reductions (or plain values) in one pass over the data."""
    import dask

    return dask.compute(*values)


def register_windows(array: Any, reader: Any) -> Any:
    """Say that ``reader[rows, cols]`` (two slices, steps 1) returns the values of the 2-D dask
    ``array`` in that window, as ``array[rows, cols].compute()`` would, bit for bit, reading
    only that window. ``reader`` must be picklable (it travels to distributed workers).
    Returns ``array``."""
    _WINDOWS[array.name] = reader
    _WINDOWS.move_to_end(array.name)
    while len(_WINDOWS) > _MAX_WINDOWS:
        _WINDOWS.popitem(last=False)
    return array


def windows_of(array: Any) -> Any | None:
    """The window reader registered for exactly this dask array (None for any other array,
    a slice or a computation of it included)."""
    return _WINDOWS.get(getattr(array, "name", None)) if is_dask(array) else None


def map_windows(
    func: Callable[[np.ndarray, tuple[slice, slice]], np.ndarray],
    array: Any,
    *,
    halo: int,
    dtype: type = np.float32,
    bands: int | None = None,
) -> Any:
    """``func`` on every chunk of a registered ``array`` (:func:`register_windows`), each chunk
    read with a halo of ``halo`` cells by its own task.

    Parameters
    ----------
    func : callable
        ``func(window, inner)``: ``window`` the cells of the chunk and up to ``halo`` cells
        around it (fewer at the grid's own edges, as ``map_overlap(boundary="none")`` gives),
        ``inner`` the (rows, cols) slices of the chunk in it. Returns the chunk's result:
        shape of ``window[inner]``, plus an axis of ``bands`` if given.
    array : dask.array.Array
        2-D, with a window reader (:func:`windows_of` is not None).
    halo : int >= 0
        How far from an output cell the cells ``func`` reads lie (its stencil radius).
    dtype : numpy dtype
        Of the result.
    bands : int, optional
        Length of a third axis of the result (an RGBA map: 4).

    Returns
    -------
    dask.array.Array
        Lazy, chunked like ``array`` (and one chunk along the bands); no task depends on
        another, so each can be computed, written and dropped alone.
    """
    import dask.array as da

    reader = windows_of(array)
    if reader is None:
        raise InputError("map_windows: the array has no window reader (see register_windows)")
    halo = int(halo)
    if halo < 0:
        raise InputError(f"halo: expected an integer >= 0, got {halo}")
    rows, cols = array.shape

    def block(block_info=None) -> np.ndarray:
        (r0, r1), (c0, c1) = block_info[None]["array-location"][:2]
        a0, b0 = max(0, r0 - halo), max(0, c0 - halo)
        window = reader[a0 : min(rows, r1 + halo), b0 : min(cols, c1 + halo)]
        inner = (slice(r0 - a0, r1 - a0), slice(c0 - b0, c1 - b0))
        return func(window, inner)

    chunks = array.chunks if bands is None else (*array.chunks, (int(bands),))
    meta = np.empty((0,) * len(chunks), dtype)
    return da.map_blocks(block, chunks=chunks, dtype=dtype, meta=meta)
