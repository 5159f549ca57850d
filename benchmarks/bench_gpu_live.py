"""Benchmark: frames per second of the live edge overlay per route, GPU route included, ready
for a machine with a graphics card.

Run from the project root with the project's venv active::

    python benchmarks/bench_gpu_live.py                  # 1024x768 and 1920x1080, ~3 min here
    python benchmarks/bench_gpu_live.py --check          # the GPU route against the CPU one
    python benchmarks/bench_gpu_live.py --frames 100 --sizes 1920x1080

It prints the GL vendor, renderer and version first: a table is about the machine it names.
Headless, it renders through EGL (``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``, set here
when there is no ``DISPLAY``): Mesa llvmpipe on a machine without a GPU, the NVIDIA driver's
EGL on one with it; nothing else changes.

What is measured: an off-screen ``pyvista.Plotter`` (PyVista's default window: 4-sample MSAA)
with one mesh, PyVista's ``load_nut()``, the CAD part ``../shared/data/meshes/
vtkdata_42400-IDGH.stl`` if present, and a 1M-triangle surface (``ParametricRandomHills`` at
700 x 700), orbits its camera (``azimuth += 3`` degrees a frame). A frame is ``pl.render()``
followed by ``render_window.WaitForCompletion()`` (``glFinish``: the GPU's work is inside the
frame time, with no read-back of the picture). Per window: plain, then
``pl.gbuf.enable_edge_enhancement(source=...)`` for ``gpu`` (the edge map in shaders inside
the frame), ``frame`` (the frame's depth read back, the edge map on the CPU) and ``capture``
(a second, offscreen render of the ids, the edge map on the CPU). Every frame has a new
camera, so the CPU routes make a new G-buffer every frame. Untimed warm-up frames first;
the best of ``--repeat`` runs. ``ratio``: edges fps / plain fps in the same window.

``--check`` asserts, for every mesh and size, that the GPU route's edge planes agree with
``capture`` + ``edge_map`` of the same camera: >= 95 % of the strong pixels of each within one
pixel of the other's, profile recall >= 0.98 (exit status 1 if not).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np
import pyvista as pv
from pyvista import examples
from scipy import ndimage

import sciviz_gbuf as sg
from sciviz_gbuf import pyvista_plugin  # noqa: F401  (registers .gbuf without entry points)
from sciviz_gbuf.filters import edge_map
from sciviz_gbuf.live import gl_info

STL = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes" / "vtkdata_42400-IDGH.stl"
ROUTES = ("gpu", "frame", "capture")


def plotter(mesh: pv.DataSet, size: tuple[int, int]) -> pv.Plotter:
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.add_mesh(mesh, color="tan")
    pl.camera.elevation = 20
    pl.show(auto_close=False)  # the first render: PyVista's render() does nothing before it
    return pl


def fps(mesh: pv.DataSet, size: tuple[int, int], frames: int, source: str | None) -> float:
    """Frames per second of orbit + render + glFinish (``source`` None: no overlay)."""
    pl = plotter(mesh, size)
    if source is not None:
        pl.gbuf.enable_edge_enhancement(source=source)
    window = pl.render_window
    for _ in range(3):  # warm-up: the first render, shader compiles, numba's cache
        pl.camera.azimuth += 3.0
        pl.render()
    window.WaitForCompletion()
    t0 = time.perf_counter()
    for _ in range(frames):
        pl.camera.azimuth += 3.0
        pl.render()
        window.WaitForCompletion()
    dt = time.perf_counter() - t0
    if source is not None:
        live = pl.gbuf.live
        assert live.route == source, (live.route, live.gpu_unavailable)
        if source == "gpu":
            assert live.gpu_frames >= frames
        else:
            assert live.updates >= frames, "every new view must make a new G-buffer"
    pl.close()
    return frames / dt


def check(mesh: pv.DataSet, size: tuple[int, int]) -> tuple[float, float, float]:
    """(precision, recall, profile recall) of the GPU route against capture + edge_map."""
    pl = plotter(mesh, size)
    pl.camera.azimuth += 30
    pl.gbuf.enable_edge_enhancement(source="gpu")
    pl.render()
    inner, prof = pl.gbuf.live.gpu_edge_planes()
    ref = edge_map(sg.capture(pl))
    pl.close()
    ring = np.ones((3, 3), bool)
    gs = (inner > 0.5) | (prof > 0.5)
    rs = (ref[..., 0] > 0.5) | (ref[..., 3] > 0.5)
    rp = ref[..., 3] > 0.5
    precision = float(ndimage.binary_dilation(rs, ring)[gs].mean())
    recall = float(ndimage.binary_dilation(gs, ring)[rs].mean())
    profile_recall = float(ndimage.binary_dilation(prof > 0.5, ring)[rp].mean())
    return precision, recall, profile_recall


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=2, help="runs per cell (best kept)")
    ap.add_argument("--sizes", default="1024x768,1920x1080")
    ap.add_argument("--no-big", action="store_true", help="leave out the 1M-triangle surface")
    ap.add_argument("--check", action="store_true", help="only check the GPU route's edges")
    args = ap.parse_args()
    sizes = [tuple(int(v) for v in s.split("x")) for s in args.sizes.split(",")]
    meshes = {"nut": examples.load_nut()}
    if STL.is_file():
        meshes["cad_stl"] = pv.read(STL)
    if not args.no_big:
        meshes["hills_1M"] = pv.ParametricRandomHills(u_res=700, v_res=700).triangulate()
    probe = plotter(meshes["nut"], (64, 64))
    probe.render()
    info = gl_info(probe.render_window)
    probe.close()
    print(f"# GL vendor: {info['vendor']}")
    print(f"# GL renderer: {info['renderer']}")
    print(f"# GL version: {info['version']}")
    print(f"# {os.cpu_count()} CPUs, VTK {pv.vtk_version_info}, PyVista {pv.__version__}")
    if args.check:
        ok = True
        print(f"{'mesh':9s} {'window':>9s} {'precision':>9s} {'recall':>7s} {'profile':>8s}")
        for name, mesh in meshes.items():
            for size in sizes:
                p, r, pr = check(mesh, size)
                good = p >= 0.95 and r >= 0.95 and pr >= 0.98
                ok &= good
                print(f"{name:9s} {size[0]:4d}x{size[1]:<4d} {p:9.3f} {r:7.3f} {pr:8.3f}"
                      f"{'' if good else '  FAILED'}")  # fmt: skip
        return 0 if ok else 1
    print(f"orbit + render + glFinish, {args.frames} frames, best of {args.repeat}")
    head = f"{'mesh':9s} {'cells':>7s} {'window':>9s} {'plain fps':>9s}"
    for route in ROUTES:
        head += f" {route:>8s} {'ratio':>6s}"
    print(head)
    for name, mesh in meshes.items():
        for size in sizes:
            plain = max(fps(mesh, size, args.frames, None) for _ in range(args.repeat))
            row = f"{name:9s} {mesh.n_cells:7d} {size[0]:4d}x{size[1]:<4d} {plain:9.1f}"
            for route in ROUTES:
                f = max(fps(mesh, size, args.frames, route) for _ in range(args.repeat))
                row += f" {f:8.1f} {f / plain:6.2f}"
            print(row, flush=True)
    print("fps per route: gpu = shaders inside the frame, frame = depth read back + CPU edge")
    print("map, capture = a second offscreen render + CPU edge map; ratio = fps / plain fps.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
