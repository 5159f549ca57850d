"""``sciviz-gbuf demo``: every recipe on bundled data, PNGs and an index.html."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..apps.demo import run_demo
from ._args import size

__all__ = ["add_demo"]


def _cmd_demo(args: argparse.Namespace) -> int:
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


def add_demo(sub) -> None:
    """Add the ``demo`` command to the sub-parsers ``sub``."""
    p = sub.add_parser("demo", help="run every recipe on bundled data; write PNGs + index.html")
    p.add_argument("-o", "--output", default="sciviz_gbuf_demo", help="output folder")
    p.add_argument("--size", type=size, default=(800, 600), help="image size WxH")
    p.add_argument("--progress", action="store_true", help="show progress bars")
    p.set_defaults(func=_cmd_demo)
