"""``sciviz-gbuf topo | birdseye``: plan-view topographic maps (in memory or out of core) and
bird's-eye maps of DEMs. The parsers; the commands' work is in :mod:`._terrain_run`, imported
when a command runs (so ``topo --help`` loads neither numba nor the filters)."""

from __future__ import annotations

import argparse
import math

from ..recipes.map_options import PAGES, RELIEFS
from ._args import (
    add_progress,
    number,
    positive_int,
)

__all__ = ["add_birdseye", "add_topo"]


def _cmd_topo(args: argparse.Namespace) -> int:
    # the map's modules (filters, numba, rasterio) load only now that the command runs
    from ._terrain_run import cmd_topo

    return cmd_topo(args)


def _cmd_birdseye(args: argparse.Namespace) -> int:
    from ._terrain_run import cmd_birdseye

    return cmd_birdseye(args)


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
        help="also write the map as an RGBA Cloud-Optimised GeoTIFF with the DEM's CRS and "
        "transform (its pixel size that of the map: --size/--scale)",
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
        metavar="FOLDER|FILE.pmtiles",
        help="write the map as an XYZ web-map tile pyramid (Web Mercator, FOLDER/z/x/y.png) "
        "with a viewer, FOLDER/index.html (Leaflet, bundled), or as one PMTiles archive "
        "(a name ending in .pmtiles); instead of -o",
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
