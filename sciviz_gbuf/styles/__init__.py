"""NPR styles of a G-buffer (Nienhaus & Döllner 2003 §5; Saito & Takahashi 1990 §4.1-4.2, §5.2).

One function each, on a :class:`~sciviz_gbuf.GBuffer`, returning an image at its output size:

- :func:`gooch`: technical illustration (Gooch et al. 1998) with the 2003 edge map (Fig. 7);
- :func:`toon`: cartoon shading (Lake et al. 2000) and the smoothed "cartoon map" (Fig. 9);
- :func:`hatch`: halftone hatching with a prioritised stroke texture (Freudenberg et al. 2002;
  2003 Fig. 8);
- :func:`line_drawing`: the 1990 Fig. 9 illustrations (sh, pr, cu, cv, shu, shv, shuv), and
  :func:`photocopy`, a copy-machine model for the Fig. 10 test;
- :func:`mirror_gbuffers` / :func:`mirror_enhance`: edge-enhanced planar mirrors (2003 Fig. 8);
- :func:`local_style`: a style on chosen objects or cells only (1990 §5.2).
"""

from .hatch import hatch
from .lines import line_drawing, photocopy
from .local import local_style
from .mirror import mirror_enhance, mirror_gbuffers
from .tone import gooch, toon

__all__ = [
    "gooch",
    "hatch",
    "line_drawing",
    "local_style",
    "mirror_enhance",
    "mirror_gbuffers",
    "photocopy",
    "toon",
]
