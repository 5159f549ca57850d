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

Then the live contour lines (``pl.gbuf.enable_contour_lines``: Eq. 7-15 in the actor's own
fragment shader, one pass) on a DEM surface in UTM coordinates (400 x 300 cells of 30 m) and
on the 1M-triangle surface: in one window, ``--rounds`` rounds of ``--frames`` plain
frames, then as many with the lines (20 m levels, 100 m majors; the same orbit); fps from
the median frame time, the ratio of the medians and the range of the per-round ratios.

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


def dem_surface() -> pv.PolyData:
    """400 x 300 cells of 30 m in UTM coordinates (x ~ 4.5e5, y ~ 4.4e6), 1700-2300 m."""
    y, x = np.mgrid[0:300, 0:400] * 30.0
    z = 2000 + 300 * np.sin(x / 900) * np.cos(y / 700) + 0.04 * x
    grid = pv.StructuredGrid(x + 4.5e5, y + 4.4e6, z)
    return grid.extract_surface(algorithm="dataset_surface").triangulate()


def frame_times(pl: pv.Plotter, frames: int) -> list[float]:
    """Seconds of each of ``frames`` orbit frames (render + glFinish), after one untimed."""
    window = pl.render_window
    pl.render()
    window.WaitForCompletion()
    out = []
    for _ in range(frames):
        pl.camera.azimuth += 3.0
        t0 = time.perf_counter()
        pl.render()
        window.WaitForCompletion()
        out.append(time.perf_counter() - t0)
    return out


def contour_rounds(mesh: pv.DataSet, size: tuple[int, int], frames: int, rounds: int, height: bool):
    """(plain fps, lines fps, per-round ratios) in one window, plain and lines alternating in
    blocks of ``frames`` frames; fps from the median frame time (a shared VM's stalls hit
    single frames, which a median leaves out)."""
    pl = plotter(mesh, size)
    actor = next(iter(pl.renderer.actors.values()))
    opts = {"interval": 20.0, "major_interval": 100.0} if height else {"interval": 0.25}
    plain: list[float] = []
    lines: list[float] = []
    ratios = []
    for _ in range(rounds):
        pl.gbuf.disable_contour_lines()
        a = frame_times(pl, frames)
        pl.gbuf.enable_contour_lines(actor, height="z", **opts)
        b = frame_times(pl, frames)
        plain += a
        lines += b
        ratios.append(float(np.median(a) / np.median(b)))
    pl.close()
    return 1.0 / float(np.median(plain)), 1.0 / float(np.median(lines)), ratios


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
    ap.add_argument("--rounds", type=int, default=5, help="rounds of the contour-line runs")
    ap.add_argument("--no-edges", action="store_true", help="only the contour-line table")
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
    if not args.no_edges:
        edge_table(meshes, sizes, args.frames, args.repeat)
    print(f"\nlive contour lines, {args.frames} frames a run, {args.rounds} rounds "
          "(plain, lines) in one window")  # fmt: skip
    print(f"{'mesh':9s} {'cells':>7s} {'window':>9s} {'plain fps':>9s} {'lines fps':>9s} "
          f"{'ratio':>6s} {'range':>11s}")  # fmt: skip
    surfaces = {"dem_utm": (dem_surface(), True)}
    if "hills_1M" in meshes:
        surfaces["hills_1M"] = (meshes["hills_1M"], False)
    for name, (mesh, height) in surfaces.items():
        for size in sizes:
            p, f, r = contour_rounds(mesh, size, args.frames, args.rounds, height)
            print(f"{name:9s} {mesh.n_cells:7d} {size[0]:4d}x{size[1]:<4d} {p:9.1f} {f:9.1f} "
                  f"{f / p:6.2f} {min(r):5.2f}-{max(r):4.2f}", flush=True)  # fmt: skip
    print("lines: 20 m levels, 100 m majors on the DEM (world height); levels 0.25 on the")
    print("hills (world z); fps from median frame times; ratio = lines fps / plain fps, with")
    print("the range of the rounds' ratios.")
    return 0


def edge_table(meshes: dict, sizes: list, frames: int, repeat: int) -> None:
    """The edge overlay's fps per route."""
    print(f"orbit + render + glFinish, {frames} frames, best of {repeat}")
    head = f"{'mesh':9s} {'cells':>7s} {'window':>9s} {'plain fps':>9s}"
    for route in ROUTES:
        head += f" {route:>8s} {'ratio':>6s}"
    print(head)
    for name, mesh in meshes.items():
        for size in sizes:
            plain = max(fps(mesh, size, frames, None) for _ in range(repeat))
            row = f"{name:9s} {mesh.n_cells:7d} {size[0]:4d}x{size[1]:<4d} {plain:9.1f}"
            for route in ROUTES:
                f = max(fps(mesh, size, frames, route) for _ in range(repeat))
                row += f" {f:8.1f} {f / plain:6.2f}"
            print(row, flush=True)
    print("fps per route: gpu = shaders inside the frame, frame = depth read back + CPU edge")
    print("map, capture = a second offscreen render + CPU edge map; ratio = fps / plain fps.")


if __name__ == "__main__":
    sys.exit(main())
