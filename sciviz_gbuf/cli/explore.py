"""The ``sciviz-gbuf explore`` command: serve the explorer's web page
(:mod:`sciviz_gbuf.apps.explorer_web`) on 127.0.0.1."""

from __future__ import annotations

import argparse
import sys

from ..apps.explorer import Explorer
from ..apps.explorer_web import build_app
from ..errors import InputError
from ._args import positive_int, size

__all__ = ["add_explore"]


def _cmd_explore(args: argparse.Namespace) -> int:
    try:
        import trame  # noqa: F401
        import trame_vuetify  # noqa: F401
    except ImportError as exc:
        raise InputError(
            f"explore needs trame and trame-vuetify: pip install 'sciviz-gbuf[web]' ({exc})"
        ) from exc
    explorer = Explorer.from_file(args.file, window_size=args.size)
    server = build_app(explorer, port=args.port)
    print(f"sciviz-gbuf explore: http://127.0.0.1:{args.port}/", flush=True)
    # trame parses sys.argv itself (--host among others): hide ours so nothing can move the
    # server off the loopback address.
    sys.argv = sys.argv[:1]
    server.start(
        host="127.0.0.1",
        port=args.port,
        open_browser=False,
        show_connection_info=False,
        disable_logging=True,
    )
    return 0


def add_explore(sub) -> None:
    """Add the ``explore`` sub-command to the ``sciviz-gbuf`` parser."""
    p = sub.add_parser(
        "explore",
        help="web explorer on 127.0.0.1: every enhancement parameter live (needs trame)",
        description="Capture a mesh, DEM or DICOM folder once and serve a local web page "
        "(trame, 127.0.0.1 only) with the picture and controls for the edge thresholds, "
        "contour lines, colour bands, light, style and camera. A control re-runs only the "
        "filters on the cached G-buffer; moving the camera captures again. A DEM opens as a "
        "plan-view topographic map on its grid (relief light, z factor, contour interval, "
        "major lines, line width, colour bands), with a view selector for the 3-D height field.",
    )
    p.add_argument(
        "file",
        nargs="?",
        default=None,
        help="mesh file, DEM (.tif/.asc/.hgt/.dem/.npy/.npz) or DICOM folder "
        "(default: the bundled machine nut)",
    )
    p.add_argument("--port", type=positive_int, default=8080, help="TCP port (default 8080)")
    p.add_argument("--size", type=size, default=(1024, 768), help="image size WxH")
    p.set_defaults(func=_cmd_explore)
