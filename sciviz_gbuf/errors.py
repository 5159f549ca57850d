"""The exception family of sciviz_gbuf.

Every error raised on purpose by this package derives from :class:`SciVizGBufError`,
so callers can catch the whole family with one ``except``.
"""

from __future__ import annotations

__all__ = ["InputError", "OutputError", "RenderError", "SciVizGBufError"]


class SciVizGBufError(Exception):
    """Base class of all errors raised on purpose by sciviz_gbuf."""


class InputError(SciVizGBufError, ValueError):
    """A bad file or parameter: the message names it and says what was expected."""


class RenderError(SciVizGBufError, RuntimeError):
    """The offscreen renderer could not be created or produced no image."""


class OutputError(SciVizGBufError, OSError):
    """An output could not be written completely (disk full, no permission, interrupted): the
    message names the file; nothing is left behind under its name."""
