"""Benchmark: frames per second of PyVista with and without the live edge overlay.

Run from the project root with the project's venv active::

    python benchmarks/bench_live.py                 # 1024x768, nut + CAD STL, 30 frames each
    python benchmarks/bench_live.py --frames 60 --size 800 600

What is measured: an off-screen ``pyvista.Plotter`` at ``--size`` with one mesh (PyVista's
``load_nut()``, the CAD part ``../shared/data/meshes/vtkdata_42400-IDGH.stl`` if present, and a
1M-triangle surface, ``pyvista.ParametricRandomHills`` at 700 x 700, unless ``--no-big``)
orbits its camera (``azimuth += 3`` degrees a frame), and each frame is ``pl.render()`` +
``pl.screenshot()``: what a user saving an animation does, and an upper bound on what an
interactive window shows. Once plain, once with ``pl.gbuf.enable_edge_enhancement()`` (every
frame has a new camera, so every frame re-captures the G-buffer and recomputes the edge map).
One untimed warm-up frame each (numba compiles or loads its cache). The per-frame cost of the
overlay is split into capture (what the overlay does: ``CaptureSession.capture`` of the
subplot's scene, the session made once) and edge map (``overlay_rgba``: edge map and
composition), timed separately on the same views; ``ratio`` is edges fps / plain fps (the
issue's goal: >= 0.8).
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

import sciviz_gbuf as sg
from sciviz_gbuf import pyvista_plugin  # noqa: F401  (registers .gbuf without entry points)
from sciviz_gbuf._live import EdgeParams, overlay_rgba

STL = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes" / "vtkdata_42400-IDGH.stl"


def fps(mesh: pv.DataSet, size: tuple[int, int], frames: int, enhance: bool) -> float:
    """Frames per second of orbit + render + screenshot."""
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.add_mesh(mesh)
    if enhance:
        pl.gbuf.enable_edge_enhancement()
    pl.screenshot()  # warm-up (first render, numba)
    t0 = time.perf_counter()
    for _ in range(frames):
        pl.camera.azimuth += 3.0
        pl.render()
        pl.screenshot()
    dt = time.perf_counter() - t0
    if enhance:
        assert pl.gbuf.live.updates == frames + 1, "every new view must be re-captured"
    pl.close()
    return frames / dt


def split(mesh: pv.DataSet, size: tuple[int, int], frames: int) -> tuple[float, float]:
    """Mean seconds per frame of capture and of the edge-map overlay."""
    pl = pv.Plotter(off_screen=True, window_size=size)
    pl.add_mesh(mesh)
    pl.screenshot()
    params = EdgeParams()
    session = sg.CaptureSession(pl)
    overlay_rgba(session.capture(camera=pl.camera), params)  # warm-up
    t_cap = t_map = 0.0
    for _ in range(frames):
        pl.camera.azimuth += 3.0
        t0 = time.perf_counter()
        gb = session.capture(camera=pl.camera, reuse=True)
        t1 = time.perf_counter()
        overlay_rgba(gb, params)
        t2 = time.perf_counter()
        t_cap += t1 - t0
        t_map += t2 - t1
    session.close()
    pl.close()
    return t_cap / frames, t_map / frames


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=30)
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
    print(f"{'mesh':10s} {'cells':>8s} {'plain fps':>10s} {'edges fps':>10s} {'ratio':>6s} "
          f"{'capture ms':>11s} {'edgemap ms':>11s}")  # fmt: skip
    for name, mesh in meshes.items():
        plain = fps(mesh, size, args.frames, enhance=False)
        live = fps(mesh, size, args.frames, enhance=True)
        cap, emap = split(mesh, size, max(5, args.frames // 3))
        print(
            f"{name:10s} {mesh.n_cells:8d} {plain:10.1f} {live:10.1f} {live / plain:6.2f} "
            f"{cap * 1e3:11.1f} {emap * 1e3:11.1f}"
        )


if __name__ == "__main__":
    main()
