"""Benchmark: frames per second of PyVista with and without the live edge overlay.

Run from the project root with the project's venv active::

    python benchmarks/bench_live.py                 # 1024x768, nut + CAD STL + 1M, ~4 min
    python benchmarks/bench_live.py --frames 60 --size 800 600 --no-big

What is measured: an off-screen ``pyvista.Plotter`` at ``--size`` with one mesh (PyVista's
``load_nut()``, the CAD part ``../shared/data/meshes/vtkdata_42400-IDGH.stl`` if present, and a
1M-triangle surface, ``pyvista.ParametricRandomHills`` at 700 x 700, unless ``--no-big``)
orbits its camera (``azimuth += 3`` degrees a frame), and each frame is ``pl.render()`` +
``pl.screenshot()``: what a user saving an animation does, and an upper bound on what an
interactive window shows. Each mesh in two windows: PyVista's default (``msaa``, 4 samples)
and without anti-aliasing (``none``: ``disable_anti_aliasing()``, one sample per pixel). In
each: plain, then with ``pl.gbuf.enable_edge_enhancement(source=...)`` for both routes
(``capture``: a second, offscreen render of the ids per new view; ``frame``: the frame's own
depth read back, no second render). Every frame has a new camera, so every frame makes a new
G-buffer and edge map. One untimed warm-up frame each (numba compiles or loads its cache);
``ratio`` is edges fps / plain fps in the same window (the issue's goal: >= 0.8). ``auto`` is
the route of the default ``source="auto"`` there (``frame`` only where it gives the capture's
lines: no multisampling). The split below times the routes' parts on the same views.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

if not os.environ.get("DISPLAY"):
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pyvista as pv
from pyvista import examples
from vtkmodules.vtkCommonCore import vtkFloatArray

import sciviz_gbuf as sg
from sciviz_gbuf import pyvista_plugin  # noqa: F401  (registers .gbuf without entry points)
from sciviz_gbuf.core import CameraInfo, gbuffer_from_zbuffer, read_zbuffer
from sciviz_gbuf.live import EdgeParams, overlay_rgba

STL = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes" / "vtkdata_42400-IDGH.stl"


def plotter(mesh: pv.DataSet, size: tuple[int, int], aa: str) -> pv.Plotter:
    """An off-screen plotter with the mesh; ``aa``: "msaa" (PyVista's default anti-aliasing,
    4 samples) or "none" (one depth sample per pixel)."""
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.add_mesh(mesh)
    if aa == "none":
        pl.disable_anti_aliasing()
        pl.render_window.SetMultiSamples(0)
    return pl


def fps(mesh: pv.DataSet, size: tuple[int, int], frames: int, aa: str, source: str | None) -> float:
    """Frames per second of orbit + render + screenshot (``source`` None: no overlay)."""
    pl = plotter(mesh, size, aa)
    if source is not None:
        pl.gbuf.enable_edge_enhancement(source=source)
    pl.screenshot()  # warm-up (first render, numba)
    t0 = time.perf_counter()
    for _ in range(frames):
        pl.camera.azimuth += 3.0
        pl.render()
        pl.screenshot()
    dt = time.perf_counter() - t0
    if source is not None:
        assert pl.gbuf.live.updates == frames + 1, "every new view must be re-captured"
        assert pl.gbuf.live.route == (source if source != "auto" else pl.gbuf.live.route)
    pl.close()
    return frames / dt


def split(mesh: pv.DataSet, size: tuple[int, int], frames: int) -> tuple[float, float, float]:
    """Mean seconds per frame of the capture route's capture, of the frame route's read-back
    and conversion (after a frame without multisampling), and of the edge-map overlay."""
    pl = plotter(mesh, size, "none")
    pl.screenshot()
    params = EdgeParams()
    session = sg.CaptureSession(pl)
    overlay_rgba(session.capture(camera=pl.camera), params)  # warm-up
    ren = pl.renderer
    zbuf = vtkFloatArray()
    t_cap = t_frame = t_map = 0.0
    for _ in range(frames):
        pl.camera.azimuth += 3.0
        pl.render()
        t0 = time.perf_counter()
        gb = session.capture(camera=pl.camera, reuse=True)
        t1 = time.perf_counter()
        z = read_zbuffer(pl.render_window, ren.GetOrigin(), ren.GetSize(), out=zbuf)
        gbuffer_from_zbuffer(z, CameraInfo.from_vtk(ren.GetActiveCamera(), ren.GetSize()))
        t2 = time.perf_counter()
        overlay_rgba(gb, params)
        t3 = time.perf_counter()
        t_cap += t1 - t0
        t_frame += t2 - t1
        t_map += t3 - t2
    session.close()
    pl.close()
    return t_cap / frames, t_frame / frames, t_map / frames


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--size", type=int, nargs=2, default=(1024, 768))
    ap.add_argument("--no-big", action="store_true", help="leave out the 1M-triangle surface")
    args = ap.parse_args()
    size = tuple(args.size)
    meshes = {"nut": examples.load_nut()}
    if STL.is_file():
        meshes["cad_stl"] = pv.read(STL)
    if not args.no_big:
        meshes["hills_1M"] = pv.ParametricRandomHills(u_res=700, v_res=700).triangulate()
    print(f"window {size[0]}x{size[1]}, {args.frames} frames, orbit + render + screenshot")
    print(f"{'mesh':9s} {'cells':>7s} {'window':>6s} {'plain fps':>9s} {'capture':>8s} "
          f"{'ratio':>6s} {'frame':>6s} {'ratio':>6s} {'auto':>7s}")  # fmt: skip
    splits = {}
    for name, mesh in meshes.items():
        for aa in ("msaa", "none"):
            plain = fps(mesh, size, args.frames, aa, None)
            cap = fps(mesh, size, args.frames, aa, "capture")
            frame = fps(mesh, size, args.frames, aa, "frame")
            auto = "frame" if aa == "none" else "capture"
            print(
                f"{name:9s} {mesh.n_cells:7d} {aa:>6s} {plain:9.1f} {cap:8.1f} {cap / plain:6.2f} "
                f"{frame:6.1f} {frame / plain:6.2f} {auto:>7s}"
            )
        splits[name] = split(mesh, size, max(5, args.frames // 3))
    print("fps: capture = source='capture', frame = source='frame'; ratio = edges fps / plain fps")
    print("(goal >= 0.8); auto = the route source='auto' takes in that window.")
    print(f"\n{'mesh':9s} {'capture ms':>11s} {'read+convert ms':>16s} {'edge map ms':>12s}")
    for name, (cap, frame, emap) in splits.items():
        print(f"{name:9s} {cap * 1e3:11.1f} {frame * 1e3:16.1f} {emap * 1e3:12.1f}")


if __name__ == "__main__":
    main()
