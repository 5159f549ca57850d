"""Benchmark: every filter and style at the largest parameters its bounds allow, on a small input.

The acceptance of issue 20 asks that a filter with parameters at their bounds returns (or
refuses) within a second on small inputs; this measures it (tests only check the outcome).

Run from the project root with the project's venv active::

    python benchmarks/bench_bounds.py              # 64x64 arrays, 64x48 capture (supersample 2)
    python benchmarks/bench_bounds.py --side 128 --supersample 8

Each row is one call (after one untimed warm-up call of the same filter, so numba's compile or
cache load is not counted): the filter, the parameter at its bound, the bound and the best of
``--repeats`` wall-clock times. ``--capture-memory`` adds the peak RSS per buffer pixel of a
capture (what ``capture.BYTES_PER_PIXEL`` is rounded up from), in a child process per size.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

import numpy as np
import pyvista as pv

import sciviz_gbuf.filters as F
from sciviz_gbuf._validate import LIMITS
from sciviz_gbuf.core.capture import capture
from sciviz_gbuf.errors import InputError
from sciviz_gbuf.styles import STYLES, photocopy

W = LIMITS["line_width"]
K = LIMITS["supersample"]


def cases(field: np.ndarray, gb) -> list[tuple[str, str, str, object]]:
    """(filter, parameter, bound, thunk) at the largest allowed values."""
    lv = int(LIMITS["levels"])
    span = float(field.max() - field.min())
    styles = {n: s.draw for n, s in STYLES.items() if s.draw is not None}
    return [
        ("edge_map", "width", f"{W:g}", lambda: F.edge_map(gb, width=W)),
        ("profile_edges", "width", f"{W:g}", lambda: F.profile_edges(gb, width=W)),
        ("internal_edges", "width", f"{W:g}", lambda: F.internal_edges(gb, width=W)),
        ("crease_edges", "width", f"{W:g}", lambda: F.crease_edges(gb, width=W)),
        ("id_edges", "width", f"{W:g}", lambda: F.id_edges(gb, width=W)),
        (
            "contour_lines",
            "width, major_width",
            f"{W * K:g}",
            lambda: F.contour_lines(
                field, interval=0.1, major_interval=1.0, width=W * K, major_width=W * K
            ),
        ),
        (
            "contour_lines",
            "levels",
            f"{lv}",
            lambda: F.contour_lines(field, levels=np.linspace(field.min(), field.max(), lv)),
        ),
        (
            "contour_polylines",
            "levels",
            f"{lv}",
            lambda: F.contour_polylines(field, levels=np.linspace(field.min(), field.max(), lv)),
        ),
        (
            "contour_polylines",
            "levels (16x16 corner)",
            f"{lv}",
            lambda: F.contour_polylines(
                field[:16, :16],
                levels=np.linspace(field[:16, :16].min(), field[:16, :16].max(), lv),
            ),
        ),
        (
            "contour_polylines",
            "interval",
            f"{lv} levels",
            lambda: F.contour_polylines(field, interval=span / (lv - 1)),
        ),
        (
            "hatching",
            "spacing, width",
            f"{LIMITS['spacing'] * K:g}, {W * K:g}",
            lambda: F.hatching(field, spacing=LIMITS["spacing"] * K, width=W * K),
        ),
        (
            "color_bands",
            "levels",
            f"{int(LIMITS['bands'])}",
            lambda: F.color_bands(
                field, levels=np.linspace(field.min(), field.max(), int(LIMITS["bands"]))
            ),
        ),
        (
            "sky_view",
            "directions, radius",
            f"{int(LIMITS['directions'])}, {int(LIMITS['reach'])} cells",
            lambda: F.sky_view(
                field, directions=int(LIMITS["directions"]), radius=float(LIMITS["reach"])
            ),
        ),
        ("cast_shadows", "altitude", "0.5 deg", lambda: F.cast_shadows(field, altitude=0.5)),
        (
            "reflection_lines",
            "stripes, width",
            f"{lv}, {W:g}",
            lambda: F.reflection_lines(gb, stripes=float(lv), width=W),
        ),
        (
            "reflection_lines",
            "stripes (zebra)",
            f"{lv}",
            lambda: F.reflection_lines(gb, stripes=float(lv), style="stripes"),
        ),
        (
            "isophotes",
            "interval, width",
            f"{180 / lv:g} deg, {W:g}",
            lambda: F.isophotes(gb, interval=180.0 / lv, width=W),
        ),
        (
            "isophotes",
            "levels",
            f"{lv}",
            lambda: F.isophotes(gb, levels=np.linspace(-1, 1, lv)),
        ),
        (
            "hatch (style)",
            "spacing, max_width, angles, profile_width",
            f"{LIMITS['spacing']:g}, {W:g}, {int(LIMITS['families'])}, {W:g}",
            lambda: styles["hatch"](
                gb,
                spacing=LIMITS["spacing"],
                max_width=W,
                angles=np.linspace(0, 180, int(LIMITS["families"])),
                profile_width=W,
            ),
        ),
        (
            "toon (style)",
            "levels, width",
            f"{int(LIMITS['shade_levels'])}, {W:g}",
            lambda: styles["toon"](gb, levels=int(LIMITS["shade_levels"]), smooth=1.0, width=W),
        ),
        ("gooch (style)", "width", f"{W:g}", lambda: styles["gooch"](gb, width=W)),
        ("enhance (style)", "width", f"{W:g}", lambda: styles["enhance"](gb, width=W)),
        (
            "drawing (style)",
            "spacing, width, profile_width",
            f"{LIMITS['spacing']:g}, {W:g}, {W:g}",
            lambda: styles["drawing"](gb, spacing=LIMITS["spacing"], width=W, profile_width=W),
        ),
        (
            "photocopy",
            "copies, blur",
            f"{int(LIMITS['copies'])}, {LIMITS['blur']:g}",
            lambda: photocopy(
                field / field.max(), copies=int(LIMITS["copies"]), blur=LIMITS["blur"]
            ),
        ),
    ]


def best_time(thunk, repeats: int) -> str:
    """Best of ``repeats`` seconds, or how fast a bound refused the call (an InputError raised
    before the work: e.g. contour_polylines counts its segments first)."""
    try:
        thunk()  # warm: numba compile / cache load, first touch of memory
    except InputError:
        t0 = time.perf_counter()
        try:
            thunk()
        except InputError:
            pass
        return f"{time.perf_counter() - t0:.3f} (refused: InputError)"
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        thunk()
        times.append(time.perf_counter() - t0)
    return f"{min(times):.3f}"


_MEMORY_CHILD = r"""
import resource, sys
import pyvista as pv
import sciviz_gbuf as sg
s = pv.Sphere(theta_resolution=64, phi_resolution=64)
sg.capture(s, window_size=(64, 64))
def rss():
    with open('/proc/self/status') as f:
        for line in f:
            if line.startswith('VmRSS'):
                return int(line.split()[1]) * 1024
base = rss()
n, k = int(sys.argv[1]), int(sys.argv[2])
gb = sg.capture(s, window_size=(n, n), supersample=k)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print((peak - base) / (n * k) ** 2, (rss() - base) / (n * k) ** 2)
"""


def capture_memory(sides: list[int]) -> None:
    print("\n| buffer | peak bytes / px | kept bytes / px |\n|---|---|---|")
    for side in sides:
        out = subprocess.run(
            [sys.executable, "-c", _MEMORY_CHILD, str(side // 2), "2"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
        print(f"| {side}^2 | {float(out[0]):.1f} | {float(out[1]):.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--side", type=int, default=64, help="side of the array inputs")
    ap.add_argument("--capture", type=int, nargs=2, default=(64, 48), help="window size")
    ap.add_argument("--supersample", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--capture-memory", type=int, nargs="*", metavar="SIDE")
    args = ap.parse_args()

    y, x = np.mgrid[0 : args.side, 0 : args.side].astype(np.float32)
    field = (np.sin(x / 5.0) * 20.0 + np.cos(y / 7.0) * 15.0 + y).astype(np.float32)
    torus = pv.ParametricTorus(texture_coordinates=True)
    gb = capture(torus, window_size=tuple(args.capture), camera="iso", supersample=args.supersample)
    print(
        f"arrays {args.side}x{args.side}; G-buffer {gb.shape[1]}x{gb.shape[0]} "
        f"(window {args.capture[0]}x{args.capture[1]}, supersample {args.supersample})\n"
    )
    print("| filter | parameter | bound | seconds |\n|---|---|---|---|")
    for name, param, bound, thunk in cases(field, gb):
        print(f"| {name} | {param} | {bound} | {best_time(thunk, args.repeats)} |", flush=True)
    if args.capture_memory:
        capture_memory(args.capture_memory)


if __name__ == "__main__":
    main()
