"""``sciviz-gbuf topo | birdseye``: plan-view topographic maps (in memory or out of core) and
bird's-eye maps of DEMs."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from .._progress import progress
from ..apps.warmup import start as start_warmup
from ..apps.warmup import stop as stop_warmup
from ..compose import write_geotiff, write_png
from ..errors import InputError
from ..readers import read_dem
from ..recipes.labels import contour_labels, label_options, labels_to_geojson
from ..recipes.layout import PAGES, write_map_page
from ..recipes.terrain import RELIEFS, topographic_map
from ..recipes.tiles import write_map_tiles
from ..writers.cog import (
    check_chunk_memory,
    check_worker_memory,
    killed_worker_error,
    local_client,
    write_cog,
)
from ..writers.geojson import write_geojson
from ._args import (
    VECTOR_SUFFIXES,
    add_progress,
    number,
    png_output,
    positive_int,
    show_progress,
)

__all__ = ["add_birdseye", "add_topo"]


def _contours(text: str) -> tuple[float, float] | str | None:
    """``MINOR,MAJOR``, ``MAJOR`` alone (minors at a fifth), ``none`` or ``auto``."""
    t = text.strip().lower()
    if t in ("none", "auto"):
        return t
    try:
        vals = [float(v) for v in t.split(",")]
    except ValueError:
        vals = []
    if not (1 <= len(vals) <= 2 and all(math.isfinite(v) and v > 0 for v in vals)):
        raise argparse.ArgumentTypeError(
            f"expected MINOR,MAJOR intervals such as 20,100 (or one major interval, 'auto', "
            f"'none'), got {text!r}"
        )
    if len(vals) == 1:
        return vals[0] / 5.0, vals[0]
    if vals[1] < vals[0]:
        raise argparse.ArgumentTypeError(f"expected MINOR <= MAJOR, got {text!r}")
    return vals[0], vals[1]


def _bands(text: str):
    """``auto`` (one per major interval), ``none``, ``continuous``, an interval or ``L1,L2,...``."""
    t = text.strip().lower()
    if t in ("auto", "none", "continuous"):
        return {"auto": True, "none": False}.get(t, t)
    try:
        vals = [float(v) for v in t.split(",")]
    except ValueError:
        vals = []
    if not vals or not all(math.isfinite(v) for v in vals) or (len(vals) == 1 and vals[0] <= 0):
        raise argparse.ArgumentTypeError(
            f"expected auto, none, continuous, an interval > 0 or levels L1,L2,..., got {text!r}"
        )
    return vals[0] if len(vals) == 1 else vals


def _map_size(text: str) -> int | tuple[int, int]:
    """``--size``: ``N`` (the long side) or ``WxH`` in pixels, one of them 0 to keep the
    aspect (``2048x0``)."""
    try:
        vals = [int(v) for v in text.lower().split("x")]
    except ValueError:
        vals = []
    if len(vals) not in (1, 2) or min(vals) < 0 or max(vals) < 1:
        raise argparse.ArgumentTypeError(
            f"expected a long side N or WIDTHxHEIGHT in pixels such as 2048 or 2048x1536 "
            f"(0 keeps the aspect: 2048x0), got {text!r}"
        )
    return vals[0] if len(vals) == 1 else (vals[0], vals[1])


def _scale_arg(text: str) -> float | str:
    """``--scale``: pixels per DEM cell (a number > 0), or a map scale ``1:N`` (with --dpi)."""
    t = text.strip()
    if ":" in t:
        head, _, tail = t.partition(":")
        try:
            ok = head.strip() == "1" and math.isfinite(float(tail)) and float(tail) >= 1
        except ValueError:
            ok = False
        if ok:
            return f"1:{float(tail):g}"
    else:
        try:
            v = float(t)
        except ValueError:
            v = float("nan")
        if math.isfinite(v) and v > 0:
            return v
    raise argparse.ArgumentTypeError(
        f"expected pixels per DEM cell (a number > 0, e.g. 4) or a map scale 1:N (e.g. 1:25000, "
        f"with --dpi), got {text!r}"
    )


def _add_size_options(p: argparse.ArgumentParser, *, plan_view: bool) -> None:
    """``--size``, ``--scale`` and ``--dpi`` of the map commands."""
    if plan_view:
        p.add_argument(
            "--size",
            type=_map_size,
            default=None,
            metavar="N|WxH",
            help="output size in pixels: the long side N (aspect kept, like gdal_translate "
            "-outsize N 0) or WxH over the DEM's extent (0 keeps the aspect); default one "
            "pixel per DEM cell. Larger maps resample the heights smoothly (cubic) first, "
            "smaller ones average them",
        )
        p.add_argument(
            "--scale",
            type=_scale_arg,
            default=None,
            metavar="S|1:N",
            help="instead of --size: S output pixels per DEM cell (e.g. 4), or with --dpi the map "
            "scale 1:N (e.g. --scale 1:25000 --dpi 300: 25000 x 0.0254 / 300 = 2.12 m per pixel)",
        )
        p.add_argument(
            "--dpi",
            type=number(lambda v: v > 0, "dots per inch > 0"),
            default=None,
            help="print resolution: sizes a map scale (--scale 1:N) and is recorded in a PNG "
            "output (pHYs)",
        )
        return
    p.add_argument(
        "--size",
        type=_map_size,
        default=None,
        metavar="N|WxH",
        help="image size WxH, or the long side N (4:3); default 1024x768",
    )
    p.add_argument(
        "--scale",
        type=_scale_arg,
        default=None,
        metavar="S",
        help="instead of --size: about S pixels per DEM cell across the terrain (the long "
        "side is S times the DEM's long side in cells, 4:3)",
    )
    p.add_argument(
        "--dpi",
        type=number(lambda v: v > 0, "dots per inch > 0"),
        default=None,
        help="print resolution recorded in the PNG (pHYs); the pixels do not depend on it",
    )


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


def _chunks_arg(text: str) -> tuple[int, int]:
    """``--chunks``: ``N`` (square) or ``ROWS,COLS`` positive integers."""
    try:
        vals = [int(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) not in (1, 2) or min(vals) < 1:
        raise argparse.ArgumentTypeError(
            f"expected a chunk size N or ROWS,COLS of positive integers such as 2048, got {text!r}"
        )
    return (vals[0], vals[0]) if len(vals) == 1 else (vals[0], vals[1])


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


def _cmd_topo(args: argparse.Namespace) -> int:
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
        dem = _read_terrain(source, args.geographic)
        bar.step("map")
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
            write_geotiff(args.geotiff, rgba, dem=dem)
            bar.step("geotiff")
        if args.labels_geojson is not None:
            opts = _topo_options(args, False)
            keys = ("interval", "major_interval", "size", "scale", "dpi", "label_size",
                    "label_spacing")  # fmt: skip
            placed = contour_labels(dem, **{k: opts[k] for k in keys if k in opts})
            write_geojson(args.labels_geojson, labels_to_geojson(placed, crs=dem.crs))
    h, w = rgba.shape[:2]
    extra = "".join(f" and {f}" for f in (args.geotiff, args.overview, args.labels_geojson) if f)
    print(f"wrote {out}{extra} ({w}x{h}) in {time.perf_counter() - t0:.1f} s")
    return 0


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
            opts = _topo_options(args, False)
            keys = ("interval", "major_interval", "size", "scale", "dpi", "label_size",
                    "label_spacing")  # fmt: skip
            placed = contour_labels(dem, **{k: opts[k] for k in keys if k in opts})
            write_geojson(args.labels_geojson, labels_to_geojson(placed, crs=dem.crs))
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


def _zoom_arg(text: str) -> tuple[int, int]:
    parts = text.replace(" ", "").split("-")
    try:
        vals = [int(v) for v in parts]
    except ValueError:
        vals = []
    if len(vals) not in (1, 2) or not 0 <= vals[0] <= vals[-1] <= 24:
        raise argparse.ArgumentTypeError(
            f"expected a zoom level or a range MIN-MAX within 0-24 such as 8-14, got {text!r}"
        )
    return vals[0], vals[-1]


def _topo_tiles(args: argparse.Namespace, source, t0: float) -> int:
    """``--tiles FOLDER``: the map of every zoom level cut into an XYZ tile pyramid with a
    Leaflet viewer (index.html)."""
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
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
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
    print(
        f"wrote {out}/ ({pyramid.count} tiles, zoom {z0}-{z1}: {per}; viewer "
        f"{out / 'index.html'}) in {time.perf_counter() - t0:.1f} s"
    )
    return 0


def _cmd_birdseye(args: argparse.Namespace) -> int:
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


def _add_z_factor(p: argparse.ArgumentParser, what: str, ground: str) -> None:
    """``--z-factor``: a number > 0, default automatic (the maps' rule on ``ground``)."""
    p.add_argument(
        "--z-factor",
        type=number(lambda v: v > 0, "a number > 0"),
        default=None,
        help=f"{what}; default: automatic, 1 on {ground} steeper than 10 degrees, up to 20 on "
        "low-relief ground)",
    )


def _add_map_style(p: argparse.ArgumentParser, *, tiles: bool = False) -> None:
    """Options shared by the plan-view and bird's-eye maps; ``tiles``: several DEM files (one
    mosaic) and a .png or .tif output."""
    grid = p.add_mutually_exclusive_group()
    grid.add_argument(
        "--geographic",
        dest="geographic",
        action="store_const",
        const=True,
        default=None,
        help="the grid's coordinates are longitude/latitude degrees (default: from its CRS, "
        "or, without one, by whether its cells look like degrees)",
    )
    grid.add_argument(
        "--projected",
        dest="geographic",
        action="store_const",
        const=False,
        help="the grid's coordinates are metres (or the CRS's unit), not degrees",
    )
    p.add_argument(
        "dem",
        nargs="*" if tiles else "?",
        help="DEM file: GeoTIFF, .asc, .hgt, USGS .dem, .npy/.npz (default: the bundled "
        "Jacksboro fault DEM from Matplotlib's sample data)"
        + (
            "; several files (e.g. SRTM tiles of one CRS and resolution) make one mosaic"
            if tiles
            else ""
        ),
    )
    p.add_argument(
        "-o",
        "--output",
        required=not tiles,
        default=None,
        help="output image (.png, .tif for a Cloud-Optimised GeoTIFF, or .svg/.pdf: vector "
        "contours and labels over the map image)"
        if tiles
        else "output image (.png)",
    )
    p.add_argument(
        "--contours",
        type=_contours,
        default="auto",
        metavar="MINOR,MAJOR",
        help="contour intervals in height units, e.g. 20,100; one number is the major interval "
        "(minors at a fifth); 'none' draws none (default: about 8 round majors)",
    )
    p.add_argument(
        "--exact-contours",
        action="store_true",
        help="draw the exact contour lines of the heights (those of gdal_contour) instead of "
        "the generalised ones (smoothed within 0.6 px on gentle ground, small rings dropped)",
    )
    p.add_argument(
        "--bands",
        type=_bands,
        default=True,
        metavar="SPEC",
        help="colour bands: auto (one per major interval), none, continuous, an interval, or "
        "band edges L1,L2,...",
    )
    p.add_argument("--cmap", default=None, help="matplotlib colour map of the bands")
    p.add_argument(
        "--sea-level",
        type=number(lambda v: True, "a height"),
        default=None,
        help="topo-bathymetry: heights below it get sea colours",
    )
    p.add_argument(
        "--azimuth",
        type=number(lambda v: True, "degrees"),
        default=315.0,
        help="sun direction, degrees clockwise from north (default 315)",
    )
    p.add_argument(
        "--altitude",
        type=number(lambda v: 0 < v <= 90, "degrees in (0, 90]"),
        default=45.0,
        help="sun altitude above the horizon in degrees (default 45)",
    )


def add_topo(sub) -> None:
    """Add the ``topo`` command to the sub-parsers ``sub``."""
    p = sub.add_parser(
        "topo",
        help="plan-view topographic map of a DEM: bands, relief, contours (PNG, GeoTIFF)",
        description="Colour bands, GDAL-compatible relief and major/minor contour lines of a "
        "DEM on its own grid (Saito & Takahashi 1990, Fig. 11). Nodata is transparent. "
        "With --chunks or --dask the DEM is read, mapped and written chunk by chunk (out of "
        "core, any size): the output must be a .tif (a Cloud-Optimised GeoTIFF).",
    )
    _add_map_style(p, tiles=True)
    p.add_argument(
        "--geotiff",
        default=None,
        metavar="FILE.tif",
        help="also write an RGBA GeoTIFF with the DEM's CRS and transform (its pixel size "
        "that of the map: --size/--scale)",
    )
    _add_size_options(p, plan_view=True)
    p.add_argument(
        "--width",
        type=number(lambda v: v > 0, "a line width in pixels > 0"),
        default=1.0,
        help="minor contour width in pixels (default 1)",
    )
    p.add_argument(
        "--major-width",
        type=number(lambda v: v > 0, "a line width in pixels > 0"),
        default=2.0,
        help="major contour width in pixels (default 2)",
    )
    _add_z_factor(p, "vertical exaggeration of the relief (GDAL's -z", "ground")
    p.add_argument(
        "--variant",
        default="regular",
        choices=["regular", "combined", "multidirectional", "igor"],
        help="hillshade variant (GDAL's)",
    )
    shade = p.add_mutually_exclusive_group()
    shade.add_argument(
        "--relief",
        default="hillshade",
        choices=[name.replace("_", "-") for name in RELIEFS],
        help="relief style: hillshade (GDAL's, the default); vat (RVT's blend of hillshade, "
        "slope, openness and sky view); openness; texture (Brown's texture shading); "
        "local-relief (the simple local relief model)",
    )
    shade.add_argument("--no-relief", action="store_true", help="no relief shading")
    p.add_argument("--shadows", action="store_true", help="darken cast shadows")
    p.add_argument(
        "--sky-view", action="store_true", help="darken cells that see less sky (~15 MPix/s)"
    )
    p.add_argument(
        "--labels",
        action="store_true",
        help="write the heights of the index contours into the lines (reading uphill, the "
        "line broken under the number)",
    )
    p.add_argument(
        "--label-size",
        type=number(lambda v: v > 0, "a font size in pixels > 0"),
        default=None,
        metavar="PX",
        help="label font size in output pixels (default 11; 7 pt with --scale 1:N --dpi)",
    )
    p.add_argument(
        "--label-spacing",
        type=number(lambda v: v > 0, "a distance in pixels > 0"),
        default=None,
        metavar="PX",
        help="least distance between labels along a line, pixels (default 25 font sizes)",
    )
    p.add_argument(
        "--labels-geojson",
        default=None,
        metavar="FILE.geojson",
        help="with --labels: also write the labels as GeoJSON points (text, level, rotation) "
        "in the DEM's CRS, for a GIS",
    )
    p.add_argument(
        "--page",
        choices=sorted(PAGES),
        default=None,
        help="a print layout: the map at a round scale (or --scale 1:N) on this page with a "
        "legend, scale bar, north arrow, title and credit; -o .png or .pdf; --dpi default 300",
    )
    p.add_argument("--landscape", action="store_true", help="with --page: landscape")
    p.add_argument("--title", default=None, help="with --page: the title above the map")
    p.add_argument("--credit", default=None, help="with --page: a credit line (data sources)")
    p.add_argument(
        "--graticule",
        choices=["ticks", "grid"],
        default=None,
        help="with --page: the CRS's coordinates on the frame (ticks), or ticks and grid lines",
    )
    p.add_argument(
        "--furniture",
        choices=["outside", "inside"],
        default="outside",
        help="with --page: legend, scale bar and north arrow below the map (default) or on a "
        "panel inside its frame",
    )
    p.add_argument(
        "--chunks",
        type=_chunks_arg,
        default=None,
        metavar="N|ROWS,COLS",
        help="out of core: read, map and write the DEM in chunks of this many cells "
        "(e.g. 2048; default 2048 with --dask); needs a .tif output",
    )
    p.add_argument(
        "--dask",
        nargs="?",
        const="local",
        default=None,
        metavar="ADDRESS",
        help="out of core on dask.distributed: a new local cluster (no ADDRESS), or the "
        "scheduler at ADDRESS (tcp://host:8786)",
    )
    p.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        help="worker processes of the local --dask cluster (default 2; each gets "
        "NUMBA_NUM_THREADS = cores // workers)",
    )
    p.add_argument(
        "--memory-limit",
        default=None,
        metavar="SIZE",
        help="memory limit per worker of the local --dask cluster (default 3GB)",
    )
    p.add_argument(
        "--overview",
        default=None,
        metavar="FILE.png",
        help="with a .tif output: also a PNG preview read from its overviews",
    )
    p.add_argument(
        "--overview-size",
        type=positive_int,
        default=2048,
        metavar="PX",
        help="long side of the --overview PNG in pixels (default 2048)",
    )
    tiles = p.add_argument_group("web map tiles")
    tiles.add_argument(
        "--tiles",
        default=None,
        metavar="FOLDER",
        help="write the map as an XYZ web-map tile pyramid (Web Mercator, FOLDER/z/x/y.png) "
        "with a viewer, FOLDER/index.html (Leaflet, bundled); instead of -o",
    )
    tiles.add_argument(
        "--zoom",
        type=_zoom_arg,
        default=None,
        metavar="MIN-MAX",
        help="zoom levels of --tiles, e.g. 8-14 (default: the DEM's native zoom, whose pixels "
        "are no larger than its cells, and the four below)",
    )
    tiles.add_argument(
        "--tile-size", type=int, choices=[256, 512], default=None, help="tile side in pixels"
    )
    tiles.add_argument(
        "--tile-format",
        choices=["png", "webp"],
        default=None,
        help="png (default) or lossless webp",
    )
    add_progress(p)
    p.set_defaults(func=_cmd_topo)


def add_birdseye(sub) -> None:
    """Add the ``birdseye`` command to the sub-parsers ``sub``."""
    p = sub.add_parser(
        "birdseye",
        help="bird's-eye map of a DEM: profiles, contours, relief, bands (or a sumi-e)",
        description="Render the DEM surface once, then enhance its G-buffers: contour lines of "
        "the height, relief from the normals, profile lines from sz and colour bands "
        "(Saito & Takahashi 1990, Figs. 12 and 13).",
    )
    _add_map_style(p)
    p.add_argument(
        "--elevation-angle",
        type=number(lambda v: 0 < v < 90, "degrees in (0, 90)"),
        default=35.0,
        help="angle of the line of sight above the horizon (default 35)",
    )
    p.add_argument(
        "--view-azimuth",
        type=number(lambda v: True, "degrees"),
        default=135.0,
        help="compass direction of the eye from the terrain (default 135, south-east)",
    )
    p.add_argument(
        "--vert-exag",
        type=number(lambda v: v > 0, "a number > 0"),
        default=1.0,
        help="vertical exaggeration of the surface (default 1)",
    )
    _add_z_factor(p, "exaggeration of the relief shade only (the geometry's is --vert-exag",
                  "rendered ground")  # fmt: skip
    _add_size_options(p, plan_view=False)
    p.add_argument("--supersample", type=positive_int, default=2, help="render at k times the size")
    p.add_argument(
        "--style",
        default="mx4",
        choices=["mx4", "mx2", "cn", "pr", "sh", "sumi-e"],
        help="mx4: profiles + contours + relief + bands (default); mx2: profiles + relief; "
        "cn contours; pr profiles; sh relief; sumi-e an ink painting",
    )
    p.add_argument(
        "--labels",
        action="store_true",
        help="with --style mx4 or cn: write the heights of the index contours into the lines "
        "(along the line as seen, reading uphill, the line broken under the number)",
    )
    p.add_argument(
        "--label-size",
        type=number(lambda v: v > 0, "a font size in pixels > 0"),
        default=None,
        metavar="PX",
        help="label font size in output pixels (default 11)",
    )
    p.add_argument(
        "--label-spacing",
        type=number(lambda v: v > 0, "a distance in pixels > 0"),
        default=None,
        metavar="PX",
        help="least distance between labels along a line, pixels (default 25 font sizes)",
    )
    p.add_argument(
        "--save-gbuffer", default=None, metavar="FILE.npz", help="also save the G-buffers"
    )
    add_progress(p)
    p.set_defaults(func=_cmd_birdseye)
