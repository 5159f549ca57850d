"""The ``sciviz-gbuf`` command line: one sub-command per job."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from .errors import SciVizGBufError

__all__ = ["main"]


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT such as 1024x768, got {text!r}"
        ) from None
    return w, h


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
