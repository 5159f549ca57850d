"""Run a serial numba kernel over bands of rows on every core.

Our per-pixel kernels used to be ``@njit(parallel=True)`` with a ``prange`` over rows. numba
compiles such a kernel twice over (the function and the gufunc its parallel passes outline
from the loop, each re-optimising everything the loop calls) and its parallel passes analyse
the loop body: about a second more per kernel than the same loop written serially, and ten on
the edge pass. On a user's first run that was a third of the compile time.

So each kernel is a serial ``@njit(nogil=True)`` function of a band ``i0 .. i1`` of its
outer loop, and :func:`run_bands` calls it on one band per thread: the calling thread takes
the first band, a pool of threads the others. numba releases the GIL for the whole call, so
the bands run at the same time; the split is numba's own default (equal, static chunks), so
the work per thread, and every output pixel, is what ``prange`` gave.

The kernels are compiled with ``_nrt=False`` (numba's reference counting off). A serial loop
with it on pays an NRT incref and decref per pixel on every array that reaches an inlined
helper (the parfor gufuncs did not): 1.1-5x slower than the prange loop. Without it a kernel
cannot allocate, so a band's working rows come from ``run_bands(..., scratch=...)``.

The thread count is ``NUMBA_NUM_THREADS`` (numba's default: every core), read once per
process: the variable that sized numba's pool sizes this one, so a dask worker's
``NUMBA_NUM_THREADS = cores // workers`` (:func:`sciviz_gbuf.writers.cog.local_client`) and
the one-thread warm-up process (:mod:`sciviz_gbuf.apps.warmup`) keep their meaning.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager

__all__ = ["band_edges", "on_this_thread", "run_bands", "threads"]

#: Fewer items than this per band are not worth a thread's wake-up (~20 us): small images
#: (a live overlay's thumbnails, the tests' 48 x 36 captures) run in the calling thread.
MIN_ITEMS_PER_BAND = 8

_lock = threading.Lock()
_local = threading.local()  # .serial: run_bands runs every band on this thread
_pool: ThreadPoolExecutor | None = None
_pool_pid = -1
_threads = 0


def threads() -> int:
    """Threads :func:`run_bands` uses, >= 1: ``NUMBA_NUM_THREADS`` if set, else numba's
    default for it (the cores this process may run on), read once."""
    global _threads
    if _threads == 0:
        try:
            _threads = int(os.environ.get("NUMBA_NUM_THREADS", "0"))
        except ValueError:
            _threads = 0
        if _threads < 1:
            try:
                _threads = len(os.sched_getaffinity(0))
            except AttributeError:  # not on Linux
                _threads = os.cpu_count() or 1
        _threads = max(1, _threads)
    return _threads


def _executor() -> ThreadPoolExecutor:
    """The pool of helper threads, made on first use and again in a forked child (a pool
    inherited through ``fork`` has no threads left but believes it has)."""
    global _pool, _pool_pid
    with _lock:
        if _pool is None or _pool_pid != os.getpid():
            _pool = ThreadPoolExecutor(
                max_workers=max(1, threads() - 1), thread_name_prefix="sciviz_gbuf_band"
            )
            _pool_pid = os.getpid()
        return _pool


@contextmanager
def on_this_thread() -> Iterator[None]:
    """Within the block, :func:`run_bands` called on this thread runs the whole loop here, as
    one band: for a caller that already gives each core a piece of work of its own (blocks of
    a map computed at once on threads), whose kernels would otherwise wait for the one
    shared pool (and, from a pool thread, for themselves)."""
    before = getattr(_local, "serial", False)
    _local.serial = True
    try:
        yield
    finally:
        _local.serial = before


def band_edges(n: int, parts: int) -> list[int]:
    """``parts + 1`` increasing edges splitting ``range(n)`` into equal bands (the first ones
    one item longer when ``n`` does not divide)."""
    base, extra = divmod(n, parts)
    edges = [0]
    for p in range(parts):
        edges.append(edges[-1] + base + (1 if p < extra else 0))
    return edges


def run_bands(
    kernel: Callable[..., object],
    n: int,
    *args: object,
    scratch: Callable[[], tuple[object, ...]] | None = None,
    min_items: int = MIN_ITEMS_PER_BAND,
) -> None:
    """Call ``kernel(i0, i1, *args)`` on bands ``[i0, i1)`` covering ``range(n)``, at once.

    Parameters
    ----------
    kernel : callable
        A serial ``@njit(nogil=True)`` kernel whose first two arguments are the band; it must
        write only the rows of its band (bands run concurrently).
    n : int
        Length of the outer loop (rows of the output, or row blocks).
    *args
        The kernel's other arguments, the same for every band.
    scratch : callable, optional
        Called once per band; the arrays it returns are appended to that band's arguments,
        a working space of its own. The kernels are compiled without numba's reference
        counting (see the module notes), so they cannot allocate.
    min_items : int, default: MIN_ITEMS_PER_BAND
        The fewest items worth a band of their own (1 for items that are strips of rows).

    Notes
    -----
    An exception in a band is raised here after every band has ended, so no band still
    writes into an output the caller no longer holds.
    """
    n = int(n)
    if n <= 0:
        return
    parts = min(threads(), max(1, n // max(1, int(min_items))))

    def band_args() -> tuple[object, ...]:
        return args if scratch is None else (*args, *scratch())

    if parts == 1 or getattr(_local, "serial", False):
        kernel(0, n, *band_args())
        return
    edges = band_edges(n, parts)
    pool = _executor()
    futures: list[Future] = [
        pool.submit(kernel, edges[p], edges[p + 1], *band_args()) for p in range(1, parts)
    ]
    error: BaseException | None = None
    try:
        kernel(edges[0], edges[1], *band_args())
    except BaseException as exc:  # wait for the other bands before raising
        error = exc
    for fut in futures:
        exc = fut.exception()
        if error is None and exc is not None:
            error = exc
    if error is not None:
        raise error
