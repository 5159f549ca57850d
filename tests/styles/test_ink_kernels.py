"""The clump test on the ink pixels against whole-image scipy morphology, pixel for pixel."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage
from skimage.morphology import skeletonize

from sciviz_gbuf.styles._ink import clump_cut, clump_radius, disc

_SQUARE = np.ones((3, 3), dtype=bool)


def _reference_cut(ink: np.ndarray, width: float) -> np.ndarray | None:
    """The code it replaced: erosion, dilation and labelling of the whole image."""
    solid = np.asarray(ink) > 0.5
    se = disc(clump_radius(width))
    core = ndimage.binary_erosion(solid, se)
    if not core.any():
        return None
    clump = ndimage.binary_dilation(core, se) & solid
    labels, _ = ndimage.label(clump, structure=_SQUARE)
    cut = np.zeros(solid.shape, dtype=bool)
    pad = se.shape[0] + 2
    for i, box in enumerate(ndimage.find_objects(labels), start=1):
        win = tuple(slice(max(b.start - pad, 0), b.stop + pad) for b in box)
        region = ndimage.binary_dilation(labels[win] == i, _SQUARE)
        cut[win] |= region & ~skeletonize(solid[win])
    return cut


@settings(max_examples=120, deadline=None)
@given(
    st.integers(1, 40),
    st.integers(1, 40),
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 0.9),
    st.sampled_from([1.0, 2.0, 3.5, 6.0]),
)
def test_clump_cut_equals_whole_image_morphology(h, w, seed, density, width):
    rng = np.random.default_rng(seed)
    # lines and blobs: a few thick strokes and discs on sparse noise, NaN here and there
    ink = (rng.random((h, w)) < 0.1 * density).astype(np.float32)
    yy, xx = np.mgrid[:h, :w]
    for _ in range(rng.integers(0, 4)):
        cy, cx, rad = rng.uniform(0, h), rng.uniform(0, w), rng.uniform(0.5, 6)
        ink[(yy - cy) ** 2 + (xx - cx) ** 2 <= rad * rad] = rng.uniform(0.4, 1.0)
    ink[rng.random((h, w)) < 0.02] = np.nan
    ref = _reference_cut(ink, width)
    new = clump_cut(ink, width)
    if ref is None:
        assert new is None
    else:
        assert new is not None
        np.testing.assert_array_equal(new, ref)


def test_a_solid_disc_is_a_clump_and_a_line_is_not():
    ink = np.zeros((60, 60), np.float32)
    ink[30, 5:55] = 1.0  # a line one pixel wide
    assert clump_cut(ink, 1.0) is None
    yy, xx = np.mgrid[:60, :60]
    ink[(yy - 20) ** 2 + (xx - 20) ** 2 <= 36] = 1.0
    cut = clump_cut(ink, 1.0)
    assert cut is not None and cut[20, 14:27].sum() >= 10  # the blob is cut ...
    assert not cut[30, 40:55].any()  # ... the line far from it is not
