"""NPR styles of any captured scene as one picture (Nienhaus & Döllner 2003 §5; Saito &
Takahashi 1990 §4.1-4.2): the ``sciviz-gbuf mesh`` command and the demo's NPR figure.

The styles themselves live in :mod:`sciviz_gbuf.styles`; this module picks one by name,
captures the scene when given data instead of a G-buffer, and returns 8-bit RGB on paper.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pyvista as pv

from ..compose import to_uint8
from ..core.capture import capture
from ..core.gbuffer import GBuffer
from ..datasets import load_nut
from ..styles import STYLES as STYLE_REGISTRY
from ..styles import check_style, styles_for, with_section_uv

__all__ = ["MIRROR_CAMERA", "STYLES", "mirror_scene", "npr_image", "with_section_uv"]

#: The styles of :func:`npr_image` (``{name: description}``, from the styles registry;
#: ``"lines"`` is still accepted for ``"drawing"``).
STYLES = styles_for("npr")


def npr_image(
    source,
    *,
    style: str = "gooch",
    view: object = "iso",
    window_size: Sequence[int] = (1024, 768),
    supersample: int = 2,
    combo: str = "shuv",
    progress_bar: bool = False,
    parallel_projection: bool | None = None,
    up: str | None = None,
    **style_options,
) -> np.ndarray:
    """One NPR picture of a scene or G-buffer.

    Parameters
    ----------
    source : GBuffer, PyVista dataset(s) or Plotter
        A G-buffer is used as is; anything else is captured first (``view``, ``window_size``,
        ``supersample`` as in :func:`~sciviz_gbuf.capture`; a named view is framed by the
        package's one rule: the points' projected box centred, filling 85 % of the image).
    style : {"gooch", "toon", "hatch", "drawing"}, default: "gooch"
        See :data:`STYLES`; ``"lines"`` is the old name of ``"drawing"``.
    combo : str, default: "shuv"
        ``drawing``: which 1990 Fig. 9 combination (:func:`~sciviz_gbuf.styles.line_drawing`);
        a surface without texture coordinates is hatched along sections of one world axis
        instead (``shuv`` becomes ``shu``, see :func:`~sciviz_gbuf.styles.drawing`).
    parallel_projection : bool, optional
        Orthographic (True) or perspective (False) capture; default as the camera is.
    up : {"x", "y", "z"}, optional
        World axis upright in the ``"iso"`` view; default by the file convention of the data
        (:func:`~sciviz_gbuf.core.framing.default_up`: y for OFF/OBJ/PLY/glTF, else z).
    **style_options
        Passed to the style function (``light``, ``levels``, ``spacing``...).

    Returns
    -------
    (H, W, 3) uint8 RGB on white paper.
    """
    style = check_style(style, "npr")
    if isinstance(source, GBuffer):
        gb = source
    else:
        w, h = (int(v) for v in window_size)
        # A named view is framed by the capture itself (the one framing rule, on the points
        # it renders, transforms included).
        gb = capture(
            source, window_size=(w, h), camera=view, supersample=supersample,
            progress_bar=progress_bar, parallel_projection=parallel_projection, up=up,
        )  # fmt: skip
    if style == "drawing":
        style_options["combo"] = combo
    rgb = STYLE_REGISTRY[style].draw(gb, **style_options)
    return to_uint8(rgb)


#: The eye of :func:`mirror_scene`: in front of the mirror, above the nut and to its right.
MIRROR_CAMERA = ((125.0, 80.0, 175.0), (10.0, 14.0, -20.0), (0.0, 1.0, 0.0))


def mirror_scene() -> list[pv.DataSet]:
    """The 2003 Fig. 8 set-up on bundled data: an upright rectangular mirror (index 0, facing
    +z), PyVista's nut centred at the origin (axis along y) and a ball beside it."""
    nut = load_nut()
    nut = nut.translate([-c for c in nut.center])
    mirror = pv.Plane(center=(0.0, 22.0, -45.0), direction=(0, 0, 1), i_size=130, j_size=75)
    ball = pv.Sphere(radius=10.0, center=(-38.0, -5.0, 8.0), theta_resolution=64, phi_resolution=64)
    return [mirror, nut, ball]
