"""Benchmark: the first frames of the live overlay in a fresh Python process.

Run from the project root with the project's venv active::

    python benchmarks/bench_first_frame.py            # warm numba cache, 3 fresh processes
    python benchmarks/bench_first_frame.py --cold     # also with an empty numba cache

What is measured, each in a new interpreter (as a user's script or notebook starts): the import
of ``pyvista`` and ``sciviz_gbuf``, a ``pyvista.Plotter`` at 1024x768 with the CAD part (or
PyVista's nut) and its first plain screenshot, then ``pl.gbuf.enable_edge_enhancement()`` and
the screenshot that makes the first overlay (numba loads the capture and edge kernels from its
cache here), and the next frame after a camera move (everything loaded). The first overlay
frame minus the second is what loading the kernels costs; the issue's goal is that it stalls
the first interactive frame for well under a second on a warm install. ``--cold`` repeats the
run with ``NUMBA_CACHE_DIR`` pointing at an empty folder: what the very first run after an
install pays (the package's ``sciviz-gbuf warmup`` / first-run compile is separate).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

STL = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes" / "vtkdata_42400-IDGH.stl"

_CHILD = r"""
import json, os, sys, time
t0 = time.perf_counter()
import pyvista as pv
import sciviz_gbuf  # noqa: F401
from sciviz_gbuf import pyvista_plugin  # noqa: F401
t1 = time.perf_counter()
path = sys.argv[1]
mesh = pv.read(path) if path else pv.examples.load_nut()
pl = pv.Plotter(off_screen=True, window_size=(1024, 768))
pl.add_mesh(mesh)
pl.screenshot()
t2 = time.perf_counter()
pl.gbuf.enable_edge_enhancement()
pl.screenshot()
t3 = time.perf_counter()
pl.camera.azimuth += 10
pl.render()
pl.screenshot()
t4 = time.perf_counter()
assert pl.gbuf.live.updates == 2
pl.close()
print(json.dumps({"import": t1 - t0, "plain": t2 - t1, "first": t3 - t2, "second": t4 - t3}))
"""


def run(cache_dir: str | None, path: str) -> dict[str, float]:
    env = dict(os.environ)
    if not env.get("DISPLAY"):
        env.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    res = subprocess.run(
        [sys.executable, "-c", _CHILD, path], capture_output=True, text=True, env=env, timeout=900
    )
    if res.returncode != 0:
        raise SystemExit(res.stderr)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--cold", action="store_true")
    args = ap.parse_args()
    path = str(STL) if STL.is_file() else ""
    print(f"mesh: {Path(path).name if path else 'pyvista nut'}, 1024x768, fresh process each")
    print(f"{'cache':<6} {'import s':>9} {'plain 1st s':>12} {'overlay 1st s':>14} "
          f"{'overlay 2nd s':>14} {'load = 1st - 2nd':>17}")  # fmt: skip
    rows = [("warm", None)] * args.runs
    if args.cold:
        rows.append(("cold", tempfile.mkdtemp(prefix="numba-cold-")))
    run(None, path)  # make sure the warm cache exists
    for label, cache in rows:
        r = run(cache, path)
        print(
            f"{label:<6} {r['import']:9.2f} {r['plain']:12.2f} {r['first']:14.2f} "
            f"{r['second']:14.2f} {r['first'] - r['second']:17.2f}"
        )


if __name__ == "__main__":
    main()
