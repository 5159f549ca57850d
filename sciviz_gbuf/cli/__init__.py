"""The ``sciviz-gbuf`` command line: one sub-command per job, one module per command group
(each adds its commands with ``add_<name>(sub)``; shared option types are in ``_args``)."""

from __future__ import annotations

import argparse
import importlib
import re
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from .. import __version__
from .._atomic import Interrupted, one_line, output_group, raising_signals
from ..errors import SciVizGBufError

__all__ = ["build_parser", "main"]

#: The commands in ``--help`` order: ``(module, function)`` that adds each sub-parser. The
#: modules are imported when the parser is built, not with this package: their imports (VTK,
#: PyVista, numba) take seconds, and :func:`main` says it is starting before that.
COMMANDS = (
    ("demo", "add_demo"),
    ("gbuffer", "add_capture"),
    ("gbuffer", "add_edges"),
    ("terrain", "add_topo"),
    ("terrain", "add_birdseye"),
    ("medical", "add_ct"),
    ("surface", "add_patches"),
    ("mesh", "add_mesh"),
    ("explore", "add_explore"),
    ("gbuffer", "add_info"),
)
#: Commands that take seconds or more: on a terminal (or with ``--progress``), :func:`main`
#: prints one line as they start, before the imports.
_LONG = {"demo", "capture", "edges", "topo", "birdseye", "ct", "patches", "mesh", "explore"}


class _Parser(argparse.ArgumentParser):
    """argparse with the package's one-line errors: a bad option prints one line naming it
    (``sciviz-gbuf topo: error: argument --width: ...``) and exits 2, without the usage block
    (``--help`` still shows it)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {one_line(message)}\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser (exposed for documentation and tests); with ``command`` (the name
    of a sub-command) only that one's module is imported and its sub-parser added, so
    ``sciviz-gbuf topo --help`` does not wait for the modules of the other commands."""
    parser = _Parser(
        prog="sciviz-gbuf",
        description="Comprehensible rendering of 3-D shapes with G-buffers (PyVista/VTK).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for module, function in COMMANDS:
        if command is None or function == f"add_{command}":
            getattr(importlib.import_module(f".{module}", __name__), function)(sub)
    return parser


def _announce(argv: Sequence[str]) -> None:
    """One line on stderr as a long command starts (on a terminal, or with ``--progress``;
    never with ``--no-progress`` or ``--help``): loading the libraries takes seconds, a first
    run minutes more, and a command that says nothing looks hung."""
    if not argv or argv[0] not in _LONG or {"-h", "--help", "--no-progress"} & set(argv):
        return
    if "--progress" in argv or sys.stderr.isatty():
        print(f"sciviz-gbuf {argv[0]}: starting (loading VTK, PyVista and numba) ...",
              file=sys.stderr, flush=True)  # fmt: skip


# A value that starts with a minus sign and a digit ("-5x10", "-20,100", "-.5"): argparse takes
# anything starting with "-" that is not a plain negative number for an option.
_NEGATIVE_VALUE = re.compile(r"-[0-9.]")


def _attach_negative_values(argv: list[str]) -> list[str]:
    """``--opt -5x10`` as ``--opt=-5x10``, so that a negative-looking value reaches the
    option's own check (one line naming it and what is expected) instead of argparse's
    "expected one argument"."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        token = argv[i]
        if (
            token.startswith("--")
            and "=" not in token
            and token != "--"
            and i + 1 < len(argv)
            and _NEGATIVE_VALUE.match(argv[i + 1])
        ):
            out.append(f"{token}={argv[i + 1]}")
            i += 2
            continue
        out.append(token)
        i += 1
    return out


def _drop_warning(*args: object, **kwargs: object) -> None:
    """``warnings.showwarning`` after a failure: late warnings are not printed."""


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status: 0, or 2 for bad input, an output that
    could not be written, or SIGTERM/SIGINT (one line on stderr; no output file is left
    half-written, see ``_atomic``)."""
    given = sys.argv[1:] if argv is None else list(argv)
    _announce(given)
    known = {function.removeprefix("add_") for _, function in COMMANDS}
    parser = build_parser(given[0] if given and given[0] in known else None)
    args = parser.parse_args(_attach_negative_values(given))
    # SIGTERM and SIGINT become an exception, so that the writers' clean-up runs: the output
    # being written is removed and the process exits 2 with one line, not by the signal. The
    # outputs of one command are renamed to their names together at its end: a command that
    # fails leaves none of them (not the PNG of a --geotiff that could not be written).
    # Warnings are held and printed as one line each after the command succeeded: a failure
    # prints its one error line only (a warning about, say, a missing georeference before it
    # would only obscure it).
    failure: BaseException | None = None
    with raising_signals(), warnings.catch_warnings(record=True) as caught:
        try:
            with output_group():
                status = int(args.func(args))
        except (SciVizGBufError, Interrupted) as exc:
            failure = exc
    if failure is not None:
        # Worker threads of a failed computation (dask) may still finish a task and warn
        # after the error: nothing may follow the error line.
        warnings.simplefilter("ignore")
        warnings.showwarning = _drop_warning
        print(f"sciviz-gbuf {args.command}: error: {failure}", file=sys.stderr)
        return 2
    for w in caught:
        if not issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning)):
            text = one_line(str(w.message))
            print(f"sciviz-gbuf {args.command}: warning: {text}", file=sys.stderr)
    return status


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
