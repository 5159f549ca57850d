"""Benchmark: how long one control change of the explorer takes to make its new picture.

Run from the project root with the project's venv active::

    python benchmarks/bench_explorer.py               # nut at 1024x1024, every 3-D control
    python benchmarks/bench_explorer.py --size 800 600 --repeats 10

What is measured: an :class:`~sciviz_gbuf.apps.explorer.Explorer` of PyVista's nut (the
camera fixed, so the G-buffer is captured once), and for every style of the explorer and
every control of the 3-D view, ``render_image`` after setting the control to a new value
(``--repeats`` different values in a row, the median and the worst reported): what the web
explorer computes between a slider's message and the new frame (its JPEG encoding and the
websocket are not included). Layers the control does not change come from the explorer's
cache, as in use. One warm-up round first (numba caches, the allocator's first touch of
memory). The goal of issue "Real-time edge enhancement": every control <= 50 ms at 1024^2.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import sciviz_gbuf as sg
from sciviz_gbuf.apps.explorer import Explorer
from sciviz_gbuf.styles import styles_for

GOAL_MS = 50.0


def controls(n: int) -> dict[str, list[object]]:
    """``n`` successive values of every 3-D control (none repeats the previous one)."""
    return {
        "crease_angle": [20.0 + 3.0 * i for i in range(n)],
        "depth_jump": [0.5 + 0.2 * i for i in range(n)],
        "width": [1.0 + 0.25 * (i % 4) for i in range(1, n + 1)],
        "light_azimuth": [100.0 + 7.0 * i for i in range(n)],
        "light_elevation": [20.0 + 4.0 * i for i in range(n)],
        "contour_interval": [0.02 + 0.005 * i for i in range(n)],
        "bands": [2 + i % 6 for i in range(n)],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, nargs=2, default=(1024, 1024))
    ap.add_argument("--repeats", type=int, default=10)
    args = ap.parse_args()
    ex = Explorer(sg.datasets.load_nut(), window_size=tuple(args.size))
    styles = styles_for("explore")
    table = controls(args.repeats)
    for style in styles:  # warm-up round
        for name, values in table.items():
            ex.render_image({"style": style, name: values[-1]})
    print(f"explorer of the nut at {args.size[0]}x{args.size[1]}, median / worst of "
          f"{args.repeats} changes (ms); goal <= {GOAL_MS:g} ms")  # fmt: skip
    print(f"{'control':<17}" + "".join(f"{s:>15}" for s in styles))
    worst_median = 0.0
    for name, values in table.items():
        cells = []
        for style in styles:
            ex.render_image({"style": style, name: values[-1]})
            times = []
            for v in values:
                t0 = time.perf_counter()
                ex.render_image({"style": style, name: v})
                times.append(1e3 * (time.perf_counter() - t0))
            med = statistics.median(times)
            worst_median = max(worst_median, med)
            cells.append(f"{med:6.1f} /{max(times):6.1f}")
        print(f"{name:<17}" + "".join(f"{c:>15}" for c in cells))
    verdict = "meets" if worst_median <= GOAL_MS else "misses"
    print(f"largest median: {worst_median:.1f} ms ({verdict} the goal)")


if __name__ == "__main__":
    main()
