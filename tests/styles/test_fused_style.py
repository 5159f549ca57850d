"""The explorer's one-pass styles refuse inputs they would read out of bounds."""

from __future__ import annotations

import numpy as np
import pytest

from sciviz_gbuf.errors import InputError
from sciviz_gbuf.styles.fused import FUSED_MODES, fused_style


def _sphere_normals(h: int = 24, w: int = 32) -> tuple[np.ndarray, np.ndarray]:
    y, x = np.mgrid[-1 : 1 : h * 1j, -1 : 1 : w * 1j].astype(np.float32)
    r2 = x * x + y * y
    mask = r2 < 0.9
    z = np.sqrt(np.clip(1.0 - r2, 0.0, None))
    n = np.stack([x, y, z], axis=-1).astype(np.float32)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.ascontiguousarray(n), mask


@pytest.mark.parametrize("style", ["lines", "hatch"])
def test_a_style_that_reads_the_layer_refuses_none(style):
    n, m = _sphere_normals()
    with pytest.raises(InputError, match="layer"):
        fused_style(style, n, m, (0.0, 0.0, 1.0))


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"layer": np.zeros((5, 5), np.float32)}, "layer"),
        ({"emap": np.zeros((24, 32, 3), np.float32)}, "emap"),
        ({"tint": np.zeros((24, 31, 3), np.float32)}, "tint"),
        ({"tint": np.zeros((24, 32, 2), np.float32)}, "tint"),
        ({"ink": np.zeros((23, 32), np.float32)}, "ink"),
        ({"out": np.zeros((24, 32, 3), np.float32)}, "out"),
    ],
)
def test_arrays_of_another_shape_are_refused_by_name(kwargs, name):
    n, m = _sphere_normals()
    args = {"layer": np.zeros(m.shape, np.float32), **kwargs}
    with pytest.raises(InputError, match=f"^{name}:"):
        fused_style("lines", n, m, (0.0, 0.0, 1.0), **args)


def test_a_full_ink_layer_draws_ink_on_the_surface_only():
    n, m = _sphere_normals()
    assert "lines" in FUSED_MODES
    layer = np.where(m, 1.0, 0.0).astype(np.float32)
    rgb = fused_style("lines", n, m, (0.0, 0.0, 1.0), layer=layer)
    assert rgb.shape == (*m.shape, 3) and rgb.dtype == np.uint8
    blank = fused_style("lines", n, m, (0.0, 0.0, 1.0), layer=np.zeros(m.shape, np.float32))
    # Full ink darkens every covered pixel against no ink, and changes nothing off the mask.
    assert (rgb[m].astype(int).sum(-1) < blank[m].astype(int).sum(-1)).all()
    np.testing.assert_array_equal(rgb[~m], blank[~m])
