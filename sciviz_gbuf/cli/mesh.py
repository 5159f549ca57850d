"""The ``sciviz-gbuf mesh`` command: NPR styles of any mesh file (2003 §5, 1990 §4.1-4.2)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..compose import write_png
from ..core.camera import VIEWS
from ..core.capture import capture
from ..errors import InputError
from ..readers import read_mesh
from ..recipes.npr import STYLES, npr_image
from ..recipes.vector import drawing_picture, write_vector
from ._args import (
    add_progress,
    add_up,
    picture_output,
    positive_int,
    require_coverage,
    show_progress,
    size,
)

__all__ = ["add_mesh"]


def _light(text: str) -> tuple[float, float, float]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not any(values):
        raise argparse.ArgumentTypeError(f"expected an eye-space direction X,Y,Z, got {text!r}")
    return values  # type: ignore[return-value]


def _cmd_mesh(args: argparse.Namespace) -> int:
    out, vector = picture_output(args.output)
    style = "drawing" if args.style == "lines" else args.style
    if vector and style != "drawing":
        raise InputError(
            f"--output: vector output (.svg/.pdf) draws the line style (--style drawing or "
            f"lines), not {args.style}; for edges over a shaded surface use "
            "`sciviz-gbuf edges ... --background shade -o out.svg`"
        )
    t0 = time.perf_counter()
    meshes = [read_mesh(p) for p in args.mesh]
    options = {"light": args.light} if args.light is not None else {}
    if args.style == "toon":
        options["levels"] = args.levels
    common = {
        "window_size": args.size,
        "supersample": args.supersample,
        "progress_bar": show_progress(args),
        "parallel_projection": True if args.parallel else None,
        "up": args.up,
    }
    names = ", ".join(Path(p).name for p in args.mesh)
    if vector:
        gb = capture(meshes, camera=args.view, **common)
        require_coverage(bool(gb.mask.any()), args.mesh, args.view)
        picture = drawing_picture(gb, **options)
        write_vector(out, picture, title=names)
        what = f"{style}, {len(picture.strokes)} strokes"
    else:
        image = npr_image(meshes, style=args.style, view=args.view, **common, **options)
        require_coverage(bool((image != 255).any()), args.mesh, args.view)  # not blank paper
        write_png(out, image)
        what = args.style
    print(f"wrote {out} ({what}) of {names} in {time.perf_counter() - t0:.1f} s")
    return 0


def add_mesh(sub) -> None:
    """Add the ``mesh`` sub-command to the ``sciviz-gbuf`` parser."""
    p = sub.add_parser(
        "mesh",
        help="draw a mesh file in an NPR style: gooch, toon, hatch or lines",
        description="Render mesh file(s) once and draw them in a non-photorealistic style: "
        + "; ".join(f"{k}: {v}" for k, v in STYLES.items())
        + ".",
    )
    p.add_argument("mesh", nargs="+", help="mesh file(s) (STL, PLY, OBJ, VTK, VTP, ...)")
    p.add_argument(
        "-o", "--output", required=True,
        help="output image (.png), or vector line art (.svg/.pdf) of the drawing style",
    )  # fmt: skip
    p.add_argument(
        "--style",
        default="gooch",
        choices=[*STYLES, "lines"],
        help="picture style (lines: the old name of drawing)",
    )
    p.add_argument("--view", default="iso", choices=sorted(VIEWS), help="view direction")
    p.add_argument("--parallel", action="store_true", help="orthographic projection")
    add_up(p)
    p.add_argument("--size", type=size, default=(1024, 768), help="image size WxH")
    p.add_argument("--supersample", type=positive_int, default=2, help="render at k times the size")
    p.add_argument("--light", type=_light, default=None, help="eye-space light direction X,Y,Z")
    p.add_argument("--levels", type=positive_int, default=3, help="toon: shade levels")
    add_progress(p)
    p.set_defaults(func=_cmd_mesh)
