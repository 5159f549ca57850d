"""Benchmark: the edge functions at the sizes of issue "Real-time edge enhancement", in MPix/s.

Run from the project root with the project's venv active::

    python benchmarks/bench_edges.py              # ~1 min
    python benchmarks/bench_edges.py --repeats 30

What is measured, warm (one untimed call first), best and median of ``--repeats`` calls:

* ``edge_map`` (both operators) on the nut captured at 1024x768 with ``supersample=2``
  (2048x1536 buffers); ``profile_edges``, ``crease_edges``, ``internal_edges`` on the nut
  captured at 2048x2048. MPix/s counts the buffer's pixels, covered or not.
* ``kernel``: the numba pass alone on reused output (``_edge_kernels.edge_pass``), without the
  cleaning, dilation, box filter and the result's allocation.
* ``reference``: the per-pixel kernels it replaced (``pair_edge_kernel`` for the three line
  functions, ``edge_map_kernel`` + ``pair_edge_kernel`` for the edge map, which needs both),
  same buffers, same run; the fused pass gives the same bits (tests/filters/test_edge_pass.py).

The result of every public call is a new array; on a VM that hands free memory back to its
host, its first touch costs 1-2 ms/MB (16 MB at 2048^2), which the median shows more than the
best. Goals of the issue: edge_map >= 300 MPix/s, the three line functions >= 500 MPix/s.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np

import sciviz_gbuf as sg
from sciviz_gbuf.filters import _edge_kernels as K
from sciviz_gbuf.filters import edges as E

GOALS = {"edge_map": 300.0, "profile_edges": 500.0, "crease_edges": 500.0, "internal_edges": 500.0}


def timed(fn, repeats: int) -> tuple[float, float]:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    nut = sg.datasets.load_nut()
    ss2 = sg.capture(nut, window_size=(1024, 768), supersample=2)
    big = sg.capture(nut, window_size=(2048, 2048))
    jump, crease = E.DEFAULT_DEPTH_JUMP, E.DEFAULT_CREASE_ANGLE

    def kernels(gb, mode):
        ins = (*E._kernel_inputs(gb), *E._camera_terms(gb))
        h, w = gb.shape
        a, b = np.empty((h, w), np.float32), np.empty((h, w), np.float32)
        em = np.empty((h, w, 4), np.float32)
        none = np.zeros((1, 1), np.float32)

        def fused():
            K.edge_pass(*ins, jump, crease, 0.5 * crease, True, mode, a, b, 0.0, 0.0, none)

        def reference():
            K.pair_edge_kernel(*ins, jump, crease, 0.5 * crease, True, a, b)
            if mode != K.MODE_PAIRS:
                K.edge_map_kernel(
                    *ins[:6], jump, crease, 0.5 * crease, mode == K.MODE_C1, em
                )  # (no inv_w)

        return fused, reference

    cases = [
        ("edge_map", "diagonal", ss2, lambda: E.edge_map(ss2), K.MODE_DIAGONAL),
        ("edge_map", "c1", ss2, lambda: E.edge_map(ss2, operator="c1"), K.MODE_C1),
        ("profile_edges", "", big, lambda: E.profile_edges(big), K.MODE_PAIRS),
        ("crease_edges", "", big, lambda: E.crease_edges(big), K.MODE_PAIRS),
        ("internal_edges", "", big, lambda: E.internal_edges(big), K.MODE_PAIRS),
    ]
    print(f"nut; best / median of {args.repeats} warm calls, MPix/s of the buffer")
    print(f"{'function':<24} {'buffer':>10} {'best':>7} {'median':>7} {'kernel':>7} "
          f"{'reference':>10} {'speed-up':>9} {'goal':>6}")  # fmt: skip
    for name, op, gb, call, mode in cases:
        h, w = gb.shape
        mpix = h * w / 1e6
        best, med = timed(call, args.repeats)
        fused, ref = kernels(gb, mode)
        k_best, _ = timed(fused, args.repeats)
        r_best, _ = timed(ref, max(3, args.repeats // 3))
        label = f"{name}({op})" if op else name
        print(
            f"{label:<24} {w:>4}x{h:<5} {mpix / best:7.0f} {mpix / med:7.0f} {mpix / k_best:7.0f} "
            f"{mpix / r_best:10.0f} {r_best / k_best:8.1f}x {GOALS[name]:6.0f}"
        )
    print("kernel = edge_pass alone; reference = the per-pixel kernels it replaced (same bits)")


if __name__ == "__main__":
    main()
