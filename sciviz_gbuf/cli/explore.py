"""The ``sciviz-gbuf explore`` command: serve the explorer's web page
(:mod:`sciviz_gbuf.apps.explorer_web`) on 127.0.0.1, behind a per-launch secret."""

from __future__ import annotations

import argparse
import sys

from ..apps.explorer import Explorer
from ..apps.explorer_web import check_port, is_loopback, new_secret, serve
from ..errors import InputError
from ._args import add_up, size

__all__ = ["add_explore"]


def _port(text: str) -> int:
    """``--port`` as an int in [1, 65535] (an InputError, one line, otherwise)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 65535:
        raise InputError(f"--port: expected an integer in [1, 65535], got {text!r}")
    return value


def _cmd_explore(args: argparse.Namespace) -> int:
    try:
        import trame  # noqa: F401
        import trame_vuetify  # noqa: F401
    except ImportError as exc:
        raise InputError(
            f"explore needs trame and trame-vuetify: pip install 'sciviz-gbuf[web]' ({exc})"
        ) from exc
    port = _port(args.port)
    # Only an explicit --host moves the server off the loopback address (never TRAME_ARGS,
    # TRAME_DEFAULT_HOST or trame's own argv options), and then it says so.
    host = "127.0.0.1" if args.host is None else args.host
    if not host.strip():
        raise InputError(f"--host: expected an address or host name, got {args.host!r}")
    check_port(host, port)  # before the (slow) capture: a port in use fails at once
    if not is_loopback(host):
        print(
            f"sciviz-gbuf explore: warning: --host {host}: listening beyond this machine; "
            "anyone who can reach it and has the URL's secret controls the explorer",
            file=sys.stderr,
            flush=True,
        )
    explorer = Explorer.from_file(args.file, window_size=args.size, up=args.up)
    secret = new_secret()
    shown = "127.0.0.1" if host in ("0.0.0.0", "::", "[::]") else host
    shown = f"[{shown}]" if ":" in shown and not shown.startswith("[") else shown
    print(f"sciviz-gbuf explore: http://{shown}:{port}/?secret={secret}", flush=True)
    serve(explorer, host=host, port=port, secret=secret)
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
        "major lines, line width, colour bands), with a view selector for the 3-D height field. "
        "The camera orbits around the up axis (--up; by default the file's convention, so "
        "y-up PLY/OBJ/OFF/glTF models stand upright). "
        "Open the printed URL: it carries a secret made for this launch, without which the "
        "page cannot connect; other web pages (foreign Origin) cannot connect either.",
    )
    p.add_argument(
        "file",
        nargs="?",
        default=None,
        help="mesh file, DEM (.tif/.asc/.hgt/.dem/.npy/.npz) or DICOM folder "
        "(default: the bundled machine nut)",
    )
    # Checked in the command (one error line, exit 2), not by argparse (usage + error).
    p.add_argument("--port", default="8080", help="TCP port, 1-65535 (default 8080)")
    p.add_argument(
        "--host",
        default=None,
        help="listen on this address instead of 127.0.0.1 (prints a warning unless it is a "
        "loopback address: the explorer then answers other machines)",
    )
    p.add_argument("--size", type=size, default=(1024, 768), help="image size WxH")
    add_up(p)  # the orbit camera turns around it; heights (contours, bands) run along it
    p.set_defaults(func=_cmd_explore)
