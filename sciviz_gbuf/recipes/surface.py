"""Surface analysis of free-form surfaces (Saito & Takahashi 1990 §4.5, Fig. 15).

Bezier patch sets (:func:`~sciviz_gbuf.readers.read_patches`), tessellated with analytic normals
and curvatures, or any PyVista surface, are rendered once into G-buffers; then the quality of
the surface is shown by image operations on them: reflection lines or zebra stripes (the
pseudo-highlight pattern), highlight lines, isophotes, curvature maps (a diverging colour map
symmetric about 0) and contour lines of height. :func:`seam_patches` builds the paper's test
surface: two bicubic patches joined with C2, C1-not-C2, or only G0 continuity.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
import pyvista as pv

from ..compose import colorize
from ..core.camera import VIEWS
from ..core.capture import capture, check_capture_size
from ..core.framing import default_up, named_view_camera
from ..core.gbuffer import GBuffer
from ..errors import InputError
from ..filters import contour_lines, lambert, profile_edges
from ..filters.reflection import isophotes, reflection_lines
from ..readers.patches import PatchSet, parametric_mesh, read_patches
from ..styles import LIGHT
from ._intervals import round_up
from ._map import rgba

__all__ = [
    "CURVATURES",
    "MODES",
    "seam_patches",
    "surface_analysis",
    "surface_gbuffer",
    "surface_layers",
]

#: What :func:`surface_analysis` draws.
MODES = ("reflection", "stripes", "highlight", "isophote", "curvature", "contours")
#: Curvature arrays of a patch mesh (``PatchSet.to_mesh``).
CURVATURES = ("gaussian", "mean", "k1", "k2")
_CURVATURE_ARRAYS = {
    "gaussian": "gaussian_curvature",
    "mean": "mean_curvature",
    "k1": "k1",
    "k2": "k2",
}
#: Ink colour of the analysis lines.
LINE_COLOR = (0.05, 0.05, 0.25)
CONTINUITIES = ("C2", "C1", "G0")


def seam_patches(continuity: str = "C1", *, bend: float = 0.5):
    """Two bicubic patches side by side in x, joined along ``x = 1`` (1990 Fig. 15).

    Parameters
    ----------
    continuity : {"C2", "C1", "G0"}, default: "C1"
        ``"C2"``: the second patch continues the first's second derivative; ``"C1"``: same
        tangent plane (normals continuous) but the curvature across the seam jumps (the paper's
        surface); ``"G0"``: only the positions meet (a crease).
    bend : float, default: 0.5
        How far the C1 surface's second control row departs from the C2 one (in z).

    Returns
    -------
    PatchSet
    """
    if continuity not in CONTINUITIES:
        raise InputError(f"continuity: expected one of {CONTINUITIES}, got {continuity!r}")
    za = np.array([0.0, 0.5, 0.8, 0.9])
    # C1: Q1 = 2 P3 - P2; C2 also: Q2 = P1 - 4 P2 + 4 P3 (equal parameter lengths).
    q1 = 2 * za[3] - za[2]
    q2 = za[1] - 4 * za[2] + 4 * za[3]
    if continuity == "G0":
        q1 += 0.35
    zb = np.array([za[3], q1, q2 - (bend if continuity != "C2" else 0.0), 0.4])
    ys = np.linspace(0.0, 1.5, 4)
    swell = np.array([0.0, 0.25, 0.25, 0.0])  # the same across both: the seam is all in x

    def net(x0: float, z: np.ndarray) -> np.ndarray:
        xs = x0 + np.arange(4) / 3.0
        return np.stack(
            np.broadcast_arrays(xs[:, None], ys[None, :], z[:, None] + swell[None, :]), axis=-1
        ).astype(np.float64)

    return PatchSet.from_control_nets([net(0.0, za), net(1.0, zb)])


def _surface(source, resolution) -> pv.PolyData:
    from vtkmodules.vtkCommonComputationalGeometry import vtkParametricFunction

    if isinstance(source, (str, os.PathLike)):
        source = read_patches(source)
    if isinstance(source, PatchSet):
        return source.to_mesh(resolution=resolution)
    if isinstance(source, vtkParametricFunction) or (
        callable(source) and not isinstance(source, pv.DataSet)
    ):
        return parametric_mesh(source)  # pv.ParametricTorus and friends, with their (u, v)
    if isinstance(source, pv.PolyData) and source.n_cells > 0:
        if source.active_texture_coordinates is not None and "uv" not in source.point_data:
            return parametric_mesh(source)
        mesh = source.copy(deep=False)
        if "gaussian_curvature" not in mesh.point_data:
            # Any other surface: discrete (mesh-based) curvatures, so the curvature map works.
            mesh.point_data["gaussian_curvature"] = mesh.curvature("gaussian")
            mesh.point_data["mean_curvature"] = mesh.curvature("mean")
        return mesh
    raise InputError(
        "patches: expected a .bpt file, a PatchSet, a parametric surface or a pyvista.PolyData "
        f"surface, got {type(source).__name__}"
    )


def surface_gbuffer(
    source,
    *,
    view: str | object = "iso",
    resolution: int | tuple[int, int] = 32,
    window_size: Sequence[int] = (800, 600),
    supersample: int = 2,
    parallel_projection: bool | None = None,
    progress_bar: bool = False,
    up: str | None = None,
) -> GBuffer:
    """Tessellate (patch sets) and render once; capture the curvature arrays and patch ids.

    Parameters
    ----------
    source : path to a .bpt file, PatchSet, parametric surface or pyvista.PolyData
        Patches are tessellated with analytic normals and curvatures; a parametric surface
        (``pv.ParametricTorus``, a ``vtkParametricFunction``, or a mesh made with
        ``texture_coordinates=True``) goes through
        :func:`~sciviz_gbuf.readers.patches.parametric_mesh` (its u/v kept); any other surface
        keeps its point ``"Normals"`` and gets mesh-based curvatures if it has none.
    view : camera, default: "iso"
        Anything :func:`~sciviz_gbuf.capture` accepts (``"iso"``, ``"xy"``, a camera...); the
        named views are framed by the one rule (the surface's projected box centred, filling
        85 % of the image).
    resolution : int or (int, int), default: 32
        Tessellation of each patch (per parameter direction), at most
        ``LIMITS["resolution"]`` = 4096 and ``LIMITS["mesh_points"]`` = 2**24 points in all.
    window_size, supersample, parallel_projection, progress_bar
        As in :func:`~sciviz_gbuf.capture`.
    up : {"x", "y", "z"}, optional
        World axis upright in the ``"iso"`` view; default ``"z"`` (Bezier patch files follow
        Newell's z-up teapot; a mesh read from a file follows its format's convention).
    """
    # the capture's size is checked before the surface is tessellated
    w, h, _ = check_capture_size(window_size, supersample)
    mesh = _surface(source, resolution)
    if isinstance(view, str) and view in VIEWS:
        view = named_view_camera(
            mesh.points, view, aspect=w / max(h, 1), parallel=bool(parallel_projection),
            up=up if up is not None else default_up(source),
        )  # fmt: skip
    wanted = [a for a in (*_CURVATURE_ARRAYS.values(), "patch_id") if a in mesh.array_names]
    return capture(
        mesh,
        window_size=(w, h),
        camera=view,
        parallel_projection=parallel_projection,
        scalars=wanted,
        supersample=supersample,
        progress_bar=progress_bar,
    )


def _curvature_rgb(gb: GBuffer, kind: str, limit: float | None) -> tuple[np.ndarray, float]:
    if kind not in CURVATURES:
        raise InputError(f"curvature: expected one of {CURVATURES}, got {kind!r}")
    name = _CURVATURE_ARRAYS[kind]
    if name not in gb.scalars:
        raise InputError(
            f"curvature: the G-buffer has no {name!r} scalar (capture a PatchSet mesh, or a "
            "surface with that point array)"
        )
    k = np.where(gb.mask, gb.scalars[name], np.float32(np.nan))
    if limit is None:
        finite = np.abs(k[np.isfinite(k)])
        # Not the maximum: small tight spots (a knob, a spout) would wash out the rest.
        limit = float(np.percentile(finite, 95)) if finite.size else 1.0
        limit = limit if limit > 0 else 1.0
    elif not (np.isfinite(limit) and limit > 0):
        raise InputError(f"curvature_limit: expected a number > 0, got {limit!r}")
    # Symmetric about 0: blue negative, white flat, red positive.
    rgb = colorize(k, cmap="RdBu_r", vmin=-limit, vmax=limit, background=(1.0, 1.0, 1.0))
    return rgb, limit


def surface_layers(
    gb: GBuffer,
    *,
    mode: str = "reflection",
    axis: Sequence[float] = (0.0, 0.0, 1.0),
    stripes: float = 16,
    width: float = 1.5,
    light: Sequence[float] = LIGHT,
    curvature: str = "gaussian",
    curvature_limit: float | None = None,
    interval: float | None = None,
    profile_width: float = 1.5,
) -> dict[str, np.ndarray]:
    """The layers of one analysis picture at the output size: ``sh`` shade, ``ink`` the
    analysis lines or stripes (modes other than ``curvature``), ``rgb`` the base colour,
    ``pr`` profiles, ``alpha`` coverage; float32."""
    if mode not in MODES:
        raise InputError(f"mode: expected one of {MODES}, got {mode!r}")
    k = gb.supersample
    sh = np.nan_to_num(gb.downsample(lambert(gb.normal, light=light, mask=gb.mask)), nan=1.0)
    alpha = gb.downsample(gb.mask.astype(np.float32))
    base = np.full((*sh.shape, 3), 0.93, dtype=np.float32)
    ink = np.zeros_like(sh)
    if mode in ("reflection", "stripes", "highlight"):
        ink = reflection_lines(
            gb,
            axis=axis,
            stripes=stripes,
            width=width,
            style="stripes" if mode == "stripes" else "lines",
            mode="highlight" if mode == "highlight" else "reflection",
        )
    elif mode == "isophote":
        ink = isophotes(gb, light=light, interval=360.0 / stripes, width=width)
    elif mode == "contours":
        z = np.where(gb.mask, gb.world[..., 2], np.float32(np.nan))
        lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
        step = interval if interval is not None else round_up(max(hi - lo, 1e-9) / 20.0)
        if not (np.isfinite(step) and step > 0):
            raise InputError(f"interval: expected a height step > 0, got {interval!r}")
        ink = contour_lines(z, interval=step, width=width * k, mask=gb.mask, c_dense=1.0)
        ink = np.nan_to_num(gb.downsample(np.where(gb.mask, ink, np.nan)))
    else:
        rgb, _ = _curvature_rgb(gb, curvature, curvature_limit)
        base = np.nan_to_num(gb.downsample(np.where(gb.mask[..., None], rgb, np.nan)), nan=1.0)
    return {
        "sh": sh,
        "ink": ink.astype(np.float32),
        "rgb": base.astype(np.float32),
        "pr": profile_edges(gb, width=profile_width),
        "alpha": alpha,
    }


def surface_analysis(
    source,
    *,
    view: str | object = "iso",
    mode: str = "reflection",
    window_size: Sequence[int] = (800, 600),
    supersample: int = 2,
    resolution: int | tuple[int, int] = 32,
    axis: Sequence[float] = (0.0, 0.0, 1.0),
    stripes: float = 16,
    width: float = 1.5,
    curvature: str = "gaussian",
    curvature_limit: float | None = None,
    interval: float | None = None,
    line_color: Sequence[float] = LINE_COLOR,
    background: Sequence[float] | None = None,
    progress_bar: bool = False,
) -> np.ndarray:
    """One surface-analysis picture of a patch set or surface (1990 §4.5, Fig. 15).

    Parameters
    ----------
    source : path to a .bpt file, PatchSet, pyvista.PolyData or GBuffer
        A G-buffer from :func:`surface_gbuffer` is used as is (no tessellation or rendering).
    view : camera, default: "iso"
    mode : {"reflection", "stripes", "highlight", "isophote", "curvature", "contours"}
        Reflection lines (pseudo-highlight), zebra stripes, highlight lines, isophotes (lines
        every ``360 / stripes`` degrees of the light angle), a curvature map, or contour lines
        of height (Fig. 15 (a)); each over the shaded surface with black profiles.
    window_size, supersample, resolution
        Picture size, antialiasing, tessellation per patch.
    axis, stripes, width
        Light-line direction, lines per turn, line width (output pixels): see
        :func:`~sciviz_gbuf.filters.reflection_lines`.
    curvature : {"gaussian", "mean", "k1", "k2"}, default: "gaussian"
        Which analytic curvature the ``"curvature"`` map shows.
    curvature_limit : float, optional
        The curvature shown at full colour (symmetric: ``-limit`` blue, ``+limit`` red);
        default the 95th percentile of ``|curvature|`` in view.
    interval : float, optional
        Height step of the ``"contours"`` (default about 20 lines).
    line_color : RGB
    background : RGB, optional
        Opaque background; default transparent.
    progress_bar : bool, default: False

    Returns
    -------
    (H, W, 4) uint8 RGBA.
    """
    if mode not in MODES:
        raise InputError(f"mode: expected one of {MODES}, got {mode!r}")
    gb = (
        source
        if isinstance(source, GBuffer)
        else surface_gbuffer(
            source,
            view=view,
            resolution=resolution,
            window_size=window_size,
            supersample=supersample,
            progress_bar=progress_bar,
        )
    )
    lay = surface_layers(
        gb,
        mode=mode,
        axis=axis,
        stripes=stripes,
        width=width,
        curvature=curvature,
        curvature_limit=curvature_limit,
        interval=interval,
    )
    colour = np.clip(np.asarray(line_color, dtype=np.float32).reshape(-1)[:3], 0.0, 1.0)
    shade = (0.35 + 0.65 * lay["sh"])[..., None]
    if mode == "stripes":  # zebra: black and white stripes, lightly shaded
        img = (1.0 - lay["ink"][..., None]) * np.clip(shade + 0.15, 0.0, 1.0)
    else:
        ink = lay["ink"][..., None]
        img = (lay["rgb"] * shade) * (1.0 - ink) + colour * ink
    img = img * (1.0 - lay["pr"][..., None])
    return rgba(img, lay["alpha"], background)
