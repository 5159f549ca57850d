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
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .errors import InputError

__all__ = ["any_dask", "as_dask", "is_dask", "map_stencil", "reduce"]


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
