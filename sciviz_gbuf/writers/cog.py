"""Cloud-Optimised GeoTIFF output of images larger than memory (dask), block by block.

:func:`write_cog` computes a (dask) image one chunk at a time, writes each chunk as a window
of a tiled temporary GeoTIFF beside the output, then lets GDAL's COG driver copy that file
into a Cloud-Optimised GeoTIFF with internal overviews (it streams: neither step holds the
whole image). The chunks are computed on any dask scheduler: the local threads (default), a
local process pool, or a ``dask.distributed`` cluster, whose results are streamed back and
written one by one as they finish, so the writing process's memory stays bounded too.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .. import _dask
from .._atomic import Part, atomic_output, scratch_file
from .._progress import progress
from ..errors import InputError, SciVizGBufError
from .geotiff import check_tiff, gdal_writing, georeference, rasterio_crs, uint8_profile
from .png import to_uint8, write_png

__all__ = [
    "BYTES_PER_MAP_CELL",
    "check_chunk_memory",
    "check_worker_memory",
    "killed_worker_error",
    "local_client",
    "write_cog",
]

#: COG tile edge (GDAL's default for the COG driver).
BLOCK = 512
#: GDAL block cache (MB) while writing: a few rows of 512-pixel tiles of a wide map.
_CACHE_MB = 256


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
    deflate (horizontal predictor), internal overviews (average resampling, GDAL's COG
    ``OVERVIEWS=AUTO``: halving until a level fits one tile), BigTIFF when needed, the fourth
    band tagged as alpha like :func:`~sciviz_gbuf.compose.write_geotiff`. GDAL marks the file
    ``LAYOUT=COG`` (checked after writing).

    Parameters
    ----------
    image : (H, W), (H, W, 3) or (H, W, 4) numpy or dask array
        uint8 (as is), bool (0/255) or float in ``[0, 1]`` (``round(255 x)``), like
        :func:`~sciviz_gbuf.compose.write_geotiff`. A dask array is computed one chunk at a
        time (chunks are grown to multiples of 512 pixels so each write fills whole tiles).
    path : str or path-like
        Output ``.tif``/``.tiff``; its directory must exist. A temporary file beside it (removed
        afterwards) holds the pixels before the COG copy, so that folder needs about the
        output's size free twice.
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
        the blocks are one graph (each input chunk read once), gathered as they finish and
        each written and dropped at once.
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
        The COG or its preview could not be written completely (disk full, file too large, a
        GDAL error, interrupted): neither is left under its name. Both are written to
        temporary files beside them, checked (the TIFF is whole, its layout a COG) and renamed
        only when both are done (the preview first).
    """
    import rasterio
    import rasterio.shutil
    from rasterio.enums import ColorInterp

    out = _tif_path(path)
    png = None if overview_png is None else _png_path(overview_png)
    if isinstance(overview_size, bool) or not isinstance(overview_size, (int, np.integer)):
        raise InputError(f"overview_size: expected a positive int, got {overview_size!r}")
    if overview_size < 1:
        raise InputError(f"overview_size: expected a positive int, got {overview_size!r}")
    pixels = _as_uint8(image)
    h, w, c = pixels.shape
    profile = _profile(h, w, c, dem, transform, crs)
    is_lazy = _dask.is_dask(pixels)
    if is_lazy:
        pixels = _aligned(pixels)
        n_blocks = len(pixels.chunks[0]) * len(pixels.chunks[1])
    else:
        n_blocks = -(-h // (4 * BLOCK))
    interp = {
        1: [ColorInterp.gray],
        3: [ColorInterp.red, ColorInterp.green, ColorInterp.blue],
        4: [ColorInterp.red, ColorInterp.green, ColorInterp.blue, ColorInterp.alpha],
    }[c]
    large = h * w >= 4_000_000
    with (
        # GDAL's block cache defaults to 5 % of RAM, filled with dirty tiles before it flushes:
        # a fixed cap keeps this process's memory independent of the image size.
        rasterio.Env(GDAL_CACHEMAX=_CACHE_MB),
        progress(progress_bar, n_blocks + 1 + (png is not None), "write_cog") as bar,
        # The COG and its preview are complete or absent: the COG stays in its temporary file
        # until the preview (read from it) is written too.
        atomic_output(path) as part,
    ):
        with scratch_file(out, "tiles") as tmp:
            writer = _WindowWriter(tmp, profile, interp, part, bar, n_blocks)
            try:
                if is_lazy:
                    _compute_into(pixels, writer, client)
                else:
                    for r0 in range(0, h, 4 * BLOCK):
                        writer[r0 : r0 + 4 * BLOCK, 0:w] = pixels[r0 : r0 + 4 * BLOCK]
            except BaseException:
                writer.close(quiet=True)
                raise
            writer.close()
            check_tiff(part, (h, w, c), tmp)  # the intermediate: its close may have failed
            with gdal_writing(part):
                _waiting(
                    rasterio.shutil.copy,
                    tmp,
                    part.path,
                    driver="COG",
                    BLOCKSIZE=BLOCK,
                    COMPRESS="DEFLATE",
                    # Level 1 on large maps: ~3x faster than 6 for a few % more bytes.
                    LEVEL=1 if large else 6,
                    PREDICTOR="YES",
                    RESAMPLING="AVERAGE",
                    OVERVIEWS="IGNORE_EXISTING",
                    BIGTIFF="IF_SAFER",
                    NUM_THREADS="ALL_CPUS",
                )
        check_tiff(part, (h, w, c))
        problem = _layout_problem(part.path)
        if problem is not None:
            part.fail(f"not a valid Cloud-Optimised GeoTIFF: {problem}")
        bar.step("COG")
        if png is not None:
            _overview_png(part.path, png, int(overview_size))
            bar.step("overview")
    return out


def _waiting(func: Any, *args: Any, **kwargs: Any) -> Any:
    """``func(*args, **kwargs)`` in a helper thread, this one waiting in short steps.

    A long GDAL call (the COG copy of a large map takes minutes) holds the main thread until it
    returns, and Python runs signal handlers only there, between bytecodes: SIGTERM would wait
    for the call. GDAL releases the GIL, so while it works in the helper this thread keeps
    running bytecodes, and the :func:`~sciviz_gbuf._atomic.raising_signals` handler raises at
    once; the clean-up that follows removes the files the abandoned call was writing.
    """
    import rasterio

    box: dict[str, Any] = {}
    options = rasterio.env.getenv() if rasterio.env.hasenv() else {}

    def run() -> None:
        try:
            with rasterio.Env(**options):  # rasterio's settings are per thread
                box["result"] = func(*args, **kwargs)
        except BaseException as exc:  # re-raised in the caller's thread
            box["error"] = exc

    helper = threading.Thread(target=run, name="sciviz-gbuf-gdal", daemon=True)
    helper.start()
    while helper.is_alive():
        helper.join(0.1)
    if "error" in box:
        raise box["error"]
    return box.get("result")


def check_cog(path: str | os.PathLike) -> None:
    """Raise :class:`~sciviz_gbuf.errors.SciVizGBufError` unless ``path`` is a tiled COG (GDAL's
    ``LAYOUT=COG``) with overviews (when larger than one tile)."""
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
    if layout != "COG" or not tiled or (big and not overviews):
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
        a = to_uint8(image)  # checks shape and dtype with write_geotiff's messages
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


def _profile(h: int, w: int, c: int, dem: Any, transform: Any, crs: Any) -> dict:
    """rasterio profile of the temporary tiled GeoTIFF, georeference checked."""
    from rasterio.transform import Affine

    gt = georeference(dem, transform, crs, "write_cog", (h, w))
    # Temporary: fastest deflate; the COG copy recompresses anyway.
    return uint8_profile(
        h,
        w,
        c,
        Affine.from_gdal(*gt),
        rasterio_crs(dem.crs if dem is not None else crs),
        block=BLOCK,
        zlevel=1,
        bigtiff=True,
    )


class _WindowWriter:
    """``writer[rows, cols] = block`` writes an (h, w, c) block as a window of the tiled
    GeoTIFF ``path``, one at a time; :meth:`close` closes it.

    Each GDAL call runs under :func:`~sciviz_gbuf.writers.geotiff.gdal_writing` (GDAL's
    messages and errors become the OutputError of ``part``), but not the progress bar's
    update, which must reach the terminal as it happens.
    """

    def __init__(
        self, path: Path, profile: dict, interp: list, part: Part, bar: Any, total: int
    ) -> None:
        import rasterio

        self.part, self.bar, self.total, self.done = part, bar, total, 0
        self.lock = threading.Lock()
        self.closed = False
        with gdal_writing(part):
            self.dst = rasterio.open(path, "w", **profile)
            self.dst.colorinterp = interp  # before the pixels: GDAL sets ExtraSamples then

    def __setitem__(self, key: tuple[slice, ...], block: np.ndarray) -> None:
        from rasterio.windows import Window

        r0, c0 = key[0].start or 0, key[1].start or 0
        block = np.asarray(block)
        h, w = block.shape[:2]
        with self.lock:  # GDAL datasets are not thread-safe; da.store calls from its threads
            if self.closed:  # the write was abandoned (an error, a signal): drop the block
                raise SciVizGBufError(f"{self.part.shown}: write abandoned")
            with gdal_writing(self.part):
                self.dst.write(np.moveaxis(block, 2, 0), window=Window(c0, r0, w, h))
            self.done += 1
            self.bar.step(f"block {self.done}/{self.total}")

    def close(self, *, quiet: bool = False) -> None:
        """Close the file once no thread writes to it; ``quiet``: while another exception is
        on its way up (the file is discarded), ignore GDAL's errors of the close."""
        with self.lock:
            if self.closed:
                return
            self.closed = True
            try:
                with gdal_writing(self.part):
                    self.dst.close()
            except SciVizGBufError:
                if not quiet:
                    raise


def _compute_into(image, writer: _WindowWriter, client: Any) -> None:
    """Compute every block of ``image`` and write it, on the scheduler ``client`` says."""
    from dask.base import get_scheduler

    if client is None:
        scheduler = get_scheduler(collections=[image])
        owner = getattr(scheduler, "__self__", None)  # Client.get of an active client
        if owner is not None and type(owner).__name__ == "Client":
            _compute_distributed(image, writer, owner)
        elif getattr(scheduler, "__module__", "") in ("dask.threaded", "dask.local"):
            import dask.array as da

            # The writer shares this process: dask writes each block as soon as it exists.
            da.store(image, writer, lock=False, scheduler=scheduler)
        else:
            _compute_batches(image, writer, scheduler)
        return
    with _client(client) as c:
        _compute_distributed(image, writer, c)


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


def _block_slices(image) -> Iterator[tuple[tuple[int, int], tuple[slice, slice]]]:
    """Block index and (rows, cols) slices of every block, row-major."""
    r_edges, c_edges = (np.cumsum((0, *c)) for c in image.chunks[:2])
    for i in range(len(r_edges) - 1):
        for j in range(len(c_edges) - 1):
            yield (i, j), (slice(r_edges[i], r_edges[i + 1]), slice(c_edges[j], c_edges[j + 1]))


def _compute_distributed(image, writer: _WindowWriter, client: Any) -> None:
    """Blocks computed on the cluster and gathered one by one as they finish, each written
    and released at once.

    All blocks go to the scheduler as one graph: a map block needs its neighbours' input
    chunks (the halo), and only within one graph is each input chunk read (or generated) once
    and dropped when its last block is done (separate submissions read it up to nine times).
    Memory stays bounded on the workers by dask's queuing of root tasks (inputs are produced
    as fast as blocks finish) and in this process because writing a block takes far less
    time than computing one.
    """
    from distributed import KilledWorker, as_completed

    check_worker_memory(client, _block_shape(image))
    items = list(_block_slices(image))
    futures = client.compute([image.blocks[i, j] for (i, j), _ in items])
    where = {f.key: slices for f, (_, slices) in zip(futures, items, strict=True)}
    queue = as_completed(futures)
    del futures  # the queue holds them; each is released once its block is written
    try:
        for future in queue:
            block = future.result()
            writer[where.pop(future.key)] = block
            future.release()
            del block
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


def _compute_batches(image, writer: _WindowWriter, scheduler: Any) -> None:
    """Other local schedulers (processes): bounded batches of blocks, written in turn."""
    import dask

    batch = 2 * (os.cpu_count() or 1)
    items = list(_block_slices(image))
    for k in range(0, len(items), batch):
        part = items[k : k + batch]
        blocks = dask.compute(*(image.blocks[i, j] for (i, j), _ in part), scheduler=scheduler)
        for (_, slices), block in zip(part, blocks, strict=True):
            writer[slices] = block


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
