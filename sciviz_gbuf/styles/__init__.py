"""NPR styles of a G-buffer (Nienhaus & Döllner 2003 §5; Saito & Takahashi 1990 §4.1-4.2, §5.2).

One function each, on a :class:`~sciviz_gbuf.GBuffer`, returning an image at its output size:

- :func:`gooch`: technical illustration (Gooch et al. 1998) with the 2003 edge map (Fig. 7);
- :func:`toon`: cartoon shading (Lake et al. 2000) and the smoothed "cartoon map" (Fig. 9);
- :func:`hatch`: halftone hatching with a prioritised stroke texture (Freudenberg et al. 2002;
  2003 Fig. 8);
- :func:`line_drawing`: the 1990 Fig. 9 illustrations (sh, pr, cu, cv, shu, shv, shuv), and
  :func:`photocopy`, a copy-machine model for the Fig. 10 test;
- :func:`mirror_gbuffers` / :func:`mirror_enhance`: edge-enhanced planar mirrors (2003 Fig. 8);
- :func:`local_style`: a style on chosen objects or cells only (1990 §5.2);
- :func:`illustrate`: shaded + edge illustrations (``enhance``, ``lines``, ``fig7``,
  ``edgemap``), :func:`drawing`: a line drawing of any surface.

:data:`STYLES` is the one registry of style names (:mod:`.registry`): every front end (the
``edges`` and ``mesh`` commands, the explorer, the live overlay) takes its choices from it.
"""

from .hatch import hatch
from .illustration import (
    LIGHT,
    PAPER,
    edges_to_map,
    fig7_edge_map,
    illustrate,
    shade_image,
    signed_to_grey,
)
from .lines import drawing, line_drawing, photocopy, with_section_uv
from .local import local_style
from .mirror import mirror_enhance, mirror_gbuffers
from .registry import FRONTS, STYLES, Style, check_style, register, styles_for
from .tone import gooch, toon

__all__ = [
    "FRONTS",
    "LIGHT",
    "PAPER",
    "STYLES",
    "Style",
    "check_style",
    "drawing",
    "edges_to_map",
    "fig7_edge_map",
    "gooch",
    "hatch",
    "illustrate",
    "line_drawing",
    "local_style",
    "mirror_enhance",
    "mirror_gbuffers",
    "photocopy",
    "register",
    "shade_image",
    "signed_to_grey",
    "styles_for",
    "toon",
    "with_section_uv",
]
