"""``sciviz-gbuf capture | edges | info``: G-buffers of mesh files, edge pictures, saved files."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .._progress import progress
from ..compose import write_png
from ..core.camera import VIEWS
from ..core.capture import capture
from ..core.gbuffer import GBuffer
from ..errors import InputError
from ..readers import read_mesh
from ..recipes.vector import (
    BACKGROUNDS,
    HIDDEN,
    edge_picture,
    technical_drawing,
    technical_drawing_image,
    write_vector,
)
from ..styles import illustrate, styles_for
from ._args import add_up, number, picture_output, positive_int, require_coverage, size

__all__ = ["add_capture", "add_edges", "add_info"]

# Defaults of the edges command (the filters' own defaults).
_EDGE_DEFAULTS = {"crease_angle": 30.0, "depth_jump": 1.0, "width": 1.0}


def _cmd_capture(args: argparse.Namespace) -> int:
    meshes = [read_mesh(p) for p in args.mesh]
    g = capture(
        meshes,
        window_size=args.size,
        camera=args.view,
        parallel_projection=True if args.parallel else None,
        scalars=[s for s in args.scalars.split(",") if s] if args.scalars else (),
        supersample=args.supersample,
        progress_bar=args.progress,
        up=args.up,
    )
    require_coverage(bool(g.mask.any()), args.mesh, args.view)
    out = g.save(args.output)
    print(f"{g!r}\nwrote {out}")
    return 0


def _cmd_edges(args: argparse.Namespace) -> int:
    out, vector = picture_output(args.output)
    if args.background is not None and not (vector or args.hidden):
        raise InputError(
            "--background: the background under line art (an .svg/.pdf --output, or "
            f"--hidden); a PNG is drawn in --style {args.style}"
        )
    if args.layers is not None and not args.hidden:
        raise InputError("--layers: the surfaces behind are for hidden lines: add --hidden")
    t0 = time.perf_counter()
    with progress(args.progress, 4, "edges") as bar:
        meshes = [read_mesh(p) for p in args.mesh]
        bar.step("capture")
        g = capture(
            meshes,
            window_size=args.size,
            camera=args.view,
            parallel_projection=True if args.parallel else None,
            supersample=args.supersample,
            up=args.up,
            layers=int(args.layers or 4) if args.hidden else 1,
        )
        require_coverage(bool(g.mask.any()), args.mesh, args.view)
        bar.step("edges")
        title = ", ".join(Path(m).name for m in args.mesh)
        line_art = {"crease_angle": args.crease_angle, "depth_jump": args.depth_jump,
                    "width": args.width, "background": args.background or "none"}  # fmt: skip
        if args.hidden:
            if vector:
                picture = technical_drawing(g, hidden=args.hidden, **line_art)
                bar.step("write")
                write_vector(out, picture, title=title)
            else:
                image = technical_drawing_image(g, hidden=args.hidden, **line_art)
                bar.step("write")
                write_png(out, image)
        elif vector:
            picture = edge_picture(
                g,
                crease_angle=args.crease_angle,
                depth_jump=args.depth_jump,
                width=args.width,
                background=args.background or "none",
            )
            bar.step("write")
            write_vector(out, picture, title=title)
        else:
            image = illustrate(
                g,
                style=args.style,
                operator=args.operator,
                crease_angle=args.crease_angle,
                depth_jump=args.depth_jump,
                width=args.width,
            )
            bar.step("write")
            write_png(out, image)
        bar.step("done")
    w, h = args.size
    if args.hidden:
        what = f"hidden lines {args.hidden}, background {args.background or 'none'}"
    elif vector:
        what = f"{len(picture.strokes)} strokes, background {args.background or 'none'}"
    else:
        what = f"style {args.style}"
    print(f"wrote {out} ({w}x{h}, {what}) in {time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    g = GBuffer.load(args.file)
    print(repr(g))
    for name, arr in g.channels().items():
        print(f"  {name:<20} {arr.dtype!s:<8} {'x'.join(map(str, arr.shape))}")
    c = g.camera
    print(f"  camera position {c.position}, focal point {c.focal_point}, view up {c.view_up}")
    print(f"  clipping range {c.clipping_range}, pixel size {c.pixel_size:.6g}")
    return 0


def add_capture(sub) -> None:
    """Add the ``capture`` command to the sub-parsers ``sub``."""
    p = sub.add_parser("capture", help="capture the G-buffers of mesh files into .npz/.vti")
    p.add_argument("mesh", nargs="+", help="mesh file(s) (STL, PLY, OBJ, VTK, ...)")
    p.add_argument("-o", "--output", required=True, help="G-buffer file (.npz or .vti)")
    p.add_argument("--size", type=size, default=(1024, 768), help="image size WxH")
    p.add_argument("--view", default="iso", help="iso, xy, xz, yz, yx, zx or zy")
    p.add_argument("--parallel", action="store_true", help="orthographic projection")
    add_up(p)
    p.add_argument("--scalars", default="", help="comma-separated point/cell arrays to capture")
    p.add_argument("--supersample", type=int, default=1, help="render at k times the size")
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.set_defaults(func=_cmd_capture)


def add_edges(sub) -> None:
    """Add the ``edges`` command to the sub-parsers ``sub``."""
    p = sub.add_parser(
        "edges",
        help="draw a mesh file with edge enhancement (Saito & Takahashi 1990, 2003 edge map)",
        description="Render mesh file(s) once and draw profiles and internal edges: "
        + "; ".join(f"{k}: {v}" for k, v in styles_for("illustrate").items())
        + ".",
    )
    p.add_argument("mesh", nargs="+", help="mesh file(s) (STL, PLY, OBJ, VTK, VTP, ...)")
    p.add_argument(
        "-o", "--output", required=True,
        help="output image (.png), or profile and crease lines as vector strokes (.svg/.pdf)",
    )  # fmt: skip
    p.add_argument("--size", type=size, default=(1024, 768), help="image size WxH")
    p.add_argument("--view", default="iso", choices=sorted(VIEWS), help="view direction")
    p.add_argument("--parallel", action="store_true", help="orthographic projection")
    add_up(p)
    p.add_argument(
        "--supersample",
        type=positive_int,
        default=2,
        help="render at k times the size and average down (antialiasing; default 2)",
    )
    p.add_argument(
        "--style",
        default="enhance",
        choices=list(styles_for("illustrate")),
        help="picture style",
    )
    p.add_argument(
        "--operator",
        default="diagonal",
        choices=["diagonal", "c1"],
        help="2003 edge-map operator of the enhance and edgemap styles",
    )
    p.add_argument(
        "--crease-angle",
        type=number(lambda v: 0 < v < 180, "degrees in (0, 180)"),
        default=_EDGE_DEFAULTS["crease_angle"],
        metavar="DEG",
        help="normals turning by more than this make an internal edge (default 30)",
    )
    p.add_argument(
        "--depth-jump",
        type=number(lambda v: v > 0, "a number of pixel widths > 0"),
        default=_EDGE_DEFAULTS["depth_jump"],
        metavar="PX",
        help="unexplained depth steps larger than this many pixel widths make a profile "
        "(default 1)",
    )
    p.add_argument(
        "--width",
        type=number(lambda v: v >= 1, "a line width in pixels >= 1"),
        default=_EDGE_DEFAULTS["width"],
        metavar="PX",
        help="line width in output pixels (default 1)",
    )
    p.add_argument(
        "--background",
        default=None,
        choices=BACKGROUNDS,
        help="under the vector lines of an .svg/.pdf: none (white paper, the default) or shade "
        "(the Lambert shade, embedded as an image)",
    )
    p.add_argument(
        "--hidden",
        default=None,
        choices=HIDDEN,
        help="a technical drawing: visible edges solid, the edges behind them dashed or thin "
        "(captures the surfaces behind: --layers)",
    )
    p.add_argument(
        "--layers",
        type=number(lambda v: v == int(v) and 2 <= v <= 8, "a whole number of surfaces in [2, 8]"),
        default=None,
        metavar="K",
        help="with --hidden: surfaces kept along each ray, the visible one included (default 4)",
    )
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.set_defaults(func=_cmd_edges)


def add_info(sub) -> None:
    """Add the ``info`` command to the sub-parsers ``sub``."""
    p = sub.add_parser("info", help="describe a saved G-buffer file")
    p.add_argument("file", help=".npz or .vti written by capture")
    p.set_defaults(func=_cmd_info)
