"""The one registry of picture styles: name -> :class:`Style` (what it draws, which front ends
offer it, the function that draws it).

Each style module registers its styles with :func:`register` next to the function that draws
them, so adding a style is one module plus one ``register`` line. Front ends read their
choices here: :func:`~sciviz_gbuf.styles.illustrate` and the ``edges`` command
(``"illustrate"``), :func:`~sciviz_gbuf.recipes.npr.npr_image` and the ``mesh`` command
(``"npr"``), the explorer (``"explore"``) and the live overlay (``"live"``, which composites
its own RGBA edges over the rendering and so needs no drawing function).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["FRONTS", "STYLES", "Style", "check_style", "register", "styles_for"]

#: The front ends that offer styles.
FRONTS = ("illustrate", "npr", "explore", "live")


@dataclass(frozen=True)
class Style:
    """One picture style.

    Attributes
    ----------
    name : str
        Unique across all front ends.
    description : str
        One line, shown in ``--help`` and the explorer.
    fronts : frozenset of str
        The front ends of :data:`FRONTS` that offer it.
    draw : callable or None
        ``draw(gb, **options) -> (H, W, 3)`` float32 RGB in [0, 1] at the G-buffer's output size
        (``edgemap``: RGBA); None for an overlay-only style.
    aliases : tuple of str
        Old names still accepted for it by its front ends (unique among their styles).
    """

    name: str
    description: str
    fronts: frozenset[str]
    draw: Callable[..., np.ndarray] | None = None
    aliases: tuple[str, ...] = ()


#: name -> :class:`Style`, filled by :func:`register` as the style modules are imported.
STYLES: dict[str, Style] = {}


def register(
    name: str,
    description: str,
    *,
    fronts: Iterable[str],
    draw: Callable[..., np.ndarray] | None = None,
    aliases: Iterable[str] = (),
) -> Style:
    """Add a style to :data:`STYLES` (its name and aliases must be new, its fronts known)."""
    fronts = frozenset(fronts)
    unknown = sorted(fronts - set(FRONTS))
    if unknown or not fronts:
        raise ValueError(f"style {name!r}: fronts must be among {FRONTS}, got {sorted(fronts)}")
    aliases = tuple(aliases)
    # Names are unique; an alias only among the styles of the same front ends.
    near = {n for s in STYLES.values() if s.fronts & fronts for n in (s.name, *s.aliases)}
    clash = sorted(({name} & set(STYLES)) | (set(aliases) & near))
    if clash:
        raise ValueError(f"style {name!r}: name(s) {clash} already registered")
    style = Style(name, description, fronts, draw, aliases)
    STYLES[name] = style
    return style


def styles_for(front: str) -> dict[str, str]:
    """The styles one front end offers, ``{name: description}`` sorted by name (so the order
    does not depend on which style module was imported first)."""
    return {n: s.description for n, s in sorted(STYLES.items()) if front in s.fronts}


def check_style(style: object, front: str) -> str:
    """The registered name of ``style`` (an alias gives its style) if ``front`` offers it."""
    offered = [s for s in STYLES.values() if front in s.fronts]
    for s in offered:
        if style == s.name:
            return s.name
    for s in offered:
        if style in s.aliases:
            return s.name
    raise InputError(f"style: expected one of {sorted(styles_for(front))}, got {style!r}")
