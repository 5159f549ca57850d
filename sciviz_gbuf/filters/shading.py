"""Shading from G-buffer normals: Saito & Takahashi's ``sh`` image (1990 §4.2, Fig. 9)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _validate
from ..errors import InputError

__all__ = ["lambert", "unit_light"]


def unit_light(light: Sequence[float]) -> np.ndarray:
    """The direction towards the light, normalised, as float32 ``(3,)`` (the one
    :func:`lambert` shades with), or an :class:`InputError` naming ``light``."""
    try:
        lv = np.asarray(light, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        lv = np.zeros(0)
    if lv.size != 3 or not np.isfinite(lv).all() or not np.linalg.norm(lv) > 0:
        raise InputError(
            f"light: expected a finite non-zero 3-vector, got {_validate.brief(light)}"
        )
    return (lv / np.linalg.norm(lv)).astype(np.float32)


def lambert(
    normal: np.ndarray,
    *,
    light: Sequence[float] = (0.0, 0.0, 1.0),
    ambient: float = 0.0,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """Diffuse (Lambertian) shade ``ambient + (1 - ambient) * max(0, N . L)``.

    Parameters
    ----------
    normal : (H, W, 3) array
        Unit normals, e.g. ``GBuffer.normal`` (eye space) or ``GBuffer.world_normal()``.
    light : 3 floats, default: (0, 0, 1)
        Direction towards the light, in the normals' frame; normalised here. The default is a
        headlight for eye-space normals.
    ambient : float in [0, 1], default: 0
        Shade of surfaces turned away from the light.
    mask : (H, W) bool, optional
        Pixels to shade; NaN elsewhere. Pixels whose normal is NaN are NaN too.

    Returns
    -------
    (H, W) float32 in [0, 1]
        1 is fully lit (a shade, not ink).
    """
    n = np.asarray(normal)
    if n.ndim != 3 or n.shape[2] != 3 or not np.issubdtype(n.dtype, np.number):
        raise InputError(f"normal: expected an (H, W, 3) array of numbers, got {n.dtype} {n.shape}")
    lv = unit_light(light)
    ambient = _validate.unit_interval(ambient, "ambient")
    m = _validate.mask(mask, n.shape[:2])
    n = n.astype(np.float32, copy=False)
    # N.L summed component by component in float32 (as the styles' one-pass kernels sum it)
    ndl = n[..., 0] * lv[0]
    ndl += n[..., 1] * lv[1]
    ndl += n[..., 2] * lv[2]
    shade = np.maximum(ndl, np.float32(0.0))
    shade = np.float32(ambient) + np.float32(1.0 - ambient) * shade
    if m is not None:
        shade = np.where(m, shade, np.float32(np.nan))
    return np.clip(shade, 0.0, 1.0).astype(np.float32, copy=False)
