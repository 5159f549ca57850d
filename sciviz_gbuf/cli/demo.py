"""``sciviz-gbuf demo``: every recipe on bundled data, PNGs and an index.html."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..apps.demo import run_demo
from ._args import add_progress, show_progress, size

__all__ = ["add_demo"]


def _cmd_demo(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    # On a terminal every figure is announced as it starts and timed as it ends (a first run
    # compiles the kernels: minutes would otherwise pass in silence); elsewhere (a log, CI)
    # only the summary line below.
    show = show_progress(args)

    def report(line: str) -> None:
        print(f"sciviz-gbuf demo: {line}", file=sys.stderr, flush=True)

    files = run_demo(
        args.output, window_size=args.size, progress_bar=False, report=report if show else None
    )
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
    add_progress(p)
    p.set_defaults(func=_cmd_demo)
