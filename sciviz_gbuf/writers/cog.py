"""Cloud-Optimised GeoTIFF output of images larger than memory (dask), block by block.

:func:`write_cog` computes a (dask) image one chunk at a time; where each chunk is computed
(a thread of this process, or a ``dask.distributed`` worker) its tiles, and its tiles of the
overview levels that lie inside it, are deflated, and only those bytes come back. This
process stores them in a scratch file as they arrive, builds the coarse overview levels from
the chunks' halved pieces and writes the COG in its layout
(:mod:`sciviz_gbuf.writers._cog_layout`). Nothing holds the whole image, and nothing is
encoded twice: workers add up. The chunks are computed on any dask scheduler: the local
threads (default), a local process pool, or a cluster.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .. import _dask
from .._atomic import atomic_output, scratch_file
from .._progress import progress
from ..errors import InputError, SciVizGBufError
from ._cog_layout import (
    TILE,
    TileStore,
    deflate_level,
    encode_block,
    geo_entries,
    level_shapes,
    worker_levels,
)
from .geotiff import check_tiff, georeference, rasterio_crs
from .png import check_image, to_uint8, write_png

__all__ = [
    "BLOCK",
    "BYTES_PER_MAP_CELL",
    "check_chunk_memory",
    "check_cog_target",
    "check_worker_memory",
    "cog_target",
    "killed_worker_error",
    "local_client",
    "write_cog",
]

#: COG tile edge (GDAL's default for the COG driver).
BLOCK = TILE
#: Blocks of an in-memory image, encoded on this process's threads: whole tiles of levels
#: 0-2 each, the coarser levels from their pieces.
NUMPY_BLOCK = 4 * TILE
#: Write buffer of the COG file.
_WRITE_BUFFER = 8 * 2**20


def local_client(
    n_workers: int = 2,
    *,
    threads_per_worker: int = 1,
    memory_limit: str | int | None = "3GB",
):
    """A ``distributed.Client`` of a new ``LocalCluster`` of worker processes.

    Each worker runs ``threads_per_worker`` dask threads, and each of those may run our
    filters' numba kernels on bands of rows, one band per thread (:mod:`sciviz_gbuf.core.bands`).
    That thread count is ``NUMBA_NUM_THREADS`` as numba reads it at import, default all cores,
    so 2 workers on 2 cores would run 4 threads. The workers' environment therefore gets
    ``NUMBA_NUM_THREADS = cores // (n_workers * threads_per_worker)`` (at least 1), through
    dask's ``distributed.nanny.pre-spawn-environ`` so it is set before anything imports numba
    in the worker. A ``NUMBA_NUM_THREADS`` already set in this process's environment wins (dask's
    rule: existing variables over configuration).

    Parameters
    ----------
    n_workers : int, optional
        Worker processes (default 2).
    threads_per_worker : int, optional
        Dask threads per worker (default 1).
    memory_limit : str or int, optional
        Per worker, as ``LocalCluster`` takes it (default ``"3GB"``; None: no limit).

    Returns
    -------
    distributed.Client
        Close it with ``client.close()`` and its ``client.cluster.close()``.
    """
    import dask
    from distributed import Client, LocalCluster

    for value, what in ((n_workers, "n_workers"), (threads_per_worker, "threads_per_worker")):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise InputError(f"{what}: expected a positive integer, got {value!r}")
    numba_threads = max(1, (os.cpu_count() or 1) // (n_workers * threads_per_worker))
    # Pre-spawn, not the nanny's env=: a spawned worker re-imports the parent's __main__, which
    # may import numba before env= is applied. Dask puts these into os.environ before it
    # spawns; the old value is restored after (workers restarted later get the same).
    spawn_env = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    spawn_env["NUMBA_NUM_THREADS"] = numba_threads
    before = os.environ.get("NUMBA_NUM_THREADS")
    try:
        with dask.config.set({"distributed.nanny.pre-spawn-environ": spawn_env}):
            cluster = LocalCluster(
                n_workers=n_workers,
                threads_per_worker=threads_per_worker,
                processes=True,
                memory_limit=memory_limit if memory_limit is not None else 0,
                dashboard_address=None,
            )
    finally:
        if before is None:
            os.environ.pop("NUMBA_NUM_THREADS", None)
        else:
            os.environ["NUMBA_NUM_THREADS"] = before
    return Client(cluster)


def write_cog(
    image: Any,
    path: str | os.PathLike,
    *,
    dem: object = None,
    transform: Sequence[float] | None = None,
    crs: str | None = None,
    overview_png: str | os.PathLike | None = None,
    overview_size: int = 2048,
    client: Any = None,
    progress_bar: bool = False,
) -> Path:
    """Write an image (numpy or dask) as a georeferenced Cloud-Optimised GeoTIFF.

    The image is computed and written chunk by chunk: at no point is all of it in memory, so
    a lazy :func:`~sciviz_gbuf.recipes.terrain.topographic_map` of a DEM read with
    ``read_dem(..., chunks=...)`` can be any size the disk holds. Output: 512 x 512 tiles,
    deflate (horizontal predictor), internal overviews (halving until a level fits one
    tile, GDAL's COG ``OVERVIEWS=AUTO``; each pixel the mean of the 2 x 2 below it, the colour
    weighted by alpha), BigTIFF when needed, the fourth band tagged as alpha like
    :func:`~sciviz_gbuf.compose.write_geotiff`. GDAL reads the file as ``LAYOUT=COG``
    (checked after writing).

    Each chunk's tiles, and its tiles of the overview levels that lie inside it, are
    deflated where the chunk is computed (a dask worker, or a thread): nothing is encoded
    twice, and workers add up (:mod:`sciviz_gbuf.writers._cog_layout`). This process only
    stores the encoded tiles, builds the few coarse levels from the chunks' halved pieces,
    and writes the file in the COG order.

    Parameters
    ----------
    image : (H, W), (H, W, 3) or (H, W, 4) numpy or dask array
        uint8 (as is), bool (0/255) or float in ``[0, 1]`` (``round(255 x)``), like
        :func:`~sciviz_gbuf.compose.write_geotiff`. A dask array is computed one chunk at a
        time (chunks are grown to multiples of 512 pixels so each holds whole tiles; chunks
        of 2048 or 4096 pixels let the workers encode the overview levels too).
    path : str or path-like
        Output ``.tif``/``.tiff``; its directory must exist. Temporary files beside it
        (removed afterwards) hold the encoded tiles and a coarse level before the COG is
        written, so that folder needs about the output's size free twice.
    dem : sciviz_gbuf.readers.DEM, optional
        Take ``transform`` and ``crs`` from this DEM; an image of another size covers the
        DEM's extent (the pixel size follows the image, as in
        :func:`~sciviz_gbuf.compose.write_geotiff`).
    transform : 6 floats, optional
        GDAL geotransform of the pixel corners.
    crs : str, optional
        Anything rasterio's ``CRS.from_user_input`` accepts.
    overview_png : str or path-like, optional
        Also write a PNG preview of at most ``overview_size`` pixels on its long side, read
        from the COG's overviews (never the full-resolution grid).
    overview_size : int, optional
        Long side of the PNG preview in pixels (default 2048); smaller images keep their size.
    client : distributed.Client, str or None, optional
        Where to compute a dask image: None uses dask's current scheduler (the local threads,
        or the default ``distributed`` client if one is active); a ``Client``; the address of
        a running scheduler (``"tcp://host:8786"``); or ``"local"`` for a new
        :func:`local_client` (2 worker processes), closed afterwards. With ``distributed``,
        the blocks are one graph (each input chunk read once), gathered as they finish
        (encoded tiles, a fraction of the pixels' bytes) and each stored and dropped at once.
    progress_bar : bool, optional
        Show a tqdm bar of blocks written (PyVista's convention).

    Returns
    -------
    pathlib.Path
        The COG written.

    Raises
    ------
    InputError
        A path not ending in ``.tif``/``.tiff`` (``.png`` for ``overview_png``) or in a missing
        folder, no georeference (neither ``dem=`` nor ``transform=``) or both, a bad
        transform or CRS, an image of another shape or dtype, a bad
        ``overview_size`` or ``client``.
    OutputError
        The COG or its preview could not be written completely (disk full, file too large,
        interrupted): neither is left under its name. Both are written to temporary files
        beside them, checked (GDAL reads the TIFF whole, its layout a COG) and renamed only
        when both are done (the preview first).
    """
    _cog_paths(path, overview_png, overview_size)
    pixels = _as_uint8(image)
    is_lazy = _dask.is_dask(pixels)
    if is_lazy:
        pixels = _aligned(pixels)
        chunks = pixels.chunks[:2]
    else:
        chunks = tuple(_steps(n, NUMPY_BLOCK) for n in pixels.shape[:2])
    with cog_target(
        path, pixels.shape, chunks, dem=dem, transform=transform, crs=crs,
        overview_png=overview_png, overview_size=overview_size, progress_bar=progress_bar,
    ) as sink:  # fmt: skip
        if is_lazy:
            _compute_into(pixels, sink, client, sink.job)
        else:
            _encode_numpy(pixels, chunks, sink, sink.job)
    return Path(path)


def _cog_paths(
    path: str | os.PathLike, overview_png: str | os.PathLike | None, overview_size: int
) -> tuple[Path, Path | None]:
    """The checked COG path and preview path (None without a preview); ``overview_size``
    is checked too."""
    out = _tif_path(path)
    png = None if overview_png is None else _png_path(overview_png)
    if isinstance(overview_size, bool) or not isinstance(overview_size, (int, np.integer)):
        raise InputError(f"overview_size: expected a positive int, got {overview_size!r}")
    if overview_size < 1:
        raise InputError(f"overview_size: expected a positive int, got {overview_size!r}")
    return out, png


def check_cog_target(
    path: str | os.PathLike, dem: object, overview_png: str | os.PathLike | None = None,
    overview_size: int = 2048,
) -> None:  # fmt: skip
    """Raise :class:`~sciviz_gbuf.errors.InputError` unless :func:`write_cog` could write a
    COG of ``dem``'s grid to ``path`` with that preview (names, folders, size and
    georeference): for a caller that checks before it computes the image."""
    _cog_paths(path, overview_png, overview_size)
    georeference(dem, None, None, "write_cog")


@contextmanager
def cog_target(
    path: str | os.PathLike, shape: tuple[int, ...], chunks: tuple, *, dem: object = None,
    transform: Sequence[float] | None = None, crs: str | None = None,
    overview_png: str | os.PathLike | None = None, overview_size: int = 2048,
    progress_bar: bool = False,
) -> Iterator[_Sink]:  # fmt: skip
    """The COG :func:`write_cog` writes, of an (H, W, C) uint8 image cut into blocks of
    ``chunks`` (row sizes, column sizes; each a multiple of 512 but the last), as a sink:
    ``sink(r0, c0, tiles, piece)`` stores the result of
    :func:`~sciviz_gbuf.writers._cog_layout.encode_block` ``(block, r0, c0, *sink.job)`` of
    each block (from any thread, in any order); ``sink.encode(block, r0, c0)`` does both.
    The paths and the georeference are checked on entry; on leaving without an error the
    coarse levels are encoded and the COG (and its preview) written, checked and renamed
    into place; on an error nothing is left.

    For images made block by block elsewhere (the streamed topographic map): each block's
    tiles are deflated where the block is made."""
    out, png = _cog_paths(path, overview_png, overview_size)
    h, w, c = (int(v) for v in shape)
    gt = georeference(dem, transform, crs, "write_cog", (h, w))
    geo = geo_entries(tuple(gt), rasterio_crs(dem.crs if dem is not None else crs))
    n_blocks = len(chunks[0]) * len(chunks[1])
    n_levels = len(level_shapes(h, w))
    top = worker_levels(chunks, n_levels)
    zlevel = deflate_level(h * w >= 4_000_000)
    steps = n_blocks + (n_levels - 1 - top) + 1 + (png is not None)
    with (
        progress(progress_bar, steps, "write_cog") as bar,
        # The COG and its preview are complete or absent: the COG stays in its temporary file
        # until the preview (read from it) is written too.
        atomic_output(path) as part,
        ExitStack() as scratch,
    ):
        store = TileStore((h, w, c), lambda tag: scratch.enter_context(scratch_file(out, tag)))
        scratch.callback(store.close)
        sink = _Sink(store, top, bar, n_blocks)
        sink.job = (top, n_levels, zlevel)
        yield sink
        if top < n_levels - 1:
            store.encode_levels(top + 1, zlevel, bar.step)
        gap = store.missing()
        if gap is not None:
            part.fail(f"tile {gap[1:]} of level {gap[0]} was not computed")
        with open(part.path, "wb", buffering=_WRITE_BUFFER) as f:
            part.expected_size = store.write(f, geo)
        scratch.close()  # the scratch files go before the checks
        bar.step("COG")
        check_tiff(part, (h, w, c))
        problem = _layout_problem(part.path)
        if problem is not None:
            part.fail(f"not a valid Cloud-Optimised GeoTIFF: {problem}")
        if png is not None:
            _overview_png(part.path, png, int(overview_size))
            bar.step("overview")


def _steps(n: int, step: int) -> tuple[int, ...]:
    """Chunk sizes of ``n`` pixels in steps of ``step``."""
    return tuple(min(step, n - s) for s in range(0, n, step))


def _block_origins(chunks: Sequence[Sequence[int]]) -> list[tuple[int, int, int, int]]:
    """``(i, j, r0, c0)``: index and first pixel of every block of a grid of ``chunks``,
    row-major."""
    r_edges, c_edges = (np.cumsum((0, *c))[:-1] for c in chunks[:2])
    return [
        (i, j, int(r0), int(c0)) for i, r0 in enumerate(r_edges) for j, c0 in enumerate(c_edges)
    ]


class _Sink:
    """Stores the encoded tiles of a block and places its piece of the first level this
    process encodes; one call per block, from any thread."""

    def __init__(self, store: TileStore, top: int, bar: Any, total: int) -> None:
        self.store, self.top, self.bar, self.total = store, top, bar, total
        #: ``(top, n_levels, zlevel)``: encode_block's arguments after the block's origin
        self.job: tuple = ()
        self.done = 0
        self.lock = threading.Lock()

    def encode(self, block: np.ndarray, r0: int, c0: int) -> None:
        """Encode an (h, w, c) uint8 block at pixel ``(r0, c0)`` here (this thread) and
        store it."""
        self(r0, c0, *encode_block(block, r0, c0, *self.job))

    def __call__(self, r0: int, c0: int, tiles: list, piece: np.ndarray | None) -> None:
        self.store.add(tiles)
        if piece is not None:
            k = self.top + 1
            self.store.put(k, r0 >> k, c0 >> k, piece)
        with self.lock:
            self.done += 1
            self.bar.step(f"block {self.done}/{self.total}")


def _encode_numpy(pixels: np.ndarray, chunks: tuple, sink: _Sink, job: tuple) -> None:
    """An in-memory image: its blocks encoded on this process's threads (deflate and numpy
    release the GIL)."""
    rows, cols = chunks

    def run(origin: tuple[int, int, int, int]) -> None:
        i, j, r0, c0 = origin
        block = pixels[r0 : r0 + rows[i], c0 : c0 + cols[j]]
        sink(r0, c0, *encode_block(block, r0, c0, *job))

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        for _ in pool.map(run, _block_origins(chunks)):
            pass


def check_cog(path: str | os.PathLike) -> None:
    """Raise :class:`~sciviz_gbuf.errors.SciVizGBufError` unless ``path`` is a COG (GDAL's
    ``LAYOUT=COG``), tiled and with overviews when larger than one tile."""
    problem = _layout_problem(path)
    if problem is not None:
        raise SciVizGBufError(f"{path}: not a valid Cloud-Optimised GeoTIFF ({problem})")


def _layout_problem(path: str | os.PathLike) -> str | None:
    """What makes ``path`` no COG (``LAYOUT``, tiling, overviews), or None."""
    import rasterio

    with rasterio.open(path) as src:
        layout = src.tags(ns="IMAGE_STRUCTURE").get("LAYOUT")
        tiled = src.profile.get("tiled", False)
        overviews = src.overviews(1)
        big = max(src.shape) > BLOCK
    # one tile: rasterio calls a file whose tile is the whole image untiled
    if layout != "COG" or (big and (not tiled or not overviews)):
        return f"LAYOUT={layout}, tiled={tiled}, overviews={overviews}"
    return None


def _tif_path(path: str | os.PathLike) -> Path:
    p = Path(path)
    if p.suffix.lower() not in (".tif", ".tiff"):
        raise InputError(f"path: expected a file name ending in .tif or .tiff, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"path: no such directory {str(p.parent)!r}")
    return p


def _png_path(path: str | os.PathLike) -> Path:
    p = Path(path)
    if p.suffix.lower() != ".png":
        raise InputError(f"overview_png: expected a file name ending in .png, got {str(p)!r}")
    if not p.parent.is_dir():
        raise InputError(f"overview_png: no such directory {str(p.parent)!r}")
    return p


def _as_uint8(image: Any):
    """(H, W, C) uint8, C in 1, 3, 4: numpy converted now, dask lazily (per block)."""
    if not _dask.is_dask(image):
        a = check_image(image)  # shape and dtype, with write_geotiff's messages
        # uint8 is read as it is (the encoder only reads it: no copy of a 256 MB map)
        a = a if a.dtype == np.uint8 else to_uint8(a)
        return a[..., None] if a.ndim == 2 else a
    if not (image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (3, 4))):
        raise InputError(f"image: expected shape (H, W), (H, W, 3) or (H, W, 4), got {image.shape}")
    if 0 in image.shape or any(np.isnan(s) for s in image.shape):
        raise InputError(f"image: expected a non-empty image of known shape, got {image.shape}")
    if image.dtype == np.bool_:
        image = image.astype(np.uint8) * np.uint8(255)
    elif np.issubdtype(image.dtype, np.floating):
        image = image.map_blocks(to_uint8, dtype=np.uint8)
    elif image.dtype != np.uint8:
        raise InputError(f"image: expected float in [0, 1], uint8 or bool, got dtype {image.dtype}")
    return image[..., None] if image.ndim == 2 else image


def _aligned(image):
    """Rechunk so each block covers whole 512-pixel tiles (edge blocks excepted) and all bands.

    Writes of part of a compressed tile make GDAL recompress it and append it again."""
    rows, cols = (
        c if all(s % BLOCK == 0 for s in c[:-1]) else -(-max(c) // BLOCK) * BLOCK
        for c in image.chunks[:2]
    )
    target = (rows, cols, -1)
    if rows == image.chunks[0] and cols == image.chunks[1] and len(image.chunks[2]) == 1:
        return image
    return image.rechunk(target)


def _block_tasks(image, job: tuple) -> list[tuple[int, int, Any]]:
    """``(r0, c0, task)`` of every block, row-major: the task encodes the block
    (:func:`~sciviz_gbuf.writers._cog_layout.encode_block`) where it is computed. All tasks
    share one graph: a map block needs its neighbours' input chunks (the halo), and only
    within one graph is each input chunk read (or generated) once."""
    import dask

    blocks = image.to_delayed()
    encode = dask.delayed(encode_block, pure=True)
    return [
        (r0, c0, encode(blocks[i, j, 0], r0, c0, *job))
        for i, j, r0, c0 in _block_origins(image.chunks)
    ]


def _compute_into(image, sink: _Sink, client: Any, job: tuple) -> None:
    """Compute and encode every block of ``image`` on the scheduler ``client`` says, each
    result stored by ``sink`` as it comes."""
    from dask.base import get_scheduler

    if client is None:
        scheduler = get_scheduler(collections=[image])
        owner = getattr(scheduler, "__self__", None)  # Client.get of an active client
        if owner is not None and type(owner).__name__ == "Client":
            _compute_distributed(image, sink, owner, job)
        elif getattr(scheduler, "__module__", "") in ("dask.threaded", "dask.local"):
            _compute_local(image, sink, scheduler, job)
        else:
            _compute_batches(image, sink, scheduler, job)
        return
    with _client(client) as c:
        _compute_distributed(image, sink, c, job)


def _compute_local(image, sink: _Sink, scheduler: Any, job: tuple) -> None:
    """This process's threads (or the synchronous scheduler): one graph whose last step per
    block stores it, so each block's result is dropped as soon as it is stored."""
    import dask

    def store(r0: int, c0: int, result: tuple) -> None:
        sink(r0, c0, *result)

    put = dask.delayed(store, pure=False)
    dask.compute(*(put(r0, c0, task) for r0, c0, task in _block_tasks(image, job)),
                 scheduler=scheduler)  # fmt: skip


@contextmanager
def _client(client: Any) -> Iterator[Any]:
    """A ``Client`` for ``client=``: as given, connected to an address, or a new local one."""
    if isinstance(client, str):
        from distributed import Client

        if client == "local":
            c = local_client()
            try:
                yield c
            finally:
                cluster = c.cluster
                c.close()
                cluster.close()
            return
        try:
            c = Client(client, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(
                f"client: cannot connect to a dask scheduler at {client!r} ({exc})"
            ) from exc
        try:
            yield c
        finally:
            c.close()
        return
    if not hasattr(client, "compute") or not hasattr(client, "nthreads"):
        raise InputError(
            f"client: expected a distributed.Client, a scheduler address or 'local', got {client!r}"
        )
    yield client


def _compute_distributed(image, sink: _Sink, client: Any, job: tuple) -> None:
    """Blocks computed and encoded on the cluster, gathered one by one as they finish, each
    stored and released at once.

    All blocks go to the scheduler as one graph (:func:`_block_tasks`). Memory stays bounded
    on the workers by dask's queuing of root tasks (inputs are produced as fast as blocks
    finish) and in this process because a block's result is its encoded tiles (a fraction of
    its pixels) and storing them takes far less time than computing them.
    """
    from distributed import KilledWorker, as_completed

    check_worker_memory(client, _block_shape(image))
    tasks = _block_tasks(image, job)
    futures = client.compute([task for _, _, task in tasks])
    where = {f.key: (r0, c0) for f, (r0, c0, _) in zip(futures, tasks, strict=True)}
    del tasks
    queue = as_completed(futures)
    del futures  # the queue holds them; each is released once its block is stored
    try:
        for future in queue:
            result = future.result()
            sink(*where.pop(future.key), *result)
            future.release()
            del result
    except KilledWorker as exc:
        # A task that killed its workers (dask's allowed-failures, 3 by default): almost always
        # the memory limit. Say so instead of dask's task key.
        raise killed_worker_error(_block_shape(image)) from exc


#: Bytes a worker needs per map cell of a block (an estimate, used only to refuse a hopeless
#: memory limit at once): about ten float32 layers (heights and their halo copy, filled
#: heights, relief, contour ink, sky view, gradients), the RGBA result and dask's copies of
#: inputs and outputs, with a margin.
BYTES_PER_MAP_CELL = 60


def _block_shape(image) -> tuple[int, int]:
    return max(image.chunks[0]), max(image.chunks[1])


def killed_worker_error(block: tuple[int, int]) -> InputError:
    """The one-line error for dask's ``KilledWorker``: a task killed every worker that tried it
    (``distributed.scheduler.allowed-failures`` times), almost always the memory limit."""
    import dask

    tries = int(dask.config.get("distributed.scheduler.allowed-failures", 3)) + 1
    return InputError(
        f"memory limit: dask workers died {tries} times on one task with chunks of "
        f"{block[0]}x{block[1]} cells: use smaller chunks (--chunks) or a larger --memory-limit"
    )


def check_worker_memory(client: Any, block: tuple[int, int]) -> None:
    """Refuse at once a cluster whose workers' memory limit cannot hold one block of ``block``
    = (rows, columns) cells: dask would otherwise restart them again and again (a task that
    kills its worker is retried on the next one)."""
    try:
        workers = client.scheduler_info().get("workers", {})
        limits = [w.get("memory_limit") or 0 for w in workers.values()]
    except Exception:  # a scheduler that does not report it: no check
        return
    limits = [m for m in limits if m > 0]
    if limits:
        check_chunk_memory(block, min(limits))


def check_chunk_memory(block: tuple[int, int], limit: int) -> None:
    """InputError if one map block of ``block`` = (rows, columns) cells does not fit in a
    worker memory limit of ``limit`` bytes (see :data:`BYTES_PER_MAP_CELL`)."""
    h, w = block
    need = h * w * BYTES_PER_MAP_CELL
    if need > limit:
        raise InputError(
            f"memory limit: chunks of {h}x{w} cells need about {need / 2**20:.0f} MB on a "
            f"worker, the workers are limited to {limit / 2**20:.0f} MB: use smaller "
            "chunks (--chunks) or a larger --memory-limit"
        )


def _compute_batches(image, sink: _Sink, scheduler: Any, job: tuple) -> None:
    """Other local schedulers (processes): bounded batches of blocks, each stored in turn."""
    import dask

    batch = 2 * (os.cpu_count() or 1)
    tasks = _block_tasks(image, job)
    for k in range(0, len(tasks), batch):
        part = tasks[k : k + batch]
        results = dask.compute(*(task for _, _, task in part), scheduler=scheduler)
        for (r0, c0, _), result in zip(part, results, strict=True):
            sink(r0, c0, *result)


def _overview_png(cog: Path, png: Path, size: int) -> None:
    """A PNG of at most ``size`` pixels on its long side, from the COG's overview levels."""
    import rasterio
    from rasterio.enums import Resampling

    with rasterio.open(cog) as src:
        h, w = src.shape
        scale = min(1.0, size / max(h, w))
        oh, ow = max(1, round(h * scale)), max(1, round(w * scale))
        # A decimated read: GDAL takes the nearest overview level at least this fine.
        data = src.read(out_shape=(src.count, oh, ow), resampling=Resampling.average)
    write_png(png, data[0] if data.shape[0] == 1 else np.moveaxis(data, 0, 2))
