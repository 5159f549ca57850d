"""Local enhancement: a style applied to selected objects or cells only (Saito & Takahashi
1990 §5.2)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..core.gbuffer import GBuffer, check_gbuffer
from ..errors import InputError

__all__ = ["local_style"]


def _image(img: object, name: str, shape: tuple[int, int]) -> np.ndarray:
    a = np.asarray(img, dtype=np.float32)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=2)
    if a.ndim != 3 or a.shape != (*shape, 3):
        raise InputError(
            f"{name}: expected an RGB image of shape {(*shape, 3)} (gb.output_shape), "
            f"got {np.shape(img)}"
        )
    return a


def _ids(ids: object, kind: str, gb: GBuffer) -> np.ndarray:
    vals = np.atleast_1d(np.asarray(ids, dtype=object))
    ok = (
        vals.ndim == 1
        and vals.size > 0
        and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in vals)
    )
    if not ok:
        raise InputError(f"ids: expected a non-empty int or sequence of ints, got {ids!r}")
    out = vals.astype(np.int64)
    if (out < 0).any():
        raise InputError(f"ids: expected {kind} ids >= 0, got {ids!r}")
    if kind == "object":
        n = len(gb.object_names) or int(gb.object_id.max()) + 1
        if (out >= n).any():
            raise InputError(f"ids: the scene has objects 0..{n - 1}, got {ids!r}")
    return out


def local_style(
    styled: np.ndarray,
    base: np.ndarray,
    gb: GBuffer,
    *,
    ids: int | Sequence[int],
    kind: str = "object",
) -> np.ndarray:
    """Use ``styled`` on the selected objects (or cells) and ``base`` elsewhere (1990 §5.2).

    Saito & Takahashi enhance only the part of a scene the viewer should attend to, selected
    by the object id buffer. The weight of ``styled`` is the fraction of each output pixel's
    ``k x k`` buffer samples (``k = gb.supersample``) that show a selected id, so the border of
    the selection is antialiased like the silhouettes::

        out = (1 - coverage) * base + coverage * styled

    Parameters
    ----------
    styled, base : (H, W, 3) or (H, W) float array at ``gb.output_shape``
        E.g. a :func:`~sciviz_gbuf.styles.tone.gooch` image and a plain shade of the same
        G-buffer; grey images are broadcast to RGB.
    gb : GBuffer
        The G-buffer both images were made from.
    ids : int or sequence of ints
        Selected object ids (``gb.object_id``, 0 .. number of objects - 1) or cell ids
        (``gb.cell_id``; a cell id selects that cell in every object).
    kind : {"object", "cell"}, default: "object"

    Returns
    -------
    (H, W, 3) float32.
    """
    check_gbuffer(gb)
    if kind not in ("object", "cell"):
        raise InputError(f"kind: expected 'object' or 'cell', got {kind!r}")
    shape = gb.output_shape
    sty = _image(styled, "styled", shape)
    bas = _image(base, "base", shape)
    sel = _ids(ids, kind, gb)
    idimg = gb.object_id if kind == "object" else gb.cell_id
    inside = gb.mask & np.isin(idimg, sel)
    # Box-filtered coverage of the selection (the downsample's float path), not the id of the
    # centre sample: partly selected pixels mix the two styles.
    weight = gb.downsample(inside.astype(np.float32))[..., None]
    # (1 - w) base + w styled, not base + w (styled - base): exact at w = 0 and w = 1
    out = (np.float32(1.0) - weight) * bas + weight * sty
    return out.astype(np.float32, copy=False)
