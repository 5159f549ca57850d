"""The work of ``sciviz-gbuf topo | birdseye`` (:mod:`.terrain` holds their parsers): reading
the DEM, mapping it in memory, out of core or into web tiles, and writing the outputs. A module
of its own so that building the parsers (``topo --help``) imports none of it: the filters,
numba, rasterio and dask load when a command runs."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .._progress import progress
from ..apps.warmup import preload_map
from ..apps.warmup import start as start_warmup
from ..apps.warmup import stop as stop_warmup
from ..compose import write_png
from ..errors import InputError
from ..readers import read_dem
from ..recipes.labels import contour_labels, label_options, labels_to_geojson
from ..recipes.layout import write_map_page
from ..recipes.terrain import topographic_map, write_topographic_cog, write_topographic_png
from ..recipes.tiles import write_map_tiles
from ..writers.cog import (
    check_chunk_memory,
    check_worker_memory,
    killed_worker_error,
    local_client,
    write_cog,
)
from ..writers.geojson import write_geojson
from ._args import VECTOR_SUFFIXES, png_output, show_progress

__all__ = ["cmd_birdseye", "cmd_topo"]


def _size_options(args: argparse.Namespace) -> dict:
    """The map's ``size``/``scale``/``dpi``: ``dpi`` sizes the map only with a scale (else it
    is only recorded in a PNG)."""
    opts = {"size": args.size, "scale": args.scale}
    if args.scale is not None and args.dpi is not None:
        opts["dpi"] = args.dpi
    return opts


def _read_terrain(source, geographic: bool | None = None):
    if source is None:
        # the bundled data's module loads PyVista (for its meshes): only when it is asked for
        from ..datasets import load_jacksboro_dem

        return load_jacksboro_dem()
    return read_dem(source, geographic=geographic)


def _contour_options(spec) -> dict:
    if spec == "none":
        return {"contours": False}
    if spec == "auto":
        return {}
    return {"interval": spec[0], "major_interval": spec[1]}


def _topo_options(args: argparse.Namespace, show: bool) -> dict:
    return {
        **_contour_options(args.contours),
        "generalize": not args.exact_contours,
        "width": args.width,
        "major_width": args.major_width,
        "bands": args.bands,
        "cmap": args.cmap,
        "sea_level": args.sea_level,
        "relief": False if args.no_relief else args.relief,
        "azimuth": args.azimuth,
        "altitude": args.altitude,
        "z_factor": args.z_factor,
        "variant": args.variant,
        "shadows": args.shadows,
        "sky_view": args.sky_view,
        **_label_options(args),
        **_size_options(args),
        "progress_bar": show,
    }


def _label_options(args: argparse.Namespace) -> dict:
    if not args.labels:
        return {}
    return {"labels": True, "label_size": args.label_size, "label_spacing": args.label_spacing}


def _topo_paths(args: argparse.Namespace) -> tuple[Path, bool]:
    """Checked ``--output`` (and ``--geotiff``, ``--overview``, cluster options); True for a
    .tif output."""
    out = Path(args.output)
    suffix = out.suffix.lower()
    lazy = args.chunks is not None or args.dask is not None
    if args.page is not None:
        _check_page(args, out, lazy)
        return out, False
    if (args.landscape or args.title is not None or args.credit is not None
            or args.graticule is not None or args.furniture != "outside"):  # fmt: skip
        raise InputError(
            "--landscape/--title/--credit/--graticule/--furniture: these lay out a page: add "
            "--page A4"
        )
    if suffix not in (".png", ".tif", ".tiff", *VECTOR_SUFFIXES):
        raise InputError(
            f"--output: expected a file name ending in .png, .tif, .svg or .pdf, got "
            f"{args.output!r}"
        )
    if not out.parent.is_dir():
        raise InputError(f"--output: no such directory {str(out.parent)!r}")
    if suffix in VECTOR_SUFFIXES:
        if lazy:
            raise InputError(
                f"--output: a vector map ({suffix}) is drawn in memory; out of core "
                "(--chunks/--dask) the map is a Cloud-Optimised GeoTIFF (.tif)"
            )
        for flag, value in (("--geotiff", args.geotiff), ("--overview", args.overview)):
            if value is not None:
                raise InputError(
                    f"{flag}: a raster copy of the map comes with a .png/.tif --output, not "
                    f"{suffix}"
                )
    tif = suffix in (".tif", ".tiff")
    if lazy and (args.size is not None or args.scale is not None):
        raise InputError(
            f"{'--size' if args.size is not None else '--scale'}: out of core (--chunks/--dask) "
            "a map is drawn one pixel per DEM cell; resample the DEM first (gdalwarp -ts/-tr) "
            "or map it in memory"
        )
    if lazy and not tif:
        raise InputError(
            f"--output: out of core (--chunks/--dask) the map is written as a Cloud-Optimised "
            f"GeoTIFF: expected a .tif file, got {args.output!r} (add --overview FILE.png for "
            "a PNG preview)"
        )
    if args.overview is not None and not tif:
        raise InputError("--overview: a PNG preview comes from a .tif output: use -o FILE.tif")
    if args.geotiff is not None:
        if tif:
            raise InputError("--geotiff: the output is already a GeoTIFF: use -o FILE.tif alone")
        g = Path(args.geotiff)
        if g.suffix.lower() not in (".tif", ".tiff") or not g.parent.is_dir():
            raise InputError(
                f"--geotiff: expected a .tif/.tiff file in an existing folder, got {args.geotiff!r}"
            )
    if args.labels_geojson is not None:
        if not args.labels:
            raise InputError("--labels-geojson: the labels' positions come with --labels")
        g = Path(args.labels_geojson)
        if g.suffix.lower() not in (".geojson", ".json") or not g.parent.is_dir():
            raise InputError(
                "--labels-geojson: expected a .geojson/.json file in an existing folder, got "
                f"{args.labels_geojson!r}"
            )
    if args.labels and lazy:
        raise InputError(
            "--labels: contour labels are placed on a DEM in memory; out of core "
            "(--chunks/--dask) maps have none"
        )
    cluster_options = args.workers is not None or args.memory_limit is not None
    if cluster_options and args.dask != "local":
        raise InputError(
            "--workers/--memory-limit: only for a new local cluster (--dask without an address)"
        )
    return out, tif


def _check_page(args: argparse.Namespace, out: Path, lazy: bool) -> None:
    """``--page``: a .png or .pdf in an existing folder, in memory, sized by its scale."""
    if out.suffix.lower() not in (".png", ".pdf"):
        raise InputError(f"--output: a page is written as .png or .pdf, got {args.output!r}")
    if not out.parent.is_dir():
        raise InputError(f"--output: no such directory {str(out.parent)!r}")
    if lazy:
        raise InputError("--page: a page layout is drawn in memory (not with --chunks/--dask)")
    if args.size is not None:
        raise InputError("--size: a page's map is sized by its scale (--scale 1:N) and --dpi")
    if args.scale is not None and not str(args.scale).startswith("1:"):
        raise InputError(f"--scale: a page needs a map scale 1:N, got {args.scale!r}")
    for flag, value in (("--geotiff", args.geotiff), ("--overview", args.overview),
                        ("--labels-geojson", args.labels_geojson)):  # fmt: skip
        if value is not None:
            raise InputError(f"{flag}: not with --page (write the map without --page)")


def _topo_page(args: argparse.Namespace, source, out: Path, show: bool, t0: float) -> int:
    opts = _topo_options(args, show)
    for key in ("size", "scale", "dpi", "progress_bar", "labels", "label_size",
                "label_spacing"):  # fmt: skip
        opts.pop(key, None)
    with progress(show, 2, "topo page") as bar:
        dem = _read_terrain(source, args.geographic)
        bar.step("page")
        w, h = write_map_page(
            out, dem, page=args.page, landscape=args.landscape, dpi=args.dpi or 300.0,
            scale=args.scale, title=args.title, credit=args.credit, labels=args.labels,
            graticule=args.graticule or False, furniture=args.furniture, **opts,
        )  # fmt: skip
    print(f"wrote {out} ({args.page}, {w}x{h} px) in {time.perf_counter() - t0:.1f} s")
    return 0


def cmd_topo(args: argparse.Namespace) -> int:
    source = None if not args.dem else args.dem[0] if len(args.dem) == 1 else list(args.dem)
    if args.tiles is not None:
        return _topo_tiles(args, source, time.perf_counter())
    if args.output is None:
        raise InputError("--output: expected a map file (-o map.png) or --tiles FOLDER")
    for flag, value in (("--zoom", args.zoom), ("--tile-size", args.tile_size),
                        ("--tile-format", args.tile_format)):  # fmt: skip
        if value is not None:
            raise InputError(f"{flag}: comes with --tiles FOLDER")
    out, tif = _topo_paths(args)
    t0 = time.perf_counter()
    show = show_progress(args)
    if args.chunks is not None or args.dask is not None:
        return _topo_out_of_core(args, source, out, show, t0)
    # A first run compiles the map's kernels: the ones it needs last compile on the other core.
    second = start_warmup(["sciviz_gbuf.apps.warmup", "topo"], job="topo")
    try:
        if args.page is not None:
            return _topo_page(args, source, out, show, t0)
        if out.suffix.lower() in VECTOR_SUFFIXES:
            return _topo_vector(args, source, out, show, t0)
        return _topo_in_memory(args, source, out, tif, show, t0)
    finally:
        stop_warmup(second)


def _topo_in_memory(
    args: argparse.Namespace, source, out: Path, tif: bool, show: bool, t0: float
) -> int:
    with progress(show, 2 + (args.geotiff is not None), "topo") as bar:
        # the map's kernels load on another thread while the DEM is read
        opts = _topo_options(args, False)
        kernels = {k: opts[k] for k in ("generalize", "relief", "variant", "sky_view")}
        loader = preload_map(**kernels)
        dem = _read_terrain(source, args.geographic)
        loader.join()
        bar.step("map")
        if not args.labels:
            # mapped and written block by block (the same pixels, mapping and deflating at once;
            # a COG's tiles deflated with each block)
            opts = _topo_options(args, show)
            for key in ("progress_bar", "dpi"):
                opts.pop(key, None)
            if tif:
                h, w = write_topographic_cog(out, dem, **opts, dpi=args.dpi,
                                             overview_png=args.overview,
                                             overview_size=args.overview_size)  # fmt: skip
            else:
                h, w = write_topographic_png(out, dem, **opts, dpi=args.dpi,
                                             geotiff=args.geotiff)  # fmt: skip
            bar.step("write")
            if args.geotiff is not None:
                bar.step("geotiff")
            if args.labels_geojson is not None:
                _write_labels_geojson(args, dem)
            print(f"wrote {out}{_also(args)} ({w}x{h}) in {time.perf_counter() - t0:.1f} s")
            return 0
        rgba = topographic_map(dem, **_topo_options(args, show))
        bar.step("write")
        if tif:
            write_cog(
                rgba, out, dem=dem, overview_png=args.overview, overview_size=args.overview_size
            )
        else:
            write_png(out, rgba, dpi=args.dpi)
        if args.geotiff is not None:
            # an image of another size than the DEM covers its extent: the transform follows
            write_cog(rgba, args.geotiff, dem=dem)
            bar.step("geotiff")
        if args.labels_geojson is not None:
            _write_labels_geojson(args, dem)
    h, w = rgba.shape[:2]
    print(f"wrote {out}{_also(args)} ({w}x{h}) in {time.perf_counter() - t0:.1f} s")
    return 0


def _also(args: argparse.Namespace) -> str:
    """`` and F`` for each other file a topo run wrote."""
    return "".join(f" and {f}" for f in (args.geotiff, args.overview, args.labels_geojson) if f)


def _write_labels_geojson(args: argparse.Namespace, dem) -> None:
    """``--labels-geojson``: the map's label placements as GeoJSON points."""
    opts = _topo_options(args, False)
    keys = ("interval", "major_interval", "size", "scale", "dpi", "label_size", "label_spacing")
    placed = contour_labels(dem, **{k: opts[k] for k in keys if k in opts})
    write_geojson(args.labels_geojson, labels_to_geojson(placed, crs=dem.crs))


def _topo_vector(args: argparse.Namespace, source, out: Path, show: bool, t0: float) -> int:
    """``-o map.svg|map.pdf``: the map's colour and relief as an image, its contour lines as
    strokes with their levels and its labels as text."""
    # the vector writers load the illustration styles: only for an SVG or PDF map
    from ..recipes.vector import topographic_picture, write_vector

    with progress(show, 2, "topo") as bar:
        dem = _read_terrain(source, args.geographic)
        bar.step("map")
        picture = topographic_picture(dem, **_topo_options(args, show))
        bar.step("write")
        write_vector(out, picture, title=Path(args.dem[0]).name if args.dem else "Jacksboro")
        if args.labels_geojson is not None:
            _write_labels_geojson(args, dem)
    w, h = picture.size
    extra = f" and {args.labels_geojson}" if args.labels_geojson else ""
    print(
        f"wrote {out}{extra} ({w}x{h}, {len(picture.strokes)} contour strokes, "
        f"{len(picture.texts)} labels) in {time.perf_counter() - t0:.1f} s"
    )
    return 0


def _dask_client(args: argparse.Namespace, block: tuple[int, ...]):
    """The dask.distributed client of ``--dask`` (a new local cluster, or the scheduler at
    its address; None without ``--dask``), the memory limit checked against a chunk of
    ``block`` cells before any worker starts."""
    if args.dask == "local":
        from dask.utils import parse_bytes

        limit = args.memory_limit or "3GB"
        try:
            limit_bytes = parse_bytes(limit)
        except (ValueError, TypeError):
            raise InputError(
                f"--memory-limit: expected a size such as 3GB, got {limit!r}"
            ) from None
        check_chunk_memory(block, limit_bytes)
        return local_client(args.workers or 2, memory_limit=limit)
    if args.dask is not None:
        from distributed import Client

        try:
            return Client(args.dask, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(
                f"--dask: cannot connect to a dask scheduler at {args.dask!r} ({exc})"
            ) from exc
    return None


def _close_client(args: argparse.Namespace, client) -> None:
    """Close the client of :func:`_dask_client`, and its cluster if ``--dask`` made one."""
    if client is not None:
        cluster = client.cluster if args.dask == "local" else None
        client.close()
        if cluster is not None:
            cluster.close()


def _topo_out_of_core(args: argparse.Namespace, source, out: Path, show: bool, t0: float) -> int:
    """``--chunks``/``--dask``: lazy DEM -> lazy map -> COG written block by block."""
    if source is None:
        raise InputError("dem: out of core (--chunks/--dask) needs DEM file(s) to read")
    # Read (metadata only) before a cluster starts: a bad file fails fast.
    dem = read_dem(source, chunks=args.chunks or 2048, geographic=args.geographic)
    block = tuple(int(v) for v in dem.heights.chunksize)
    client = _dask_client(args, block)
    try:
        if client is not None:
            check_worker_memory(client, block)
        # While open, the Client is dask's default scheduler: the map's whole-grid reductions
        # (colour range, contour interval) run on the cluster too.
        rgba = topographic_map(dem, **_topo_options(args, show))
        write_cog(
            rgba,
            out,
            dem=dem,
            overview_png=args.overview,
            overview_size=args.overview_size,
            client=client,
            progress_bar=show,
        )
    except Exception as exc:
        # dask's KilledWorker (a task that killed its workers): the memory limit, in one line
        if type(exc).__name__ == "KilledWorker":
            raise killed_worker_error(block) from exc
        raise
    finally:
        _close_client(args, client)
    h, w = dem.shape
    where = "local threads" if client is None else f"dask cluster {args.dask}"
    extra = f" and {args.overview}" if args.overview else ""
    print(
        f"wrote {out}{extra} ({w}x{h}, chunks {dem.heights.chunksize}, {where}) "
        f"in {time.perf_counter() - t0:.1f} s"
    )
    return 0


def _topo_tiles(args: argparse.Namespace, source, t0: float) -> int:
    """``--tiles FOLDER``: the map of every zoom level cut into an XYZ tile pyramid with a
    Leaflet viewer (index.html); ``--tiles FILE.pmtiles``: the same tiles in one PMTiles
    archive."""
    if args.output is not None:
        raise InputError("--tiles: the map is written as tiles into the folder: leave out -o")
    refused = (("--page", args.page), ("--geotiff", args.geotiff), ("--overview", args.overview),
               ("--size", args.size), ("--scale", args.scale), ("--dpi", args.dpi),
               ("--labels-geojson", args.labels_geojson), ("--graticule", args.graticule),
               ("--title", args.title), ("--credit", args.credit))  # fmt: skip
    for flag, value in refused:
        if value is not None:
            raise InputError(f"{flag}: not with --tiles (a tile's pixel size is its zoom's)")
    if args.labels and (args.chunks is not None or args.dask is not None):
        raise InputError(
            "--labels: labels are placed on each zoom level's whole map in memory; not with "
            "--chunks/--dask"
        )
    out = Path(args.tiles)
    archive = out.suffix.lower() == ".pmtiles"
    if archive and out.is_dir():
        raise InputError(f"--tiles: {str(out)!r} is a folder; a .pmtiles archive is a file")
    if not archive and out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise InputError(f"--tiles: {str(out)!r} exists and is not an empty folder")
    if not out.parent.is_dir():
        raise InputError(f"--tiles: no such directory {str(out.parent)!r}")
    show = show_progress(args)
    lazy = args.chunks is not None or args.dask is not None
    if lazy and source is None:
        raise InputError("dem: out of core (--chunks/--dask) needs DEM file(s) to read")
    dem = (read_dem(source, chunks=args.chunks or 2048, geographic=args.geographic) if lazy
           else _read_terrain(source, args.geographic))  # fmt: skip
    opts = _topo_options(args, False)
    for key in ("size", "scale", "dpi", "progress_bar"):
        opts.pop(key, None)
    block = tuple(int(v) for v in dem.heights.chunksize) if lazy else dem.shape
    client = _dask_client(args, block)
    try:
        with progress(show, 1, "topo tiles") as bar:
            pyramid = write_map_tiles(
                dem, out, zoom=args.zoom, tile_size=args.tile_size or 256,
                format=args.tile_format or "png", client=client,
                title=Path(args.dem[0]).name if args.dem else "Jacksboro fault DEM", **opts,
            )  # fmt: skip
            bar.step("done")
    finally:
        _close_client(args, client)
    z0, z1 = pyramid.zooms
    per = ", ".join(f"{z}: {n}" for z, n in pyramid.tiles.items())
    where = f"{out}" if archive else f"{out}/"
    viewer = "" if archive else f"; viewer {out / 'index.html'}"
    print(
        f"wrote {where} ({pyramid.count} tiles, zoom {z0}-{z1}: {per}{viewer}) in "
        f"{time.perf_counter() - t0:.1f} s"
    )
    return 0


def cmd_birdseye(args: argparse.Namespace) -> int:
    # VTK and PyVista load with the bird's-eye renderer: not for the plan-view commands
    from ..recipes.birdseye import birdseye_gbuffer, birdseye_panels, sumi_e

    out = png_output(args.output)
    if args.labels and args.style not in ("mx4", "cn"):
        raise InputError(
            f"--labels: the heights are written into the contour lines of --style mx4 or cn, "
            f"not {args.style}"
        )
    if args.labels and args.contours == "none":
        raise InputError("--labels: --contours none draws no contour lines to label")
    if args.labels:
        label_options(args.label_size, args.label_spacing)  # checked before the render
    t0 = time.perf_counter()
    show = show_progress(args)
    dem = _read_terrain(args.dem, args.geographic)
    gb = birdseye_gbuffer(
        dem,
        view_azimuth=args.view_azimuth,
        elevation_angle=args.elevation_angle,
        size=args.size,
        scale=args.scale,
        vert_exag=args.vert_exag,
        supersample=args.supersample,
        progress_bar=show,
    )
    if args.save_gbuffer:
        gb.save(args.save_gbuffer)
    if args.style == "sumi-e":
        opts = {} if args.contours in ("auto", "none") else {"interval": args.contours[0]}
        image = sumi_e(gb, **opts)
    else:
        panels = birdseye_panels(
            gb,
            **_contour_options(args.contours),
            generalize=not args.exact_contours,
            bands=args.bands,
            cmap=args.cmap,
            sea_level=args.sea_level,
            azimuth=args.azimuth,
            altitude=args.altitude,
            z_factor=args.z_factor,
            **_label_options(args),
        )
        image = panels[args.style]
    write_png(out, image, dpi=args.dpi)
    h, w = image.shape[:2]
    print(f"wrote {out} ({w}x{h}, {args.style}) in {time.perf_counter() - t0:.1f} s")
    return 0
