"""NPR styles of any captured scene as one picture (Nienhaus & Döllner 2003 §5; Saito &
Takahashi 1990 §4.1-4.2): the ``sciviz-gbuf mesh`` command and the demo's NPR figure.

The styles themselves live in :mod:`sciviz_gbuf.styles`; this module picks one by name,
captures the scene when given data instead of a G-buffer, and returns 8-bit RGB on paper.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
import pyvista as pv

from ..compose import to_uint8
from ..core.camera import VIEWS
from ..core.capture import capture
from ..core.framing import named_view_camera
from ..core.gbuffer import GBuffer
from ..errors import InputError
from ..styles import gooch, hatch, line_drawing, toon

__all__ = ["MIRROR_CAMERA", "STYLES", "mirror_scene", "npr_image", "with_section_uv"]

#: Style name -> one-line description.
STYLES = {
    "gooch": "technical illustration: warm-cool shading, white inner edges, black profiles",
    "toon": "cartoon shading: a few flat shade levels and black profiles",
    "hatch": "pen-and-ink hatching: strokes thickening with the shade, black profiles",
    "lines": "line drawing: profiles and shade-modulated curved hatching (1990 Fig. 9)",
}


def with_section_uv(gb: GBuffer) -> GBuffer:
    """The G-buffer with ``uv`` replaced by two world coordinates, for surfaces without a
    parameterisation: curved hatching of them draws parallel sections (1990 §3.4), across the
    two world axes least aligned with the line of sight."""
    sight = np.abs(np.asarray(gb.camera.direction, dtype=np.float64))
    a, b = sorted(np.argsort(sight)[:2])
    uv = np.where(gb.mask[..., None], gb.world[..., [a, b]], np.float32(np.nan))
    return dataclasses.replace(gb, uv=uv.astype(np.float32))


def npr_image(
    source,
    *,
    style: str = "gooch",
    view: object = "iso",
    window_size: Sequence[int] = (1024, 768),
    supersample: int = 2,
    combo: str = "shuv",
    progress_bar: bool = False,
    **style_options,
) -> np.ndarray:
    """One NPR picture of a scene or G-buffer.

    Parameters
    ----------
    source : GBuffer, PyVista dataset(s) or Plotter
        A G-buffer is used as is; anything else is captured first (``view``, ``window_size``,
        ``supersample`` as in :func:`~sciviz_gbuf.capture`; a named view of datasets is framed
        tightly on their points).
    style : {"gooch", "toon", "hatch", "lines"}, default: "gooch"
        See :data:`STYLES`.
    combo : str, default: "shuv"
        ``lines``: which 1990 Fig. 9 combination (:func:`~sciviz_gbuf.styles.line_drawing`);
        a surface without texture coordinates is hatched along sections of one world axis
        instead (``shuv`` becomes ``shu``).
    **style_options
        Passed to the style function (``light``, ``levels``, ``spacing``...).

    Returns
    -------
    (H, W, 3) uint8 RGB on white paper.
    """
    if style not in STYLES:
        raise InputError(f"style: expected one of {sorted(STYLES)}, got {style!r}")
    if isinstance(source, GBuffer):
        gb = source
    else:
        w, h = (int(v) for v in window_size)
        if isinstance(view, str) and view in VIEWS and isinstance(source, (pv.DataSet, list)):
            items = source if isinstance(source, list) else [source]
            points = np.concatenate([np.asarray(d.points) for d in items if d.n_points])
            view = named_view_camera(points, view, aspect=w / max(h, 1))
        gb = capture(
            source, window_size=(w, h), camera=view, supersample=supersample,
            progress_bar=progress_bar,
        )  # fmt: skip
    if style == "gooch":
        rgb = gooch(gb, **style_options)
    elif style == "toon":
        rgb = toon(gb, **style_options)
    elif style == "hatch":
        rgb = hatch(gb, **style_options)
    else:
        if gb.uv is None:
            # Sections along one world axis: two crossing families of sections make moire on
            # curved parts; the surface parameterisation of u and v does not.
            gb, combo = (
                with_section_uv(gb),
                {"shuv": "shu", "cv": "cu", "shv": "shu"}.get(combo, combo),
            )
        grey = line_drawing(gb, combo=combo, **style_options)
        rgb = np.repeat(grey[..., None], 3, axis=2)
    return to_uint8(rgb)


#: The eye of :func:`mirror_scene`: in front of the mirror, above the nut and to its right.
MIRROR_CAMERA = ((125.0, 80.0, 175.0), (10.0, 14.0, -20.0), (0.0, 1.0, 0.0))


def mirror_scene() -> list[pv.DataSet]:
    """The 2003 Fig. 8 set-up on bundled data: an upright rectangular mirror (index 0, facing
    +z), PyVista's nut centred at the origin (axis along y) and a ball beside it."""
    from ..datasets import load_nut

    nut = load_nut()
    nut = nut.translate([-c for c in nut.center])
    mirror = pv.Plane(center=(0.0, 22.0, -45.0), direction=(0, 0, 1), i_size=130, j_size=75)
    ball = pv.Sphere(radius=10.0, center=(-38.0, -5.0, 8.0), theta_resolution=64, phi_resolution=64)
    return [mirror, nut, ball]
