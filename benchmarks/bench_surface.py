"""Benchmark: surface analysis (1990 §4.5): tessellation with analytic geometry, then the line
patterns on the kept G-buffer.

Run from the project root with the project's venv active::

    python benchmarks/bench_surface.py                 # 1024^2 and 2048^2 buffers (~1 min)
    python benchmarks/bench_surface.py --sizes 512     # quick

Tessellation: ``PatchSet.to_mesh`` of the 8-patch sphere built in code (positions, analytic
normals, Gaussian/mean/principal curvatures per point) against the peer a PyVista user has,
``compute_normals`` + ``curvature("gaussian")`` + ``curvature("mean")`` on the same triangles
(discrete, mesh-based), same run.

Filters, on one capture of the C1 seam surface: ``reflection_lines`` (lines and stripes),
``isophotes``, and the floor of any per-pixel shading, ``lambert`` of the same normals (the
``x lambert`` column). MPix/s are buffer pixels per second; best of ``--repeats``, warm.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable

# Headless: VTK's default window class would try X first; must precede the sciviz_gbuf import.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np

from sciviz_gbuf.filters import isophotes, lambert, reflection_lines
from sciviz_gbuf.readers.patches import PatchSet
from sciviz_gbuf.recipes.surface import seam_patches, surface_gbuffer

K = 0.5522847498  # cubic Bezier quarter-circle handle length


def sphere_octant_nets() -> list[np.ndarray]:
    """8 bicubic patches close to the unit sphere (one per octant, a collapsed pole each)."""
    arc = np.array([[1, 0], [1, K], [K, 1], [0, 1]], dtype=np.float64)
    nets = []
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                net = np.empty((4, 4, 3))
                for i, (c, s) in enumerate(arc):  # from the equator (i=0) to the pole
                    for j, (a, b) in enumerate(arc):
                        net[i, j] = (sx * c * a, sy * c * b, sz * s)
                nets.append(net)
    return nets


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
    ap.add_argument("--sizes", default="1024,2048", help="buffer sizes (square)")
    ap.add_argument("--resolution", type=int, default=128, help="tessellation per patch")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    patches = PatchSet.from_control_nets(sphere_octant_nets())
    res = args.resolution
    t_mesh = best(lambda: patches.to_mesh(resolution=res), args.repeats)
    mesh = patches.to_mesh(resolution=res)
    bare = mesh.copy()
    bare.point_data.clear()

    def peer():
        m = bare.compute_normals(split_vertices=False)
        m.curvature("gaussian")
        m.curvature("mean")

    t_peer = best(peer, args.repeats)
    print(f"tessellation, 8 patches x {res}^2: {mesh.n_points} points, {mesh.n_cells} triangles")
    print(f"{'':<52} {'s':>8} {'Mpts/s':>8}")
    print(
        f"{'to_mesh: analytic normals + 4 curvatures':<52} {t_mesh:8.3f} "
        f"{mesh.n_points / t_mesh / 1e6:8.2f}"
    )
    print(
        f"{'peer: compute_normals + curvature x2 (discrete)':<52} {t_peer:8.3f} "
        f"{mesh.n_points / t_peer / 1e6:8.2f}   ours/peer {t_mesh / t_peer:.2f}"
    )

    print()
    print(f"{'buffer':>8} {'filter':<34} {'ms':>8} {'MPix/s':>8} {'x lambert':>10}")
    seam = seam_patches("C1")
    for n in (int(v) for v in args.sizes.split(",")):
        gb = surface_gbuffer(seam, view="xy", window_size=(n, n), supersample=1)
        floor = lambda gb=gb: lambert(gb.normal, mask=gb.mask)  # noqa: E731
        base = best(floor, args.repeats)
        cases = {
            "reflection_lines, lines": lambda gb=gb: reflection_lines(gb, stripes=24),
            "reflection_lines, stripes": lambda gb=gb: reflection_lines(
                gb, stripes=24, style="stripes"
            ),
            "reflection_lines, highlight": lambda gb=gb: reflection_lines(gb, mode="highlight"),
            "isophotes": lambda gb=gb: isophotes(gb, interval=10),
        }
        print(f"{n:>7}² {'lambert (the floor)':<34} {base * 1e3:8.1f} {n * n / base / 1e6:8.1f}")
        for name, fn in cases.items():
            t = best(fn, args.repeats)
            print(f"{n:>7}² {name:<34} {t * 1e3:8.1f} {n * n / t / 1e6:8.1f} {t / base:10.1f}")


if __name__ == "__main__":
    main()
