"""Option types and options shared by the command modules (argparse ``type=`` callables raise
``ArgumentTypeError`` with what was expected; file checks raise ``InputError``)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path

from ..errors import InputError

__all__ = [
    "UP_HELP",
    "add_progress",
    "add_up",
    "number",
    "png_output",
    "positive_int",
    "require_coverage",
    "show_progress",
    "size",
]


def size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        w = h = 0
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT of positive integers such as 1024x768, got {text!r}"
        )
    return w, h


def number(ok: Callable[[float], bool], expected: str) -> Callable[[str], float]:
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


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        v = 0
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def show_progress(args: argparse.Namespace) -> bool:
    """``--progress``/``--no-progress``, else on only when stderr is a terminal."""
    return sys.stderr.isatty() if args.progress is None else bool(args.progress)


def png_output(text: str) -> Path:
    out = Path(text)
    if out.suffix.lower() != ".png":
        raise InputError(f"--output: expected a file name ending in .png, got {text!r}")
    if not out.parent.is_dir():
        raise InputError(f"--output: no such directory {str(out.parent)!r}")
    return out


#: Suffixes of vector pictures (strokes over an optional raster background).
VECTOR_SUFFIXES = (".svg", ".pdf")


def picture_output(text: str) -> tuple[Path, bool]:
    """``--output`` of a command that writes PNG or vector pictures: the path and True for an
    .svg or .pdf (checked: suffix, existing folder)."""
    out = Path(text)
    suffix = out.suffix.lower()
    if suffix not in (".png", *VECTOR_SUFFIXES):
        raise InputError(
            f"--output: expected a file name ending in .png, .svg or .pdf, got {text!r}"
        )
    if not out.parent.is_dir():
        raise InputError(f"--output: no such directory {str(out.parent)!r}")
    return out, suffix in VECTOR_SUFFIXES


def add_progress(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show a progress bar (default: only when stderr is a terminal)",
    )


#: The documented default of ``--up`` (the convention of the file's format, ``FORMATS``).
UP_HELP = (
    "world axis upright in the picture (default by the file's convention: y for OFF, OBJ, "
    "PLY, glTF; z for STL, VTK, VTP, Bezier patches, DICOM)"
)


def add_up(p: argparse.ArgumentParser) -> None:
    """``--up x|y|z`` (and the short ``-x``, ``-y``, ``-z``): the upright world axis; default
    None, the file format's convention."""
    p.add_argument("--up", choices=["x", "y", "z"], default=None, help=UP_HELP)
    for axis in "xyz":
        p.add_argument(
            f"-{axis}", dest="up", action="store_const", const=axis, help=f"same as --up {axis}"
        )


def require_coverage(covered: bool, files: list[str], view: object) -> None:
    """A picture of nothing is not a success: an InputError naming the file(s) when the capture
    covers no pixel (a flat mesh seen edge-on, a mesh smaller than a pixel)."""
    if not covered:
        what = files[0] if len(files) == 1 else f"{files[0]} (+{len(files) - 1} more)"
        raise InputError(
            f"{what}: nothing of it covers a pixel from view {view!r} (seen edge-on, or smaller "
            "than a pixel): try another --view or a larger --size"
        )
