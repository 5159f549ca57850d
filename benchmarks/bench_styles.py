"""Benchmark: NPR styles on a kept G-buffer, against re-rendering with PyVista.

Run from the project root with the project's venv active::

    python benchmarks/bench_styles.py               # 1024x768 output, 2x supersampled (~1 min)
    python benchmarks/bench_styles.py --size 512x384 --supersample 1
    python benchmarks/bench_styles.py --size 1024x1024 --supersample 1   # web explorer update

The 1990 paper's promise: with the G-buffers kept, a new style or parameter costs only image
processing. Per style, the time to make one picture from the kept G-buffer of PyVista's nut is
compared with the time PyVista takes to re-render the same mesh and take a plain screenshot of
the same size (same run, warm, best of ``--repeats``); the capture itself is listed too. The
styles are also timed without their edges, and the edge filters alone, to tell the tone work
from the edge work.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

# Headless: VTK's default window class would try X first; must precede the sciviz_gbuf import.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pyvista as pv

import sciviz_gbuf as sg
from sciviz_gbuf import styles
from sciviz_gbuf.recipes import named_view_camera
from sciviz_gbuf.recipes.npr import with_section_uv
from sciviz_gbuf.styles.registry import STYLES


def best(fn: Callable[[], object], repeats: int) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", default="1024x768", help="output WxH")
    ap.add_argument("--supersample", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    k = args.supersample
    nut = sg.datasets.load_nut()
    cam = named_view_camera(nut.points, "iso", aspect=w / h)

    def screenshot():
        pl = pv.Plotter(off_screen=True, window_size=(w, h))
        pl.add_mesh(nut, color="lightgrey", smooth_shading=True)
        pl.camera_position = cam
        pl.screenshot(None, return_img=True)
        pl.close()

    t_shot = best(screenshot, args.repeats)
    t_cap = best(lambda: sg.capture(nut, window_size=(w, h), camera=cam, supersample=k), 1)
    gb = sg.capture(nut, window_size=(w, h), camera=cam, supersample=k)
    sections = with_section_uv(gb)

    # Every style of the registry that draws from a kept G-buffer, at its defaults (the
    # issue's goal: each <= 0.5x the re-render), then variants and the parts alone.
    def drawn(draw, buffers):
        return lambda: draw(buffers)

    cases = {
        f"style {name}": drawn(st.draw, sections if name == "drawing" else gb)
        for name, st in STYLES.items()
        if st.draw is not None
    }
    cases |= {
        "gooch (+ edge map)": lambda: styles.gooch(gb),
        "gooch, no edges": lambda: styles.gooch(gb, edges=False),
        "toon, 3 levels (+ edges)": lambda: styles.toon(gb),
        "toon, 3 levels, no edges": lambda: styles.toon(gb, edges=False),
        "toon, smoothed": lambda: styles.toon(gb, smooth=0.12),
        "hatch, screen space": lambda: styles.hatch(gb),
        "hatch, screen space, no edges": lambda: styles.hatch(gb, edges=False),
        "edge_map alone": lambda: sg.filters.edge_map(gb),
        "profile_edges alone": lambda: sg.filters.profile_edges(gb),
        "line_drawing shu (sections)": lambda: styles.line_drawing(sections, combo="shu"),
        "photocopy x5 of the output": lambda: styles.photocopy(
            styles.line_drawing(sections, combo="shu"), copies=5, seed=0
        ),
    }
    print(f"nut, {w}x{h} output, supersample {k} ({w * k}x{h * k} buffers); best of {args.repeats}")
    print(f"{'step':<34} {'s':>8} {'vs PyVista re-render + screenshot':>36}")
    print(f"{'PyVista re-render + screenshot':<34} {t_shot:8.3f} {1.0:36.2f}")
    print(f"{'capture (once)':<34} {t_cap:8.3f} {t_cap / t_shot:36.2f}")
    for name, fn in cases.items():
        t = best(fn, args.repeats)
        goal = "  (goal <= 0.5)" if name.startswith("style ") else ""
        print(f"{name:<34} {t:8.3f} {t / t_shot:36.2f}{goal}")


if __name__ == "__main__":
    main()
