"""The ``sciviz-gbuf patches`` command: surface analysis of Bezier patches (1990 Fig. 15)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..compose import write_png
from ..readers.patches import read_patches
from ..recipes.surface import CURVATURES, MODES, surface_analysis, surface_gbuffer
from ..recipes.vector import surface_picture, write_vector
from ._args import add_progress, add_up, number, picture_output, positive_int, show_progress, size

__all__ = ["add_patches"]

_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def _axis(text: str) -> tuple[float, float, float]:
    key = text.strip().lower()
    if key in _AXES:
        return _AXES[key]
    try:
        values = tuple(float(v) for v in key.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not any(values):
        raise argparse.ArgumentTypeError(f"expected x, y, z or a vector X,Y,Z, got {text!r}")
    return values  # type: ignore[return-value]


def _cmd_patches(args: argparse.Namespace) -> int:
    out, vector = picture_output(args.output)
    t0 = time.perf_counter()
    patches = read_patches(args.file)
    gb = surface_gbuffer(
        patches,
        view=args.view,
        resolution=args.resolution,
        window_size=args.size,
        supersample=args.supersample,
        progress_bar=show_progress(args),
        up=args.up,
    )
    options = {"mode": args.mode, "axis": args.axis, "stripes": args.stripes,
               "width": args.width, "curvature": args.curvature}  # fmt: skip
    if vector:  # the lines as strokes over the shaded surface on white paper
        write_vector(out, surface_picture(gb, **options), title=Path(args.file).name)
    else:
        image = surface_analysis(gb, **options,
                                 background=(1.0, 1.0, 1.0) if args.white else None)  # fmt: skip
        write_png(out, image)
    print(
        f"wrote {out} ({args.mode}) of {len(patches)} patches from {Path(args.file).name} "
        f"in {time.perf_counter() - t0:.1f} s"
    )
    return 0


def add_patches(sub) -> None:
    """Add the ``patches`` sub-command to the ``sciviz-gbuf`` parser."""
    p = sub.add_parser(
        "patches",
        help="surface analysis of Bezier patches: reflection lines, zebra, curvature (Fig. 15)",
        description="Read a .bpt Bezier patch file, tessellate it with analytic normals and "
        "curvatures, render it once and draw reflection lines (pseudo-highlight), zebra "
        "stripes, highlight lines, isophotes, a curvature map or contour lines of height.",
    )
    p.add_argument("file", help=".bpt patch file (count; per patch 'du dv' and the points)")
    p.add_argument(
        "-o", "--output", required=True,
        help="output image (.png), or its lines as vector strokes (.svg/.pdf)",
    )  # fmt: skip
    p.add_argument("--mode", default="reflection", choices=MODES, help="what to draw")
    p.add_argument("--view", default="iso", help="iso, xy, xz, yz, yx, zx or zy")
    add_up(p)
    p.add_argument("--size", type=size, default=(1024, 768), help="image size WxH")
    p.add_argument("--supersample", type=positive_int, default=2, help="render at k times the size")
    p.add_argument(
        "--resolution", type=positive_int, default=32, help="tessellation per patch and side"
    )
    p.add_argument(
        "--axis", type=_axis, default=(0.0, 0.0, 1.0), help="light-line direction (x|y|z|X,Y,Z)"
    )
    p.add_argument(
        "--stripes",
        type=number(lambda v: v >= 1, "a number >= 1"),
        default=16.0,
        help="lines (or stripe pairs) per turn around the axis (default 16)",
    )
    p.add_argument(
        "--width",
        type=number(lambda v: v > 0, "a width in pixels > 0"),
        default=1.5,
        help="line width in pixels (default 1.5)",
    )
    p.add_argument("--curvature", default="gaussian", choices=CURVATURES, help="curvature map")
    p.add_argument("--white", action="store_true", help="white background (default transparent)")
    add_progress(p)
    p.set_defaults(func=_cmd_patches)
