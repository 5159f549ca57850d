"""Discontinuity operators of Saito & Takahashi (1990 §3.1) and Nienhaus & Döllner (2003 §4.1.2).

Every operator works on a float image with an optional coverage ``mask`` and follows one border
rule: a neighbour that lies outside the image, is masked, or is not finite is replaced by the
linear extrapolation ``2X - O`` from the centre X and the opposite neighbour O (A<->H, B<->G,
C<->F, D<->E), or by X when O is missing too; the min/max normalisations (Eq. 3, 4) use X. So a
plane gives the same response up to the border as inside: the background never creates an edge
through these operators, and never hides one either (an edge between two covered pixels sees
both of them). The price: a step within one pixel of the border is extrapolated too, so the
outermost ring of pixels can over-state it. Pixels that are masked or not
finite themselves get the neutral value (0, or 1 for the 2003 intensities, which are 1 where
there is no discontinuity). The outline of the coverage against the background is the profile;
:func:`sciviz_gbuf.filters.profile_edges` draws it from the mask explicitly.

References
----------
T. Saito, T. Takahashi, "Comprehensible Rendering of 3-D Shapes", SIGGRAPH 1990.
M. Nienhaus, J. Döllner, "Edge-Enhancement - An Algorithm for Real-Time Non-Photorealistic
Rendering", WSCG 2003.
"""

from __future__ import annotations

import numpy as np

from .. import _dask as _chunks
from .. import _validate
from ..errors import InputError
from . import _stencil_kernels as _stencil

__all__ = [
    "c1_discontinuity",
    "diagonal_depth_discontinuity",
    "diagonal_normal_discontinuity",
    "normalize_gradient",
    "second_order",
    "sobel_gradient",
    "suppress_zeroth_order",
]


#: Cells read around each output cell (3x3 operators), for chunked evaluation.
RADIUS = 1


def _chunked(func, arrays: dict, **params):
    """``func`` chunk by chunk when an input is a dask array (see :mod:`sciviz_gbuf._dask`)."""
    return _chunks.map_stencil(func, arrays, halo=RADIUS, **params)


def sobel_gradient(image: np.ndarray, *, mask: np.ndarray | None = None) -> np.ndarray:
    """Sobel gradient magnitude ``g`` per pixel (1990 Eq. 1).

    ``g = (|A + 2B + C - F - 2G - H| + |C + 2E + H - A - 2D - F|) / 8``, normalised so that a
    ramp of slope ``s`` per pixel gives ``g = s`` along an axis.

    Parameters
    ----------
    image : (H, W) array
        Any real image, e.g. ``GBuffer.sz``. NaN/inf pixels are treated as masked.
    mask : (H, W) bool, optional
        Coverage; see the module docstring for the border rule.

    Returns
    -------
    (H, W) float32 >= 0; 0 on masked pixels.
    """
    if _chunks.any_dask(image, mask):
        return _chunked(sobel_gradient, {"image": image, "mask": mask})
    img = _validate.image(image)
    return _stencil.run("sobel", img, _validate.mask(mask, img.shape))


def second_order(image: np.ndarray, *, mask: np.ndarray | None = None) -> np.ndarray:
    """Second-order operator ``l = (8X - A - B - C - D - E - F - G - H) / 3`` (1990 Eq. 2).

    Positive where the centre lies above its neighbours: on ``sz`` (larger is nearer) a convex
    edge is positive and a concave one negative.

    Returns
    -------
    (H, W) float32, signed; 0 on masked pixels.
    """
    if _chunks.any_dask(image, mask):
        return _chunked(second_order, {"image": image, "mask": mask})
    img = _validate.image(image)
    return _stencil.run("second", img, _validate.mask(mask, img.shape))


def normalize_gradient(
    gradient: np.ndarray, *, k_g: float = 10.0, mask: np.ndarray | None = None
) -> np.ndarray:
    """Min/max normalisation ``p`` of a gradient image (1990 Eq. 3).

    ``p = (g - g_min) / max(g_max - g_min, k_g)`` with ``g_min``, ``g_max`` over the 3x3
    neighbourhood. The paper writes ``(g_min - g)``, i.e. the same value as a (negative)
    darkness; here it is returned as ink in [0, 1]. ``k_g`` separates discontinuities from
    large continuous changes: a gradient range below ``k_g`` is scaled down, not stretched.

    Parameters
    ----------
    gradient : (H, W) array
        ``g`` from :func:`sobel_gradient` (or any non-negative gradient image).
    k_g : float > 0, default: 10
        The 1990 Fig. 3 profile image uses ``k_g = 10`` on ``sz``.
    mask : (H, W) bool, optional

    Returns
    -------
    (H, W) float32 in [0, 1]; 0 on masked pixels.
    """
    if _chunks.any_dask(gradient, mask):
        return _chunked(normalize_gradient, {"gradient": gradient, "mask": mask}, k_g=k_g)
    g = _validate.image(gradient, "gradient")
    k = _validate.positive(k_g, "k_g")
    return _stencil.run("normalize", g, _validate.mask(mask, g.shape), k)


def suppress_zeroth_order(
    second: np.ndarray,
    gradient: np.ndarray,
    *,
    k_l: float = 2.0,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """Remove the double lines of 0th-order discontinuities from ``l`` (1990 Eq. 4).

    ``e = l`` where ``g_max <= k_l`` and ``e = l / (g_max / k_l)**2`` elsewhere, ``g_max`` being
    the largest gradient in the 3x3 neighbourhood.

    Parameters
    ----------
    second : (H, W) array
        ``l`` from :func:`second_order`.
    gradient : (H, W) array
        ``g`` from :func:`sobel_gradient` of the same image.
    k_l : float > 0, default: 2
        The gradient limit; the 1990 Fig. 3 internal-edge image uses ``k_l = 2``.
    mask : (H, W) bool, optional

    Returns
    -------
    (H, W) float32, signed like ``l``; 0 on masked pixels.
    """
    if _chunks.any_dask(second, gradient, mask):
        return _chunked(
            suppress_zeroth_order,
            {"second": second, "gradient": gradient, "mask": mask},
            k_l=k_l,
        )
    lap = _validate.image(second, "second")
    g = _validate.image(gradient, "gradient")
    if g.shape != lap.shape:
        raise InputError(f"gradient: expected shape {lap.shape} (like second), got {g.shape}")
    k = _validate.positive(k_l, "k_l")
    return _stencil.run("suppress", g, _validate.mask(mask, g.shape), k, aux=lap)


def c1_discontinuity(image: np.ndarray, *, mask: np.ndarray | None = None) -> np.ndarray:
    """The C1 discontinuity operator (1990 Eq. 9; 2003 §4.1.2, second variant).

    ``(|A-X| + 2|B-X| + |C-X| + 2|D-X| + 2|E-X| + |F-X| + 2|G-X| + |H-X|) / 8``: the mean
    absolute difference to the 8 neighbours, axis neighbours weighted twice.

    Returns
    -------
    (H, W) float32 >= 0; 0 on masked pixels.
    """
    if _chunks.any_dask(image, mask):
        return _chunked(c1_discontinuity, {"image": image, "mask": mask})
    img = _validate.image(image)
    return _stencil.run("c1", img, _validate.mask(mask, img.shape))


def diagonal_depth_discontinuity(
    depth: np.ndarray, *, mask: np.ndarray | None = None
) -> np.ndarray:
    """Depth intensity of the 2003 diagonal operator: ``I_Z = (1-|A-H|/2)^2 (1-|C-F|/2)^2``.

    ``depth`` is expected normalised like a z-buffer (differences of order 1 mean a full
    discontinuity); differences are clipped to 2 so the result stays in [0, 1]. Note the
    paper's convention: 1 means *no* discontinuity, lower values a stronger one.

    Returns
    -------
    (H, W) float32 in [0, 1]; 1 on masked pixels.
    """
    if _chunks.any_dask(depth, mask):
        return _chunked(diagonal_depth_discontinuity, {"depth": depth, "mask": mask})
    img = _validate.image(depth, "depth")
    return _stencil.run("diag_depth", img, _validate.mask(mask, img.shape))


def diagonal_normal_discontinuity(
    normal: np.ndarray, *, mask: np.ndarray | None = None
) -> np.ndarray:
    """Normal intensity of the 2003 diagonal operator: ``I_N = (A.H + C.F) / 2``.

    The mean cosine between the normals of the two diagonal pixel pairs around each pixel:
    1 on smooth surfaces, 0 across a right-angled crease.

    Parameters
    ----------
    normal : (H, W, 3) array
        Unit normals, e.g. ``GBuffer.normal``. Pixels with a non-finite component are masked.
    mask : (H, W) bool, optional

    Returns
    -------
    (H, W) float32 in [-1, 1]; 1 on masked pixels.
    """
    n = np.asarray(normal)
    if n.ndim != 3 or n.shape[2] != 3 or n.shape[0] * n.shape[1] == 0:
        raise InputError(f"normal: expected a non-empty (H, W, 3) array, got shape {n.shape}")
    if not np.issubdtype(n.dtype, np.floating):
        raise InputError(f"normal: expected a float array, got dtype {n.dtype}")
    n = np.ascontiguousarray(n, dtype=np.float32)
    m = _validate.mask(mask, n.shape[:2])
    out = np.empty(n.shape[:2], dtype=np.float32)
    _stencil.diag_normal(n, m if m is not None else np.ones((1, n.shape[1]), np.bool_), out)
    return out
