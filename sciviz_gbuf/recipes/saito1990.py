"""The edge figures of Saito & Takahashi (1990): Fig. 3 (edge drawing) and Fig. 7 (enhancement).

:func:`fig3_panels` runs the paper's literal pipeline on the ``sz`` image (Sobel gradient, Eq. 1;
second-order operator, Eq. 2; normalised profile image, Eq. 3 with ``k_g``; internal edges with
0th-order discontinuities suppressed, Eq. 4 with ``k_l``) next to the robust
:func:`~sciviz_gbuf.filters.profile_edges` / :func:`~sciviz_gbuf.filters.internal_edges`.
:func:`fig7_panels` composes the Fig. 7 pictures and the 2003 edge-map enhancement.

Both return ``(key, title, image)`` triples at the G-buffer's output size, ready for
:func:`~sciviz_gbuf.compose.write_png` and :func:`~sciviz_gbuf.compose.montage`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..core.framing import oblique_camera
from ..core.gbuffer import GBuffer
from ..filters import (
    edge_map,
    enhance,
    internal_edges,
    normalize_gradient,
    profile_edges,
    second_order,
    sobel_gradient,
    suppress_zeroth_order,
)
from ..styles.illustration import LIGHT, edges_to_map, shade_image, signed_to_grey

__all__ = [
    "CAPTIONS",
    "depth_grey",
    "fig3_panels",
    "fig7_panels",
    "nut_camera",
    "sz_with_background",
]

Panel = tuple[str, str, np.ndarray]

#: One-sentence caption of each panel, by key.
CAPTIONS = {
    "depth": "Saito's perspective depth sz (Eq. 6) in grey: nearer brighter, background far away",
    "gradient": "Sobel gradient g of sz (Eq. 1), shown as g / (g + 4): faces grey by slope, "
    "0th-order discontinuities white",
    "second_order": "second-order operator l of sz (Eq. 2), 0 mid grey: creases light (convex) "
    "or dark (concave), depth jumps as double lines",
    "profile": "profile image: g normalised by its 3x3 range (Eq. 3, k_g = 10), black ink",
    "internal": "internal edge image: l with 0th-order discontinuities suppressed (Eq. 4, "
    "k_l = 2); white convex, black concave; the lines in the hole are facet borders (§5.3)",
    "profile_edges": "profile_edges: unexplained depth steps and the coverage outline, "
    "one pixel wide",
    "internal_edges": "internal_edges: normal creases between depth-continuous pixels, signed "
    "(white convex, black concave); no facet artefacts",
    "a_shaded": "(a) Lambert shade of the normals, light from the upper left",
    "b_depth": "(b) the depth (sz) image",
    "c_edges": "(c) edge image: convex edges white, concave edges and profiles black",
    "d_enhanced": "(d) the shade enhanced with (c): white edge highlights, black outlines",
    "c2_edges": "(c') edge image with all edges black (absolute internal edges)",
    "d2_enhanced": "(d') the shade enhanced with (c')",
    "edgemap_diagonal": "2003 edge map (diagonal operator) over the shade: white inner edges, "
    "black profiles",
    "edgemap_c1": "2003 edge map (C1 operator, Eq. 9) over the shade",
}

# Display scalings of the literal operators (their dynamic range is large: slopes of a few
# sz units per pixel on faces, hundreds across a silhouette):
#   gradient g >= 0          -> g / (g + G_HALF): faces dark to mid grey by slope, jumps white
#   second order l (signed)  -> 0.5 + 0.5 l / (|l| + L_HALF): 0 mid grey, creases clearly light
#                               or dark, the double lines of jumps saturated
#   internal e (signed)      -> 0.5 + 0.5 clip(e / E_SCALE, -1, 1): as the paper, sign =
#                               convexity (white convex, black concave), strength = sharpness
#   profile p in [0, 1]      -> 1 - p: black ink on white paper
G_HALF = 4.0
L_HALF = 2.0
E_SCALE = 1.0


def nut_camera(bounds: Sequence[float], *, aspect: float = 4 / 3, points: np.ndarray | None = None):
    """A view of PyVista's nut like the paper's: axis (world y) upright, seen from 45 degrees
    above and turned 25 degrees, so the top face, its chamfer, the hole and two side faces show.

    Framed by the one rule (:func:`~sciviz_gbuf.core.framing.framed_camera`) on ``points``
    if given, else on the elliptic cylinder inscribed in ``bounds`` about y: the nut's
    hexagonal prism, which the box's corners would overestimate from this oblique view.

    Returns ``(position, focal_point, view_up)`` for :func:`sciviz_gbuf.capture`.
    """
    if points is None:
        lo = np.asarray(bounds[0::2], dtype=np.float64)
        hi = np.asarray(bounds[1::2], dtype=np.float64)
        c, r = (lo + hi) / 2, (hi - lo) / 2
        t = np.linspace(0.0, 2 * np.pi, 73)
        ring = np.column_stack([c[0] + r[0] * np.cos(t), np.zeros_like(t), c[2] + r[2] * np.sin(t)])
        lift = np.array([0.0, 1.0, 0.0])
        points = np.concatenate([ring + lo[1] * lift, ring + hi[1] * lift])
    return oblique_camera(
        bounds, up_axis="y", elevation=45.0, azimuth=-25.0, aspect=aspect, points=points
    )


def sz_with_background(gb: GBuffer) -> np.ndarray:
    """``gb.sz`` with the background filled in as the paper's depth image has it: far away.

    In perspective Eq. 6 gives ``sz = d² / (w z) -> 0`` as ``z -> inf``, so the background is
    0; in parallel projection (``sz = (2d - z) / w``) it is the farthest ``sz`` less the
    depth extent and 100 pixel widths. Either way the silhouette is a 0th-order discontinuity
    of the image, which the literal operators draw. (With ``mask=gb.mask`` they would ignore
    the background by design: no silhouette, and Eq. 2 would answer a slanted face next to
    the background with a spurious line as strong as its slope.)
    """
    sz = gb.sz
    if not gb.mask.any():
        return np.zeros_like(sz)
    if gb.camera.parallel_projection:
        lo, hi = float(np.nanmin(sz[gb.mask])), float(np.nanmax(sz[gb.mask]))
        far = lo - (hi - lo) - 100.0
    else:
        far = 0.0
    return np.where(gb.mask, sz, np.float32(far)).astype(np.float32)


def depth_grey(gb: GBuffer) -> np.ndarray:
    """The depth (sz) image in grey at the output size: nearer brighter, from 0.25 (farthest
    visible point) to 1 (nearest); background black (far away)."""
    sz = gb.sz
    if not gb.mask.any():
        return np.zeros(gb.output_shape, dtype=np.float32)
    lo, hi = float(np.nanmin(sz[gb.mask])), float(np.nanmax(sz[gb.mask]))
    t = (sz - lo) / max(hi - lo, 1e-12)
    grey = np.where(gb.mask, 0.25 + 0.75 * np.clip(t, 0.0, 1.0), 0.0)
    return _out(gb, grey)


def _out(gb: GBuffer, image: np.ndarray) -> np.ndarray:
    return np.clip(gb.downsample(np.asarray(image, dtype=np.float32)), 0.0, 1.0)


def fig3_panels(
    gb: GBuffer,
    *,
    k_g: float = 10.0,
    k_l: float = 2.0,
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.0,
) -> list[Panel]:
    """The 1990 Fig. 3 sequence: depth, 1st and 2nd order differentials, profile and internal
    edge images (literal Eq. 1-4), and the robust profile / internal edges for comparison.

    The literal operators run on :func:`sz_with_background` at the buffer size (one buffer
    pixel is one pixel of the paper); their display images are averaged to the output size.
    ``k_g`` and ``k_l`` are the paper's constants (10 and 2 in Fig. 3); the other parameters go
    to :func:`~sciviz_gbuf.filters.profile_edges` / :func:`~sciviz_gbuf.filters.internal_edges`.
    See the module constants for the display scalings.
    """
    sz = sz_with_background(gb)
    g = sobel_gradient(sz)
    lap = second_order(sz)
    p = normalize_gradient(g, k_g=k_g)
    e = suppress_zeroth_order(lap, g, k_l=k_l)
    prof = profile_edges(gb, depth_jump=depth_jump, width=width)
    inner = internal_edges(gb, crease_angle=crease_angle, depth_jump=depth_jump, width=width)
    return [
        ("depth", "depth image (sz)", depth_grey(gb)),
        ("gradient", "1st order differential (Eq. 1)", _out(gb, g / (g + G_HALF))),
        (
            "second_order",
            "2nd order differential (Eq. 2)",
            _out(gb, 0.5 + 0.5 * lap / (np.abs(lap) + L_HALF)),
        ),
        ("profile", f"profile image (Eq. 3, k_g={k_g:g})", _out(gb, 1.0 - p)),
        (
            "internal",
            f"internal edge image (Eq. 4, k_l={k_l:g})",
            _out(gb, signed_to_grey(e, scale=E_SCALE)),
        ),
        ("profile_edges", "profile_edges (robust)", 1.0 - prof),
        ("internal_edges", "internal_edges (robust, signed)", signed_to_grey(inner)),
    ]


def fig7_panels(
    gb: GBuffer,
    *,
    crease_angle: float = 30.0,
    depth_jump: float = 1.0,
    width: float = 1.5,
    light: Sequence[float] = LIGHT,
) -> list[Panel]:
    """The 1990 Fig. 7 pictures and the 2003 edge-map enhancement of the same G-buffer.

    (a) Lambert shade, (b) depth, (c) edge image: convex edges white, concave edges and
    profiles black on mid grey, (d) shade enhanced with (c); (c'), (d') the same with all
    edges black (absolute internal edges); then the shade enhanced with the 2003 edge map of
    the ``"diagonal"`` and ``"c1"`` operators (white inner edges, black profiles).
    """
    opts = {"crease_angle": crease_angle, "depth_jump": depth_jump, "width": width}
    shade = shade_image(gb, light=light)
    grey = np.full(gb.output_shape, 0.5, dtype=np.float32)
    panels: list[Panel] = [
        ("a_shaded", "(a) shaded image", shade),
        ("b_depth", "(b) depth image", depth_grey(gb)),
    ]
    inner = internal_edges(gb, **opts)
    prof = profile_edges(gb, depth_jump=depth_jump, width=width)
    for black_only, tag, label in ((False, "", "1"), (True, "2", "2")):
        emap = edges_to_map(inner, prof, black_only=black_only, width=width)
        prime = "'" if black_only else ""
        panels += [
            (f"c{tag}_edges", f"(c{prime}) edge image ({label})", enhance(grey, emap)),
            (f"d{tag}_enhanced", f"(d{prime}) enhanced image ({label})", enhance(shade, emap)),
        ]
    for operator in ("diagonal", "c1"):
        emap = edge_map(gb, operator=operator, **opts)
        panels.append(
            (f"edgemap_{operator}", f"2003 edge map, {operator} operator", enhance(shade, emap))
        )
    return panels
