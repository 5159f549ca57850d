"""The generalisation's removal of small rings and specks (``contour_lines(generalize=True)``):
an attribute opening of the ink, so no threshold of the ink shows specks or short dashes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from sciviz_gbuf.filters import _contour_generalize, contour_lines

EIGHT = np.ones((3, 3), bool)


def opening_by_definition(ink, cut, min_ring, min_stub):
    """Each pixel: ``min(ink, T)`` for the highest level ``T`` at which its component of
    ``ink >= T`` is large, level by level with ``ndimage.label`` (the definition, slowly)."""
    out = np.zeros_like(ink)
    done = np.zeros(ink.shape, bool)
    for level in np.unique(ink[ink > 0])[::-1]:
        labels, _ = ndimage.label(ink >= level, EIGHT)
        for k, box in enumerate(ndimage.find_objects(labels), 1):
            extent = max(box[0].stop - box[0].start, box[1].stop - box[1].start)
            here = labels == k
            if extent > min_ring or (cut[here].any() and extent > min_stub):
                new = here & ~done
                out[new] = np.minimum(ink[new], level)
                done |= here
    return out


def test_opening_is_its_definition():
    rng = np.random.default_rng(5)
    for _ in range(150):
        h, w = rng.integers(2, 16, 2)
        ink = np.round(rng.random((h, w)) * (rng.random((h, w)) < 0.55) * 4) / 4  # ties
        ink = ink.astype(np.float32)
        cut = rng.random((h, w)) < 0.1
        ring, stub = float(rng.integers(0, 7)), float(rng.integers(0, 3))
        got = _contour_generalize.ring_opening(ink, cut, ring, stub)
        assert np.array_equal(got, opening_by_definition(ink, cut, ring, stub)), (ink, cut)


def small_components(ink: np.ndarray, threshold: float, largest: int = 6) -> int:
    """Components of ``ink > threshold`` of at most ``largest`` px away from the grid's edge."""
    labels, n = ndimage.label(ink > threshold, EIGHT)
    if n == 0:
        return 0
    sizes = np.bincount(labels.ravel())[1:]
    edge = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    inner = np.ones(n, bool)
    inner[edge[edge > 0] - 1] = False
    return int(np.sum((sizes <= largest) & inner))


def crowded_minors(seed: int = 2) -> np.ndarray:
    """A slope whose lines (interval 1) lie 3-4.5 px apart with a little noise: minors fade
    in and out where they crowd (Eq. 15, dense spacing 4 px)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:120, 0:160].astype(np.float64)
    slope = 1.0 / (3.75 + 0.75 * np.sin(x / 17.0) * np.cos(y / 23.0))  # height per px
    z = np.cumsum(slope, axis=1) + 0.3 * np.sin(y / 9.0)
    z += ndimage.gaussian_filter(rng.standard_normal(z.shape), 1.5) * 0.1
    return z.astype(np.float32)


OPTIONS = {"interval": 1.0, "major_interval": 5.0, "width": 1.0, "major_width": 2.0,
           "dense_spacing": 4.0}  # fmt: skip


def test_fading_minors_show_no_dashes_at_any_threshold():
    """Where the minors fade they are faint along whole pieces: at no ink threshold do short
    isolated pieces appear; the same lines without the opening (only the hysteresis at the
    lowest ink) show many at the visible thresholds (the measure can fail)."""
    z = crowded_minors()
    ink = contour_lines(z, **OPTIONS, generalize=True)
    thresholds = (0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9)
    assert max(small_components(ink, t) for t in thresholds) == 0
    assert ((ink > 0.05) & (ink < 0.9)).mean() > 0.05  # lines do fade here
    # hysteresis at the lowest ink only (what the opening does at T -> 0)
    raw = contour_lines(z, **OPTIONS, generalize=True, min_ring=0.0)
    labels, _ = ndimage.label(raw > 0, EIGHT)
    boxes = ndimage.find_objects(labels)
    small = np.array([False] + [max(b[0].stop - b[0].start, b[1].stop - b[1].start) <= 6
                                for b in boxes])  # fmt: skip
    hysteresis = np.where(small[labels], 0.0, raw)
    assert sum(small_components(hysteresis, t) for t in (0.2, 0.3, 0.5)) > 10


def test_majors_are_untouched_and_lines_keep_their_ink():
    """Lines longer than the ring size keep their ink: the majors exactly (never faded, one
    long component at each of their levels), and the ink the opening takes is a small part."""
    z = crowded_minors()
    ink = contour_lines(z, **OPTIONS, generalize=True)
    raw = contour_lines(z, **OPTIONS, generalize=True, min_ring=0.0)
    assert (ink <= raw).all()  # an opening only lowers
    majors = contour_lines(z, interval=5.0, width=2.0, generalize=True, min_ring=0.0)
    on_major = majors >= 0.999
    assert on_major.sum() > 500
    assert np.array_equal(ink[on_major], raw[on_major])
    assert ink.sum() > 0.9 * raw.sum()


@pytest.mark.parametrize("tile_cols", [10**6, 13])
def test_strips_and_tiles_give_the_same_pixels(monkeypatch, tile_cols):
    """The smoothing and the ring opening by strips of 9 rows, or tiles of 9 x 13 cells
    (read with their reach around them), draw the pixels of one piece."""
    z = crowded_minors(seed=3)
    whole = contour_lines(z, **OPTIONS, generalize=True)
    monkeypatch.setattr(_contour_generalize, "STRIP_ROWS", 9)
    monkeypatch.setattr(_contour_generalize, "TILE_COLS", tile_cols)
    monkeypatch.setattr(_contour_generalize, "RING_TILE_COLS", tile_cols)
    assert np.array_equal(contour_lines(z, **OPTIONS, generalize=True), whole)


@pytest.mark.parametrize("min_ring", [0.0, 3.0, 12.0])
def test_rings_up_to_min_ring_go_whatever_their_ink(min_ring):
    """Rings of a bump field: every ring whose box is at most ``min_ring`` px goes, at any
    ink; larger ones keep their ink."""
    y, x = np.mgrid[0:90, 0:90].astype(np.float32)
    z = np.zeros_like(x)
    for cy, cx, r in ((20, 20, 1.5), (20, 60, 3.0), (60, 25, 6.0), (62, 65, 12.0)):
        z += np.maximum(0.0, r - np.hypot(x - cx, y - cy)).astype(np.float32)
    ink = contour_lines(z, interval=1.0, width=1.0, generalize=True, min_ring=min_ring)
    raw = contour_lines(z, interval=1.0, width=1.0, generalize=True, min_ring=0.0)
    labels, _ = ndimage.label(raw > 0, EIGHT)
    gone = kept = 0
    for k, box in enumerate(ndimage.find_objects(labels), 1):
        extent = max(box[0].stop - box[0].start, box[1].stop - box[1].start)
        here = labels == k
        if extent <= min_ring:
            assert ink[here].max() == 0.0, extent
            gone += 1
        else:  # its darkest pixel keeps its ink
            assert ink[here].max() == raw[here].max(), extent
            kept += raw[here].max() > 0.5
    assert kept >= (3 if min_ring < 6 else 1)  # the rings of the larger bumps stay
    assert gone >= (0 if min_ring == 0 else 1)


def test_chunked_lines_are_the_same_pixels():
    """The opening is decided within ``min_ring`` cells of a pixel: chunk by chunk with the
    halo of :func:`~sciviz_gbuf.filters.contours.contour_halo`, the same pixels."""
    da = pytest.importorskip("dask.array")
    z = crowded_minors(seed=4)
    whole = contour_lines(z, **OPTIONS, generalize=True)
    lazy = contour_lines(da.from_array(z, chunks=(17, 29)), **OPTIONS, generalize=True)
    assert np.array_equal(lazy.compute(), whole)


# -- band heights: colour bands that agree with the generalised lines --------------------------
def bumps_across_a_band_edge():
    """A slope rising through the 100 m band edge, with small flat knolls on the low side just
    above the edge (3 and 5 px square terraces at 101 m: smoothing keeps them, as it keeps
    any flat terrace) and a large bump crossing it widely (17 px)."""
    y, x = np.mgrid[0:80, 0:120].astype(np.float64)
    z = 80.0 + 0.2 * x  # 100 m at column 100
    z += np.maximum(0.0, 1.0 - np.hypot(x - 60, y - 40) / 12.0) * (120.0 - 92.0)
    z[19:22, 29:32] = 101.0
    z[53:58, 28:33] = 101.0
    return z.astype(np.float32)


def band_islands(band: np.ndarray) -> list[int]:
    """Sizes (longer bounding-box side) of the 8-connected pieces of each band."""
    out = []
    for v in np.unique(band):
        labels, _ = ndimage.label(band == v, EIGHT)
        out += [max(b[0].stop - b[0].start, b[1].stop - b[1].start)
                for b in ndimage.find_objects(labels)]  # fmt: skip
    return out


def test_band_heights_drop_the_islands_the_lines_drop():
    from sciviz_gbuf.filters import band_heights

    z = bumps_across_a_band_edge()
    raw = np.floor(z / 100.0)
    got = np.floor(band_heights(z, band_interval=100.0, min_ring=6.0) / 100.0)
    # the bumps of radius 2 and 3 px make islands of the upper band; the 12 px one stays
    assert sorted(band_islands(raw))[:2] <= [6, 6] and len(band_islands(raw)) == 5
    assert len(band_islands(got)) == 3, band_islands(got)
    assert got[40, 60] == 1 and got[20, 30] == 0 and got[55, 30] == 0
    # away from the bumps the band edge is where it was (the plane is not moved)
    np.testing.assert_array_equal(got[:, 90:], raw[:, 90:])
    # the lines drop the same rings: no major ink on the small bumps
    ink = contour_lines(z, interval=2.0, major_interval=100.0, width=1.0, major_width=2.0,
                        c_dense=1.0, generalize=True)  # fmt: skip
    majors = contour_lines(z, levels=[100.0], width=2.0, generalize=True, min_ring=6.0)
    assert majors[15:26, 25:36].max() == 0.0 and majors[48:63, 22:39].max() == 0.0
    assert majors[25:56, 45:76].max() > 0.9 and ink.max() > 0.9
    # band edges run along the generalised major line: within 1 px of its ink
    edge = (np.diff(got, axis=1) != 0)[:, :]
    rows, cols = np.nonzero(edge)
    line = majors >= 0.5
    near = ndimage.binary_dilation(line, np.ones((3, 3), bool))
    assert near[rows, cols].mean() > 0.95 and near[rows, cols + 1].mean() > 0.95


def test_band_heights_by_levels_and_chunks_are_the_same():
    da = pytest.importorskip("dask.array")
    from sciviz_gbuf.filters import band_heights

    z = bumps_across_a_band_edge()
    a = band_heights(z, band_interval=100.0)
    b = band_heights(z, band_levels=[0.0, 100.0, 200.0])
    np.testing.assert_array_equal(a, b)
    lazy = band_heights(da.from_array(z, chunks=(23, 31)), band_interval=100.0)
    np.testing.assert_array_equal(lazy.compute(), a)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({}, "band_interval"),
        ({"band_interval": 10.0, "band_levels": [1.0]}, "band_interval"),
        ({"band_interval": -1.0}, "band_interval"),
        ({"band_levels": [1.0, float("nan")]}, "band_levels"),
        ({"band_interval": 10.0, "min_ring": -1.0}, "min_ring"),
    ],
)
def test_band_heights_checks_its_options(kwargs, match):
    from sciviz_gbuf.errors import InputError
    from sciviz_gbuf.filters import band_heights

    with pytest.raises(InputError, match=match):
        band_heights(np.zeros((8, 8), np.float32), **kwargs)


# ------------------------------------- band islands: run-length kernel vs scipy's labelling
def _rough(rng, shape, noise=3.0):
    z = np.cumsum(np.cumsum(rng.standard_normal(shape), 0), 1)
    return (z + noise * rng.standard_normal(shape)).astype(np.float32)


def _islands_by_labelling(z, valid, index, ring):
    """The band islands by definition: ``ndimage.label`` of each band, boxes by
    ``find_objects``, no cell on the grid's edge or beside nodata."""
    band = np.where(valid, index(np.where(valid, z, 0.0)), np.iinfo(np.int64).min)
    cut = _contour_generalize.cut_cells(valid)
    small = np.zeros(z.shape, bool)
    for v in np.unique(band[valid]):
        labels, _ = ndimage.label(band == v, EIGHT)
        for k, box in enumerate(ndimage.find_objects(labels), 1):
            here = labels == k
            extent = max(box[0].stop - box[0].start, box[1].stop - box[1].start)
            if extent <= ring and not cut[here].any():
                small |= here
    return small


def _filled_from_a_nearest_cell(got, s, valid, small, reach):
    """Every island cell took the height of a valid cell outside the islands at the least
    distance from it among those within ``reach`` cells along each axis (the reference's
    distance transform breaks ties otherwise), or kept its own with none there."""
    yy, xx = np.mgrid[: s.shape[0], : s.shape[1]]
    outside = valid & ~small
    for i, j in zip(*np.nonzero(small), strict=True):
        near = outside & (abs(yy - i) <= reach) & (abs(xx - j) <= reach)
        if not near.any():
            if got[i, j] != s[i, j]:
                return False
            continue
        d2 = (yy - i) ** 2 + (xx - j) ** 2
        ring = near & (d2 == d2[near].min())
        if not np.isin(got[i, j], s[ring]):
            return False
    return True


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("ring", [3.0, 6.0, 9.0])
def test_band_islands_kernel_equals_the_labelling(seed, ring):
    """The run-length labelling finds the islands that a labelling per band with
    ``scipy.ndimage`` finds (rough heights, scattered nodata, a lake, band edges), and each
    island takes the height of one of its nearest cells outside; the reference changes the
    same cells."""
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(5, 90)), int(rng.integers(5, 90)))
    z = _rough(rng, shape)
    valid = rng.random(shape) > 0.03
    valid[shape[0] // 3 : shape[0] // 2, shape[1] // 4 : shape[1] // 2] = False
    s = np.where(valid, z, np.nan).astype(np.float32)
    edges = np.array([-20.0, 0.0, 3.0, 10.0])
    for kwargs, spec, index in (
        ({"step": 5.0, "base": 1.5}, (np.float32(1.5), np.float32(5.0), np.empty(0)),
         lambda h: np.floor((h - 1.5) / 5.0).astype(np.int64)),
        ({"edges": edges}, (np.float32(0.0), np.float32(1.0), edges),
         lambda h: np.searchsorted(edges, h, side="right")),
    ):  # fmt: skip
        small = np.zeros(shape, bool)
        _contour_generalize.small_islands(s, valid, spec, ring, small)
        np.testing.assert_array_equal(small, _islands_by_labelling(s, valid, index, ring))
        got = _contour_generalize.band_heights(z, valid, ring, **kwargs)
        ref = _contour_generalize.band_heights_reference(z, valid, index, ring)
        np.testing.assert_array_equal(np.isnan(got), ~valid)
        # the same cells change (but for islands chained farther than the kernel's reach)
        assert (valid & (got != s) != (valid & (ref != s))).sum() <= 0.02 * small.sum()
        assert _filled_from_a_nearest_cell(got, s, valid, small, int(np.ceil(ring)) + 1)


def test_band_islands_in_strips_are_the_islands_of_the_whole(monkeypatch):
    rng = np.random.default_rng(11)
    z = _rough(rng, (160, 70))
    valid = rng.random(z.shape) > 0.02
    whole = _contour_generalize.band_heights(z, valid, 6.0, step=4.0)
    assert (valid & (whole != z)).sum() > 50  # islands were filled
    monkeypatch.setattr(_contour_generalize, "STRIP_ROWS", 9)
    np.testing.assert_array_equal(_contour_generalize.band_heights(z, valid, 6.0, step=4.0), whole)


def test_ink_order_is_a_stable_sort_by_decreasing_ink():
    """The radix sort of the ring opening: the order of ``argsort(-ink, kind="stable")`` over
    the pixels with ink > 0 (ties, zeros, negative zero, NaN and infinity among them)."""
    from sciviz_gbuf.filters import _contour_kernels

    rng = np.random.default_rng(2)
    ink = rng.choice(np.float32([0.0, -0.0, 0.25, 0.5, 1.0, np.nan, np.inf, 1e-30]), 5000)
    ink[::7] = rng.random(ink[::7].size).astype(np.float32)
    node = np.empty(ink.size, np.int32)
    order = np.empty(ink.size, np.int32)
    m = _contour_kernels.ink_order(ink.view(np.uint32), node, order, np.empty(ink.size, np.int32),
                                   np.empty((4, 257), np.int64))  # fmt: skip
    inked = np.flatnonzero(ink > 0)
    expect = inked[np.argsort(-ink[inked], kind="stable")]
    assert m == inked.size
    np.testing.assert_array_equal(order[:m], expect)
    np.testing.assert_array_equal(node[expect], np.arange(m))
    assert (node[ink <= 0] == -1).all() and (node[np.isnan(ink)] == -1).all()
