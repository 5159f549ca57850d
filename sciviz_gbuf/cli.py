"""The ``sciviz-gbuf`` command line: one sub-command per job."""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from .camera import VIEWS
from .errors import InputError, SciVizGBufError

__all__ = ["main"]

# Defaults of the edges command (the filters' own defaults).
_EDGE_DEFAULTS = {"crease_angle": 30.0, "depth_jump": 1.0, "width": 1.0}


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        w = h = 0
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT of positive integers such as 1024x768, got {text!r}"
        )
    return w, h


def _number(ok: Callable[[float], bool], expected: str) -> Callable[[str], float]:
    """An argparse type: a float for which ``ok`` holds (NaN never does), else an error that
    says what was ``expected``."""

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            v = float("nan")
        if not (math.isfinite(v) and ok(v)):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return v

    return parse


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        v = 0
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def _cmd_demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    t0 = time.perf_counter()
    files = run_demo(args.output, window_size=args.size, progress_bar=args.progress)
    index = next((f for f in files if f.name == "index.html"), None)
    print(
        f"wrote {len(files)} files to {Path(args.output).resolve()} "
        f"in {time.perf_counter() - t0:.1f} s"
    )
    if index is not None:
        print(f"open {index.resolve()}")
    return 0


def _cmd_capture(args: argparse.Namespace) -> int:
    from .capture import capture
    from .readers import read_mesh

    meshes = [read_mesh(p) for p in args.mesh]
    g = capture(
        meshes,
        window_size=args.size,
        camera=args.view,
        parallel_projection=True if args.parallel else None,
        scalars=[s for s in args.scalars.split(",") if s] if args.scalars else (),
        supersample=args.supersample,
        progress_bar=args.progress,
    )
    out = g.save(args.output)
    print(f"{g!r}\nwrote {out}")
    return 0


def _cmd_edges(args: argparse.Namespace) -> int:
    from ._progress import progress
    from .capture import capture
    from .compose import write_png
    from .readers import read_mesh
    from .recipes import illustrate

    out = Path(args.output)
    if out.suffix.lower() != ".png":
        raise InputError(f"--output: expected a file name ending in .png, got {str(out)!r}")
    if not out.parent.is_dir():
        raise InputError(f"--output: no such directory {str(out.parent)!r}")
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
        )
        bar.step("edges")
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
    print(f"wrote {out} ({w}x{h}, style {args.style}) in {time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    from .gbuffer import GBuffer

    g = GBuffer.load(args.file)
    print(repr(g))
    for name, arr in g.channels().items():
        print(f"  {name:<20} {arr.dtype!s:<8} {'x'.join(map(str, arr.shape))}")
    c = g.camera
    print(f"  camera position {c.position}, focal point {c.focal_point}, view up {c.view_up}")
    print(f"  clipping range {c.clipping_range}, pixel size {c.pixel_size:.6g}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for documentation and tests)."""
    from . import __version__

    parser = argparse.ArgumentParser(
        prog="sciviz-gbuf",
        description="Comprehensible rendering of 3-D shapes with G-buffers (PyVista/VTK).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("demo", help="run every recipe on bundled data; write PNGs + index.html")
    p.add_argument("-o", "--output", default="sciviz_gbuf_demo", help="output folder")
    p.add_argument("--size", type=_size, default=(800, 600), help="image size WxH")
    p.add_argument("--progress", action="store_true", help="show progress bars")
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser("capture", help="capture the G-buffers of mesh files into .npz/.vti")
    p.add_argument("mesh", nargs="+", help="mesh file(s) (STL, PLY, OBJ, VTK, ...)")
    p.add_argument("-o", "--output", required=True, help="G-buffer file (.npz or .vti)")
    p.add_argument("--size", type=_size, default=(1024, 768), help="image size WxH")
    p.add_argument("--view", default="iso", help="iso, xy, xz, yz, yx, zx or zy")
    p.add_argument("--parallel", action="store_true", help="orthographic projection")
    p.add_argument("--scalars", default="", help="comma-separated point/cell arrays to capture")
    p.add_argument("--supersample", type=int, default=1, help="render at k times the size")
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.set_defaults(func=_cmd_capture)

    from .recipes import STYLES

    p = sub.add_parser(
        "edges",
        help="draw a mesh file with edge enhancement (Saito & Takahashi 1990, 2003 edge map)",
        description="Render mesh file(s) once and draw profiles and internal edges: "
        + "; ".join(f"{k}: {v}" for k, v in STYLES.items())
        + ".",
    )
    p.add_argument("mesh", nargs="+", help="mesh file(s) (STL, PLY, OBJ, VTK, VTP, ...)")
    p.add_argument("-o", "--output", required=True, help="output image (.png)")
    p.add_argument("--size", type=_size, default=(1024, 768), help="image size WxH")
    p.add_argument("--view", default="iso", choices=sorted(VIEWS), help="view direction")
    p.add_argument("--parallel", action="store_true", help="orthographic projection")
    p.add_argument(
        "--supersample",
        type=_positive_int,
        default=2,
        help="render at k times the size and average down (antialiasing; default 2)",
    )
    p.add_argument("--style", default="enhance", choices=list(STYLES), help="picture style")
    p.add_argument(
        "--operator",
        default="diagonal",
        choices=["diagonal", "c1"],
        help="2003 edge-map operator of the enhance and edgemap styles",
    )
    p.add_argument(
        "--crease-angle",
        type=_number(lambda v: 0 < v < 180, "degrees in (0, 180)"),
        default=_EDGE_DEFAULTS["crease_angle"],
        metavar="DEG",
        help="normals turning by more than this make an internal edge (default 30)",
    )
    p.add_argument(
        "--depth-jump",
        type=_number(lambda v: v > 0, "a number of pixel widths > 0"),
        default=_EDGE_DEFAULTS["depth_jump"],
        metavar="PX",
        help="unexplained depth steps larger than this many pixel widths make a profile "
        "(default 1)",
    )
    p.add_argument(
        "--width",
        type=_number(lambda v: v >= 1, "a line width in pixels >= 1"),
        default=_EDGE_DEFAULTS["width"],
        metavar="PX",
        help="line width in output pixels (default 1)",
    )
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.set_defaults(func=_cmd_edges)

    p = sub.add_parser("info", help="describe a saved G-buffer file")
    p.add_argument("file", help=".npz or .vti written by capture")
    p.set_defaults(func=_cmd_info)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for bad input)."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except SciVizGBufError as exc:
        print(f"sciviz-gbuf {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
