"""The band runner of the kernels (sciviz_gbuf.core.bands): every item once, errors raised after
every band ended, a pool that survives ``fork``."""

from __future__ import annotations

import multiprocessing
import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from sciviz_gbuf.core import bands as _bands


@given(n=st.integers(0, 10**6), parts=st.integers(1, 64))
@settings(max_examples=200, deadline=None)
def test_band_edges_split_the_range_into_equal_bands(n: int, parts: int) -> None:
    edges = _bands.band_edges(n, parts)
    assert len(edges) == parts + 1
    assert edges[0] == 0 and edges[-1] == n
    sizes = np.diff(edges)
    assert (sizes >= 0).all()
    assert sizes.max() - sizes.min() <= 1
    assert list(sizes) == sorted(sizes, reverse=True)  # the longer bands first


@njit(cache=True, nogil=True)
def _count_rows(r0, r1, out):
    for r in range(r0, r1):
        for c in range(out.shape[1]):
            out[r, c] += r * 3 + c


@pytest.fixture
def four_threads(monkeypatch):
    """Four bands whatever the machine has (the split, not the speed, is under test)."""
    monkeypatch.setattr(_bands, "_threads", 4)
    monkeypatch.setattr(_bands, "_pool", None)
    yield
    monkeypatch.setattr(_bands, "_pool", None)


@pytest.mark.parametrize("n", [0, 1, 7, 8, 31, 32, 33, 1000])
def test_every_row_is_computed_exactly_once(four_threads, n: int) -> None:
    out = np.zeros((n, 5), dtype=np.int64)
    _bands.run_bands(_count_rows, n, out)
    expect = np.arange(n)[:, None] * 3 + np.arange(5)[None, :]
    np.testing.assert_array_equal(out, expect)


def test_bands_run_on_several_threads(four_threads) -> None:
    seen: list[tuple[int, int, int]] = []
    barrier = threading.Barrier(4, timeout=30)

    def kernel(i0: int, i1: int, log: list) -> None:
        barrier.wait()  # only passes if four bands run at the same time
        log.append((i0, i1, threading.get_ident()))

    _bands.run_bands(kernel, 64, seen)
    assert sorted((a, b) for a, b, _ in seen) == [(0, 16), (16, 32), (32, 48), (48, 64)]
    assert len({t for _, _, t in seen}) == 4


def test_small_loops_stay_in_the_calling_thread(four_threads) -> None:
    seen: list[tuple[int, int, int]] = []
    _bands.run_bands(lambda a, b, log: log.append((a, b, threading.get_ident())), 12, seen)
    assert seen == [(0, 12, threading.get_ident())]


def test_an_error_in_a_band_is_raised_after_all_bands_ended(four_threads) -> None:
    done: list[int] = []
    lock = threading.Lock()

    def kernel(i0: int, i1: int) -> None:
        if i0 == 32:
            raise ValueError("band 3 failed")
        with lock:
            done.append(i0)

    with pytest.raises(ValueError, match="band 3 failed"):
        _bands.run_bands(kernel, 64)
    assert sorted(done) == [0, 16, 48]


def _in_child(q) -> None:
    out = np.zeros((64, 2), dtype=np.int64)
    _bands.run_bands(_count_rows, 64, out)
    q.put(int(out.sum()))


def test_a_forked_child_gets_a_pool_of_its_own(four_threads) -> None:
    out = np.zeros((64, 2), dtype=np.int64)
    _bands.run_bands(_count_rows, 64, out)  # the parent's pool exists now
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()
    proc = ctx.Process(target=_in_child, args=(q,))
    proc.start()
    total = q.get(timeout=120)
    proc.join(timeout=60)
    assert proc.exitcode == 0
    assert total == int(out.sum())


def test_threads_are_numba_num_threads(monkeypatch) -> None:
    from numba import config

    monkeypatch.setattr(_bands, "_threads", 0)
    assert _bands.threads() == config.NUMBA_NUM_THREADS  # this process's numba agrees
    for value, expect in (("3", 3), ("1", 1)):
        monkeypatch.setattr(_bands, "_threads", 0)
        monkeypatch.setenv("NUMBA_NUM_THREADS", value)
        assert _bands.threads() == expect
    monkeypatch.setattr(_bands, "_threads", 0)


def test_each_band_gets_scratch_of_its_own(four_threads) -> None:
    seen: list[tuple[int, int]] = []
    lock = threading.Lock()
    barrier = threading.Barrier(4, timeout=30)

    def kernel(i0: int, i1: int, tag: str, buf: np.ndarray) -> None:
        assert tag == "args first"
        barrier.wait()  # all four bands hold their scratch at once
        with lock:
            seen.append((i0, id(buf)))

    _bands.run_bands(kernel, 64, "args first", scratch=lambda: (np.empty(3),))
    assert sorted(i for i, _ in seen) == [0, 16, 32, 48]
    assert len({b for _, b in seen}) == 4


@njit(cache=True, nogil=True, _nrt=False)
def _count_rows_nrt_off(r0, r1, out, row):
    for r in range(r0, r1):
        for c in range(out.shape[1]):
            row[c] = r * 3 + c  # scratch from run_bands: the kernel cannot allocate
        for c in range(out.shape[1]):
            out[r, c] += row[c]


def test_kernels_without_reference_counting_run_on_scratch(four_threads) -> None:
    """numba's private ``_nrt=False`` (pinned in pyproject.toml) still compiles and computes."""
    out = np.zeros((100, 6), dtype=np.int64)
    _bands.run_bands(_count_rows_nrt_off, 100, out, scratch=lambda: (np.empty(6, np.int64),))
    np.testing.assert_array_equal(out, np.arange(100)[:, None] * 3 + np.arange(6)[None, :])
    assert _count_rows_nrt_off.targetoptions["_nrt"] is False


# Band kernels that keep numba's reference counting: their per-pixel work is in callees
# compiled on their own (a call per row), and they allocate their row buffers.
NRT_KEPT: set[str] = set()


def test_every_band_kernel_runs_without_reference_counting() -> None:
    """A serial kernel with NRT on pays an incref and a decref per pixel on each array that
    reaches an inlined helper (1.1-5x slower than the prange loop it replaced): every
    ``nogil`` kernel in a ``_*_kernels.py`` module is compiled with ``_nrt=False``."""
    import importlib
    import pkgutil

    import sciviz_gbuf

    checked, kept = [], set()
    for info in pkgutil.walk_packages(sciviz_gbuf.__path__, "sciviz_gbuf."):
        if not info.name.rsplit(".", 1)[-1].startswith("_") or not info.name.endswith("_kernels"):
            continue
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            opts = getattr(obj, "targetoptions", None)
            if getattr(obj, "__module__", None) != mod.__name__ or not opts:
                continue
            if opts.get("nogil"):
                checked.append(name)
                if opts.get("_nrt", True):
                    kept.add(name)
    assert len(checked) >= 40, checked
    assert kept == NRT_KEPT
